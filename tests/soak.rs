//! A long walk in constant memory: `flaneur bench soak` walks 100,000 frames of a
//! small city (the whole city fits the buffer, so nothing churns), and the process's
//! anonymous resident set must not grow after the warm-up by more than a few MiB. A walk
//! that kept a record or a pose per frame would grow by tens of MiB.

mod common;

use flaneur::BuildOptions;

#[test]
fn a_long_walk_keeps_its_heap_flat() {
    let c = common::city(300, 9, &BuildOptions::default());
    let out = c.dir.path().join("soak");
    let text = common::succeeded(&common::flaneur(&[
        "bench",
        "soak",
        c.db.to_str().unwrap(),
        "--frames",
        "100000",
        "--warm-up",
        "10000",
        "--sample-every",
        "1000",
        "--out",
        out.to_str().unwrap(),
    ]));
    assert!(text.contains("its growth after the warm-up"), "{text}");
    assert!(out.join("soak-rss.png").exists());
    let csv = common::Csv::read(&out.join("soak.csv"));
    let anon: Vec<(f64, f64)> = csv
        .rows
        .iter()
        .map(|r| (csv.num(r, "frame"), csv.num(r, "anon_bytes")))
        .collect();
    assert_eq!(anon.len(), 101, "a sample every 1,000 frames and the last");
    let settled: Vec<f64> = anon
        .iter()
        .filter(|(frame, _)| *frame >= 10_000.0)
        .map(|s| s.1)
        .collect();
    let growth = settled.iter().copied().fold(f64::MIN, f64::max) - settled[0];
    assert!(
        growth < 8.0 * (1 << 20) as f64,
        "the heap grew {:.1} MiB after the warm-up",
        growth / (1 << 20) as f64
    );
}

/// Starts `flaneur walk DB --frames 1000000000 ARGS`, and after three seconds checks
/// that it still runs, in under 300 MiB.
fn billion_frames_stay_small(db: &std::path::Path, args: &[&str]) {
    let mut walk = std::process::Command::new(env!("CARGO_BIN_EXE_flaneur"))
        .args([
            "walk",
            db.to_str().unwrap(),
            "--frames",
            "1000000000",
            "--quiet",
        ])
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_secs(3));
    let status = std::fs::read_to_string(format!("/proc/{}/status", walk.id()));
    let still = walk.try_wait().unwrap().is_none();
    let _ = walk.kill();
    let out = walk.wait_with_output().unwrap();
    assert!(
        still,
        "the walk {args:?} ended: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rss_kb: u64 = status
        .unwrap()
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().strip_suffix("kB"))
        .and_then(|v| v.trim().parse().ok())
        .unwrap();
    assert!(
        rss_kb < 300 * 1024,
        "{args:?}: {rss_kb} kB resident after 3 s"
    );
}

#[test]
fn a_walk_of_a_billion_frames_starts_and_stays_small() {
    let c = common::city(200, 10, &BuildOptions::default());
    billion_frames_stay_small(&c.db, &[]);
}

/// The PVS, VISUAL and scene-tree walks too, along a walk through the viewcells and a
/// motion pattern, their CSVs written as they go.
#[test]
fn every_mode_walks_a_billion_frames_in_constant_memory() {
    let c = common::city(
        80,
        11,
        &BuildOptions {
            page_size: 1024,
            visibility: Some(flaneur::visibility::VisibilityOptions {
                resolution: 16,
                ..Default::default()
            }),
            hdov: Some(flaneur::hdov::HdovOptions::default()),
            ..Default::default()
        },
    );
    let csv = c.dir.path().join("frames.csv");
    let csv = csv.to_str().unwrap();
    for args in [
        &["--mode", "pvs", "--path", "cells", "--csv", csv][..],
        &["--mode", "pvs", "--path", "normal", "--never-wait"],
        &["--mode", "visual", "--path", "cells", "--csv", csv],
        &["--mode", "vsc", "--path", "cells", "--csv", csv],
        &["--mode", "pb", "--path", "normal"],
    ] {
        billion_frames_stay_small(&c.db, args);
    }
}
