//! The walk experiments (`prefetch_k`, `view_culling`, `patterns`) on a small city: every
//! row present, CSV, PNG and markdown written, the figures within their bounds, and bad
//! settings refused.

mod common;

use flaneur::bench::patterns::{self, PatternsConfig, THESIS_PATTERNS};
use flaneur::bench::prefetch_k::{self, PrefetchKConfig};
use flaneur::bench::view_culling::{self, BufferModel, ViewCullingConfig};
use flaneur::{BuildOptions, Database, Error};

fn city() -> common::City {
    common::city(2500, 6, &BuildOptions { page_size: 1024, ..Default::default() })
}

const FRAMES: usize = 150;
/// A shallow frustum, so that a city of a kilometre holds many disk cells.
const FAR: f32 = 150.0;

fn is_png(path: &std::path::Path) -> bool {
    std::fs::read(path).map(|b| b.starts_with(b"\x89PNG\r\n\x1a\n")).unwrap_or(false)
}

#[test]
fn prefetch_k_sweeps_every_pattern() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    let cfg = PrefetchKConfig { frames: FRAMES, far: FAR, ks: vec![0.0, 0.8, 1.6], ..Default::default() };
    let mut calls = 0;
    let report = prefetch_k::run_with_progress(&db, &cfg, |done, total| {
        calls += 1;
        assert!(done <= total);
    })
    .unwrap();
    assert_eq!(calls, 15);
    assert_eq!(report.rows.len(), THESIS_PATTERNS.len() * cfg.ks.len());
    for p in THESIS_PATTERNS {
        for &k in &cfg.ks {
            let r = report.rows.iter().find(|r| r.pattern == p && r.k == k);
            let r = r.unwrap_or_else(|| panic!("no row for {p:?}, k = {k}"));
            assert!(r.queries > 0 && r.mean_frame_ms > 0.0 && r.mean_query_ms >= 0.0, "{r:?}");
            assert!(r.prefetches_used <= r.queries, "{r:?}");
            assert!(r.index_pages > 0, "{r:?}");
        }
        let best = report.best_k(p).unwrap();
        assert!(cfg.ks.contains(&best), "{p:?}: best k {best}");
        let best_ms = report.rows_of(p).find(|r| r.k == best).unwrap().mean_frame_ms;
        assert!(report.rows_of(p).all(|r| r.mean_frame_ms >= best_ms));
    }
    assert_eq!(report.best_k(flaneur::walk::Motion::Random), None);
    // Something must have been prefetched on the fast walk.
    assert!(report.rows_of(flaneur::walk::Motion::Fast).any(|r| r.prefetches_used > 0));

    let csv = report.to_csv();
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].starts_with("pattern,k,mean_frame_ms"));
    assert_eq!(lines.len(), 1 + report.rows.len());
    assert!(lines[1..].iter().all(|l| l.split(',').count() == lines[0].split(',').count()));

    let out = c.dir.path().join("plots");
    report.plot(&out).unwrap();
    assert!(is_png(&out.join(prefetch_k::FRAME_PLOT_FILE)));
    assert!(is_png(&out.join(prefetch_k::QUERY_PLOT_FILE)));

    let md = report.markdown();
    for p in THESIS_PATTERNS {
        assert!(md.contains(p.name()), "markdown does not name {p:?}");
    }
    assert!(md.contains("0.8"));
}

#[test]
fn view_culling_removes_more_with_larger_cells() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    let cfg = ViewCullingConfig { frames: FRAMES, far: FAR, ..Default::default() };
    let report = view_culling::run(&db, &cfg).unwrap();
    assert_eq!(report.rows.len(), cfg.sfs.len());
    for r in &report.rows {
        assert!(r.frames > 0 && r.queries > 0, "{r:?}");
        assert!((0.0..=100.0).contains(&r.objects_removed_pct), "{r:?}");
        assert!((0.0..=100.0).contains(&r.time_removed_pct), "{r:?}");
        assert!(r.mean_drawn <= r.mean_buffered, "{r:?}");
        assert_eq!(r.overflow_queries, 0, "{r:?}");
    }
    let share = |sf: f32| report.rows.iter().find(|r| r.sf == sf).unwrap();
    assert!(share(3.1).objects_removed_pct >= share(1.0).objects_removed_pct, "{:?}", report.rows);
    assert!(share(3.1).mean_buffered > share(1.0).mean_buffered, "{:?}", report.rows);
    // A cell as large as the frustum cell is queried more often than a larger one.
    assert!(share(1.0).queries >= share(3.1).queries, "{:?}", report.rows);

    // REVIEW's buffer keeps earlier cells too: it holds more, so culling removes more.
    let review = view_culling::run(&db, &ViewCullingConfig { buffer: BufferModel::Review, ..cfg.clone() }).unwrap();
    for (a, b) in report.rows.iter().zip(&review.rows) {
        assert!(b.mean_buffered >= a.mean_buffered && b.objects_removed_pct >= a.objects_removed_pct - 1e-9, "{a:?} {b:?}");
        assert!((0.0..=100.0).contains(&b.time_removed_pct), "{b:?}");
    }

    let csv = report.to_csv();
    assert_eq!(csv.lines().count(), 1 + report.rows.len());
    assert!(csv.starts_with("sf,"));
    let out = c.dir.path().join("plots");
    report.plot(&out).unwrap();
    assert!(is_png(&out.join(view_culling::PLOT_FILE)));
    let md = report.markdown();
    assert!(md.contains("91.34") && md.contains("3.1"), "{md}");
}

