//! `flaneur bench pvs-prefetch` run small from the command line: every CSV, plot and
//! the summary written, PBNP's figures against SNP's, and bad settings refused before
//! anything is written.

mod common;

use common::flaneur;

use flaneur_bench::pvs_prefetch::{
    cumulative_plot, steps_plot, LATENCY_CSV, LATENCY_MISSES_PLOT, LATENCY_SWAPS_PLOT, MISSES_PLOT,
    REGIONS_CSV, REGIONS_PLOT, ROUTES_CSV, ROUTES_PLOT, STEPS_CSV,
};

fn is_png(path: &std::path::Path) -> bool {
    std::fs::read(path)
        .map(|b| b.starts_with(b"\x89PNG\r\n\x1a\n"))
        .unwrap_or(false)
}

/// A city of 10 × 10 blocks and routes of 400 steps: well under a second.
const SMALL: [&str; 8] = [
    "--blocks",
    "10",
    "--steps",
    "400",
    "--borders",
    "0.1,0.25",
    "--latencies",
    "0,3,5",
];

#[test]
fn pvs_prefetch_writes_table_7_2_and_its_figures() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("bench");
    let mut args = vec!["bench", "pvs-prefetch", "--out", out_dir.to_str().unwrap()];
    args.extend(SMALL);
    let out = flaneur(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    for word in [
        "Table 7.2",
        "route 1 SNP",
        "route 2 PBNP",
        "1785",
        "cache swaps",
    ] {
        assert!(stdout.contains(word), "{word} missing from\n{stdout}");
    }

    let csv = common::Csv::read(&out_dir.join("pvs-prefetch.csv"));
    assert_eq!(csv.rows.len(), 4);
    let get = |route: &str, alg: &str, name: &str| -> f64 {
        let r = csv
            .rows
            .iter()
            .find(|r| r[0] == route && r[1] == alg)
            .unwrap_or_else(|| panic!("no row for {route} {alg}"));
        csv.num(r, name)
    };
    for route in ["1", "2"] {
        assert!(get(route, "PBNP", "cache_swaps") < get(route, "SNP", "cache_swaps"));
        assert!(
            get(route, "PBNP", "objects_per_transaction")
                < get(route, "SNP", "objects_per_transaction")
        );
        assert_eq!(get(route, "SNP", "visual_misses"), 0.0);
    }
    assert_eq!(get("2", "PBNP", "thesis_cache_swaps"), 828.0);

    // SNP, PBNP and LANP at each latency asked for, on both routes.
    let latency = std::fs::read_to_string(out_dir.join(LATENCY_CSV)).unwrap();
    assert_eq!(latency.lines().count(), 1 + 2 * 3 * 3, "{latency}");
    assert!(
        latency.lines().any(|l| l.starts_with("2,LANP,5,")),
        "{latency}"
    );
    assert!(stdout.contains("Under latency"), "{stdout}");

    for f in ["pvs-prefetch.md", STEPS_CSV, REGIONS_CSV, ROUTES_CSV] {
        assert!(out_dir.join(f).exists(), "{f} missing");
    }
    // One row per position: the start and 400 steps.
    let steps = std::fs::read_to_string(out_dir.join(STEPS_CSV)).unwrap();
    assert_eq!(steps.lines().count(), 1 + 401);
    let mut pngs = vec![
        ROUTES_PLOT.to_string(),
        REGIONS_PLOT.to_string(),
        MISSES_PLOT.to_string(),
        LATENCY_MISSES_PLOT.to_string(),
        LATENCY_SWAPS_PLOT.to_string(),
    ];
    for route in [1, 2] {
        pngs.push(cumulative_plot(route));
        for alg in ["SNP", "PBNP"] {
            pngs.push(steps_plot(route, alg));
        }
    }
    for f in &pngs {
        assert!(is_png(&out_dir.join(f)), "{f}");
    }
}

#[test]
fn pvs_prefetch_refuses_bad_settings() {
    let dir = tempfile::tempdir().unwrap();
    for (bad, says) in [
        (["--border", "0.7"], "region border"),
        (["--border", "NaN"], "--border"),
        (["--borders", "0"], "region border"),
        (["--cache", "8"], "too small"),
        (["--steps", "0"], "steps"),
        (["--overlap", "1"], "overlap"),
        (["--share", "0"], "PVS share"),
        (["--step", "0"], "step length"),
        (["--latencies", "5000"], "latency"),
    ] {
        let none = dir.path().join("none");
        let mut args = vec!["bench", "pvs-prefetch", "--out", none.to_str().unwrap()];
        args.extend(SMALL);
        args.extend(bad);
        let out = flaneur(&args);
        assert!(!out.status.success(), "{bad:?} was accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("error") && err.contains(says),
            "{bad:?}: {err}"
        );
        assert!(!none.exists(), "{bad:?} wrote files");
    }
}
