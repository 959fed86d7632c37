//! `flaneur bench hdov-search` on a small city built with the HDoV-tree: every method and
//! threshold present, the naive list flat across η, the tree's I/O falling as η grows,
//! η = 0 finding the naive method's objects, and the command's files written.

mod common;

use flaneur::hdov::HdovOptions;
use flaneur::visibility::VisibilityOptions;
use flaneur::{BuildOptions, Database};
use flaneur_bench::hdov_search::{self, HdovSearchConfig, HdovSearchRow, PLOT_SEARCH, PLOT_TOTAL};
use flaneur_bench::report::Report;

fn city() -> common::City {
    common::city(
        400,
        9,
        &BuildOptions {
            page_size: 1024,
            visibility: Some(VisibilityOptions {
                resolution: 16,
                ..Default::default()
            }),
            hdov: Some(HdovOptions::default()),
            ..Default::default()
        },
    )
}

const ETAS: [f32; 3] = [0.0, 0.002, 0.05];

#[test]
fn hdov_search_reads_less_as_eta_grows_and_beats_the_naive_total() {
    let city = city();
    let db = Database::open(&city.db).unwrap();
    let cfg = HdovSearchConfig {
        queries: 300,
        load_queries: 30,
        etas: ETAS.to_vec(),
        seed: 4,
    };
    let mut ticks = 0;
    let r = hdov_search::run(&db, &cfg, |_, _| ticks += 1).unwrap();
    assert_eq!(r.rows.len(), 4 * ETAS.len());
    assert_eq!(ticks, r.rows.len());
    let of = |m: &str| -> Vec<&HdovSearchRow> { r.rows.iter().filter(|x| x.method == m).collect() };
    let naive = of("naive");
    assert!(naive
        .windows(2)
        .all(|w| w[0].search_pages == w[1].search_pages));
    for scheme in ["horizontal", "vertical", "indexed"] {
        let rows = of(scheme);
        assert_eq!(rows.len(), ETAS.len());
        // η = 0 finds every object of the PVS, and nothing at an internal LOD.
        assert_eq!(rows[0].internal, 0.0);
        assert!(
            (rows[0].objects - naive[0].objects).abs() < 1e-9,
            "{scheme}"
        );
        // The search falls (or stays) as η grows, and stops somewhere. The total need
        // not fall at every step: a node's internal LOD stands for all its objects, the
        // hidden ones too, and may take more pages than its few visible objects at their
        // coarse levels; over the sweep it falls.
        for w in rows.windows(2) {
            assert!(w[1].search_pages <= w[0].search_pages, "{scheme}: {w:?}");
        }
        assert!(
            rows[2].total_pages < rows[0].total_pages,
            "{scheme}: {rows:?}"
        );
        assert!(rows[2].internal > 0.0, "{scheme}: {:?}", rows[2]);
        // Objects barely seen come at coarse levels: fewer pages than the naive method
        // reading every object at full detail, at any η.
        assert!(rows[0].total_pages < naive[0].total_pages, "{scheme}");
        // A tree costs more to search than a list to read (Fig. 5.22b).
        assert!(rows[0].search_pages > naive[0].search_pages, "{scheme}");
    }
    let dir = tempfile::tempdir().unwrap();
    r.plot(dir.path()).unwrap();
    for f in [PLOT_TOTAL, PLOT_SEARCH] {
        let b = std::fs::read(dir.path().join(f)).unwrap();
        assert!(b.starts_with(b"\x89PNG\r\n\x1a\n"), "{f}");
    }
    assert_eq!(r.to_csv().lines().count(), 1 + r.rows.len());
    assert!(r.markdown().contains("| 0.002 |"));
}

#[test]
fn the_command_writes_its_report_and_refuses_a_database_without_the_tree() {
    let city = city();
    let out = tempfile::tempdir().unwrap();
    let run = |db: &std::path::Path| {
        std::process::Command::new(env!("CARGO_BIN_EXE_flaneur"))
            .args(["bench", "hdov-search"])
            .arg(db)
            .args([
                "--queries",
                "40",
                "--load-queries",
                "5",
                "--etas",
                "0,0.01",
                "--out",
            ])
            .arg(out.path())
            .output()
            .unwrap()
    };
    let done = run(&city.db);
    assert!(
        done.status.success(),
        "{}",
        String::from_utf8_lossy(&done.stderr)
    );
    for f in ["hdov-search.csv", "hdov-search.md", PLOT_TOTAL, PLOT_SEARCH] {
        assert!(out.path().join(f).exists(), "{f}");
    }
    let plain = common::city(20, 1, &BuildOptions::default());
    let refused = run(&plain.db);
    assert!(!refused.status.success());
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(err.contains("no HDoV-tree"), "{err}");
}