#[test]
fn optimal_reads_fewer_pages_per_query_than_box() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    // A minute of walking, so that even the slow walk (4 m/s) leaves a few disk cells:
    // the first query of a walk is the same for both configurations.
    let cfg = PatternsConfig { frames: 600, fps: 10.0, far: FAR, ..Default::default() };
    let report = patterns::run(&db, &cfg).unwrap();
    assert_eq!(report.rows.len(), THESIS_PATTERNS.len());
    for (r, p) in report.rows.iter().zip(THESIS_PATTERNS) {
        assert_eq!(r.pattern, p);
        assert!(r.optimal.queries > 0 && r.box_io.queries > 0, "{r:?}");
        assert!(r.optimal.index_per_query < r.box_io.index_per_query, "{p:?}: {r:?}");
        assert!(r.ratio > 0.0 && r.ratio <= 1.0, "{p:?}: {r:?}");
        let sum = r.box_io.index_per_query + r.box_io.mesh_per_query;
        assert!((r.box_io.io_per_query - sum).abs() < 1e-9);
    }
    let csv = report.to_csv();
    assert_eq!(csv.lines().count(), 1 + 2 * report.rows.len());
    let out = c.dir.path().join("plots");
    report.plot(&out).unwrap();
    assert!(is_png(&out.join(patterns::PLOT_FILE)));
    let md = report.markdown();
    assert!(THESIS_PATTERNS.iter().all(|p| md.contains(p.name())));
    assert!(md.contains("1877.75"));
}

#[test]
fn bad_settings_are_errors() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    let invalid = |r: flaneur::Result<()>| matches!(r, Err(Error::Invalid(_)));

    let k = |f: fn(&mut PrefetchKConfig)| {
        let mut cfg = PrefetchKConfig { frames: 10, far: FAR, ..Default::default() };
        f(&mut cfg);
        prefetch_k::run(&db, &cfg).map(|_| ())
    };
    assert!(invalid(k(|c| c.ks.clear())));
    assert!(invalid(k(|c| c.ks = vec![0.4, -0.2])));
    assert!(invalid(k(|c| c.ks = vec![f32::NAN])));
    assert!(invalid(k(|c| c.ks = vec![0.4, 0.4])));
    assert!(invalid(k(|c| c.patterns.clear())));
    assert!(invalid(k(|c| c.sf = 0.5)));
    assert!(invalid(k(|c| c.frames = 0)));
    assert!(invalid(k(|c| c.far = f32::NAN)));
    assert!(invalid(k(|c| c.fps = 0.0)));
    assert!(invalid(k(|c| c.memory_budget = 0)));

    let v = |f: fn(&mut ViewCullingConfig)| {
        let mut cfg = ViewCullingConfig { frames: 10, far: FAR, ..Default::default() };
        f(&mut cfg);
        view_culling::run(&db, &cfg).map(|_| ())
    };
    assert!(invalid(v(|c| c.sfs.clear())));
    assert!(invalid(v(|c| c.sfs = vec![1.5, 0.9])));
    assert!(invalid(v(|c| c.sfs = vec![f32::INFINITY])));
    assert!(invalid(v(|c| c.repeats = 0)));
    assert!(invalid(v(|c| c.far = 0.5)));

    let p = |f: fn(&mut PatternsConfig)| {
        let mut cfg = PatternsConfig { frames: 10, far: FAR, ..Default::default() };
        f(&mut cfg);
        patterns::run(&db, &cfg).map(|_| ())
    };
    assert!(invalid(p(|c| c.patterns.clear())));
    assert!(invalid(p(|c| c.sf = f32::NAN)));
    assert!(invalid(p(|c| c.prefetch_k = -1.0)));
    assert!(invalid(p(|c| c.frames = 0)));
    // A sane short run still works.
    assert!(p(|_| {}).is_ok());
}
