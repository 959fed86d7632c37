//! The walk experiments (`prefetch_k`, `view_culling`, `patterns`, and `bench csearch`'s
//! `cell_size`, `frame_time` and `db_size`) on a small city: every row present, CSV, PNG
//! and markdown written, the figures within their bounds, and bad settings refused.

mod common;

use common::flaneur;

use flaneur::path::motion::Motion;
use flaneur::walk::review::Preset;
use flaneur::{BuildOptions, Database, Error};
use flaneur_bench::cell_size::{self, CellSizeConfig};
use flaneur_bench::db_size::{self, DbSizeConfig};
use flaneur_bench::frame_time::{self, FrameTimeConfig};
use flaneur_bench::patterns::{self, PatternsConfig};
use flaneur_bench::prefetch_k::{self, PrefetchKConfig};
use flaneur_bench::report::Report;
use flaneur_bench::view_culling::{self, BufferModel, ViewCullingConfig};
use flaneur_bench::walk_setup::{WalkSetup, THESIS_PATTERNS};

fn city() -> common::City {
    common::city(
        2500,
        6,
        &BuildOptions {
            page_size: 1024,
            ..Default::default()
        },
    )
}

const FRAMES: usize = 150;
/// A shallow frustum, so that a city of a kilometre holds many disk cells.
const FAR: f32 = 150.0;

fn is_png(path: &std::path::Path) -> bool {
    std::fs::read(path)
        .map(|b| b.starts_with(b"\x89PNG\r\n\x1a\n"))
        .unwrap_or(false)
}

/// The short walk of these tests: `frames` frames through a shallow frustum, played
/// eight times faster than real time.
fn walk(frames: usize) -> WalkSetup {
    WalkSetup {
        frames,
        far: FAR,
        pace: Some(8.0),
        ..WalkSetup::default()
    }
}

/// A short path of one pattern for the figures that walk once per configuration and per
/// cell size or city: a second and a half of path, since a walk that prefetches may be
/// paced against the path's clock.
fn short_walk(pattern: Motion) -> WalkSetup {
    WalkSetup {
        frames: SHORT_FRAMES,
        fps: 60.0,
        patterns: vec![pattern],
        ..walk(SHORT_FRAMES)
    }
}

const SHORT_FRAMES: usize = 90;

/// A CSV row: its text fields, then its numbers.
type CsvRow = (Vec<String>, Vec<f64>);

/// Parses a CSV whose first `text` columns are text and the rest numbers: the header,
/// and every row with as many fields as the header.
fn parse_csv(csv: &str, text: usize) -> (Vec<String>, Vec<CsvRow>) {
    let mut lines = csv.lines();
    let head: Vec<String> = lines
        .next()
        .expect("a header")
        .split(',')
        .map(String::from)
        .collect();
    let rows = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), head.len(), "{l}");
            let nums = f[text..]
                .iter()
                .map(|x| x.parse::<f64>().unwrap_or_else(|_| panic!("'{x}' in {l}")))
                .collect();
            (f[..text].iter().map(|x| x.to_string()).collect(), nums)
        })
        .collect();
    (head, rows)
}

#[test]
fn prefetch_k_sweeps_every_pattern() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    let cfg = PrefetchKConfig {
        walk: walk(FRAMES),
        ks: vec![0.0, 0.8, 1.6],
        repeats: 1,
    };
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
            assert!(
                r.queries > 0 && r.mean_frame_ms > 0.0 && r.mean_query_ms >= 0.0,
                "{r:?}"
            );
            assert!(r.prefetches_used <= r.queries, "{r:?}");
            assert!(r.index_pages > 0, "{r:?}");
        }
        let best = report.best_k(p).unwrap();
        assert!(cfg.ks.contains(&best), "{p:?}: best k {best}");
        let at_best = report.rows_of(p).find(|r| r.k == best).unwrap();
        let fewest = (at_best.sync_queries, at_best.pages());
        assert!(report
            .rows_of(p)
            .all(|r| (r.sync_queries, r.pages()) >= fewest));
        let fastest = report.best_frame_k(p).unwrap();
        let best_ms = report
            .rows_of(p)
            .find(|r| r.k == fastest)
            .unwrap()
            .mean_frame_ms;
        assert!(report.rows_of(p).all(|r| r.mean_frame_ms >= best_ms));
    }
    assert_eq!(report.best_k(Motion::Random), None);
    // Something must have been prefetched on the fast walk.
    assert!(report.rows_of(Motion::Fast).any(|r| r.prefetches_used > 0));

    let csv = report.to_csv();
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].starts_with("pattern,k,mean_frame_ms"));
    assert_eq!(lines.len(), 1 + report.rows.len());
    assert!(lines[1..]
        .iter()
        .all(|l| l.split(',').count() == lines[0].split(',').count()));

    let out = c.dir.path().join("plots");
    report.plot(&out).unwrap();
    assert!(is_png(&out.join(prefetch_k::FRAME_PLOT_FILE)));
    assert!(is_png(&out.join(prefetch_k::QUERY_PLOT_FILE)));
    assert!(is_png(&out.join(prefetch_k::PAGES_PLOT_FILE)));

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
    let cfg = ViewCullingConfig {
        walk: WalkSetup {
            patterns: vec![Motion::Normal],
            ..walk(FRAMES)
        },
        ..Default::default()
    };
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
    assert!(
        share(3.1).objects_removed_pct >= share(1.0).objects_removed_pct,
        "{:?}",
        report.rows
    );
    assert!(
        share(3.1).mean_buffered > share(1.0).mean_buffered,
        "{:?}",
        report.rows
    );
    // A cell as large as the frustum cell is queried more often than a larger one.
    assert!(
        share(1.0).queries >= share(3.1).queries,
        "{:?}",
        report.rows
    );

    // REVIEW's buffer keeps earlier cells too: it holds more, so culling removes more.
    let review = view_culling::run(
        &db,
        &ViewCullingConfig {
            buffer: BufferModel::Review,
            ..cfg.clone()
        },
    )
    .unwrap();
    for (a, b) in report.rows.iter().zip(&review.rows) {
        assert!(
            b.mean_buffered >= a.mean_buffered
                && b.objects_removed_pct >= a.objects_removed_pct - 1e-9,
            "{a:?} {b:?}"
        );
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
    let cfg = PatternsConfig {
        walk: WalkSetup {
            fps: 10.0,
            ..walk(600)
        },
        ..Default::default()
    };
    let report = patterns::run(&db, &cfg).unwrap();
    assert_eq!(report.rows.len(), THESIS_PATTERNS.len());
    for (r, p) in report.rows.iter().zip(THESIS_PATTERNS) {
        assert_eq!(r.pattern, p);
        assert!(r.optimal.queries > 0 && r.box_io.queries > 0, "{r:?}");
        assert!(
            r.optimal.index_per_query < r.box_io.index_per_query,
            "{p:?}: {r:?}"
        );
        // Per query after the first cell, which both load the same way, cold; 0 when
        // Optimal needed no page after it (a slow walk in a small city can).
        assert!(r.optimal.first_load_pages > 0, "{p:?}: {r:?}");
        assert_eq!(
            r.optimal.first_load_pages, r.box_io.first_load_pages,
            "{p:?}"
        );
        assert!((0.0..=1.0).contains(&r.ratio), "{p:?}: {r:?}");
        assert!(
            r.ratio_with_first > 0.0 && r.ratio_with_first <= 1.0,
            "{p:?}: {r:?}"
        );
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
        let mut cfg = PrefetchKConfig {
            walk: walk(10),
            ..Default::default()
        };
        f(&mut cfg);
        prefetch_k::run(&db, &cfg).map(|_| ())
    };
    assert!(invalid(k(|c| c.ks.clear())));
    assert!(invalid(k(|c| c.ks = vec![0.4, -0.2])));
    assert!(invalid(k(|c| c.ks = vec![f32::NAN])));
    assert!(invalid(k(|c| c.ks = vec![0.4, 0.4])));
    assert!(invalid(k(|c| c.repeats = 0)));
    assert!(invalid(k(|c| c.walk.patterns.clear())));
    assert!(invalid(k(|c| c.walk.sf = 0.5)));
    assert!(invalid(k(|c| c.walk.frames = 0)));
    assert!(invalid(k(|c| c.walk.far = f32::NAN)));
    assert!(invalid(k(|c| c.walk.fps = 0.0)));
    assert!(invalid(k(|c| c.walk.memory_budget = 0)));

    let v = |f: fn(&mut ViewCullingConfig)| {
        let mut cfg = ViewCullingConfig {
            walk: WalkSetup {
                patterns: vec![Motion::Normal],
                ..walk(10)
            },
            ..Default::default()
        };
        f(&mut cfg);
        view_culling::run(&db, &cfg).map(|_| ())
    };
    assert!(invalid(v(|c| c.sfs.clear())));
    assert!(invalid(v(|c| c.sfs = vec![1.5, 0.9])));
    assert!(invalid(v(|c| c.sfs = vec![f32::INFINITY])));
    assert!(invalid(v(|c| c.repeats = 0)));
    assert!(invalid(v(|c| c.walk.far = 0.5)));
    assert!(invalid(v(
        |c| c.walk.patterns = vec![Motion::Normal, Motion::Fast]
    )));

    let p = |f: fn(&mut PatternsConfig)| {
        let mut cfg = PatternsConfig {
            walk: walk(10),
            ..Default::default()
        };
        f(&mut cfg);
        patterns::run(&db, &cfg).map(|_| ())
    };
    assert!(invalid(p(|c| c.walk.patterns.clear())));
    assert!(invalid(p(|c| c.walk.sf = f32::NAN)));
    assert!(invalid(p(|c| c.prefetch_k = -1.0)));
    assert!(invalid(p(|c| c.walk.frames = 0)));
    // A sane short run still works.
    assert!(p(|_| {}).is_ok());

    let one = || WalkSetup {
        patterns: vec![Motion::Normal],
        ..walk(10)
    };
    let cs = |f: fn(&mut CellSizeConfig)| {
        let mut cfg = CellSizeConfig {
            walk: one(),
            ..Default::default()
        };
        f(&mut cfg);
        cell_size::run(&db, &cfg).map(|_| ())
    };
    assert!(invalid(cs(|c| c.sfs.clear())));
    assert!(invalid(cs(|c| c.sfs = vec![1.5, 0.9])));
    assert!(invalid(cs(|c| c.sfs = vec![1.5, 1.5])));
    assert!(invalid(cs(|c| c.sfs = vec![f32::NAN])));
    assert!(invalid(cs(
        |c| c.walk.patterns = vec![Motion::Normal, Motion::Slow]
    )));
    assert!(invalid(cs(|c| c.walk.frames = 0)));

    let ft = |f: fn(&mut FrameTimeConfig)| {
        let mut cfg = FrameTimeConfig { walk: one() };
        f(&mut cfg);
        frame_time::run(&db, &cfg).map(|_| ())
    };
    assert!(invalid(ft(|c| c.walk.patterns.clear())));
    assert!(invalid(ft(|c| c.walk.patterns = THESIS_PATTERNS.to_vec())));
    assert!(invalid(ft(|c| c.walk.memory_budget = 0)));

    // Refused before a city is generated.
    let dir = c.dir.path().join("no-cities");
    let ds = |f: fn(&mut DbSizeConfig)| {
        let mut cfg = DbSizeConfig {
            walk: one(),
            sizes: vec![100],
            page_size: 1024,
            ..Default::default()
        };
        f(&mut cfg);
        db_size::run(&dir, &cfg).map(|_| ())
    };
    assert!(invalid(ds(|c| c.sizes.clear())));
    assert!(invalid(ds(|c| c.sizes = vec![100, 0])));
    assert!(invalid(ds(|c| c.sizes = vec![100, 200, 100])));
    assert!(invalid(ds(|c| c.walk.sf = 0.5)));
    assert!(invalid(ds(
        |c| c.walk.patterns = vec![Motion::Fast, Motion::Slow]
    )));
    assert!(!dir.exists());
}

#[test]
fn cell_size_sweeps_every_configuration() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    let cfg = CellSizeConfig {
        walk: short_walk(Motion::Normal),
        sfs: vec![1.0, 3.1],
    };
    let mut calls = 0;
    let report = cell_size::run_with_progress(&db, &cfg, |done, total| {
        calls += 1;
        assert!(done <= total);
    })
    .unwrap();
    assert_eq!(calls, cfg.sfs.len() * Preset::ALL.len());
    assert_eq!(report.rows.len(), cfg.sfs.len() * Preset::ALL.len());
    for &sf in &cfg.sfs {
        for p in Preset::ALL {
            let r = report
                .row(sf, p)
                .unwrap_or_else(|| panic!("no row for {p:?} at SF {sf}"));
            assert!(r.queries > 0 && r.index_pages > 0, "{r:?}");
            assert!(
                r.mean_frame_ms >= 0.0
                    && r.frame_ms_variance >= 0.0
                    && r.max_frame_ms >= r.mean_frame_ms,
                "{r:?}"
            );
        }
        // Complement search, index cache and prefetching never read more per query than BOX.
        let (o, b) = (
            report.row(sf, Preset::Optimal).unwrap(),
            report.row(sf, Preset::Box).unwrap(),
        );
        assert!(
            o.index_per_query <= b.index_per_query,
            "SF {sf}: {o:?} {b:?}"
        );
        assert!(o.io_per_query <= b.io_per_query, "SF {sf}: {o:?} {b:?}");
    }
    // A disk cell as large as the frustum cell is left at every step; a larger one less often.
    let queries = |sf: f32| report.row(sf, Preset::Box).unwrap().queries;
    assert!(queries(1.0) > queries(3.1), "{:?}", report.rows);

    let (head, rows) = parse_csv(&report.to_csv(), 2);
    assert_eq!(&head[..3], ["sf", "configuration", "mean_frame_ms"]);
    assert_eq!(rows.len(), report.rows.len());
    for &sf in &cfg.sfs {
        for p in Preset::ALL {
            assert!(
                rows.iter()
                    .any(|(t, _)| t[0].parse::<f32>().unwrap() == sf && t[1] == p.name()),
                "{p:?} at {sf}"
            );
        }
    }

    let out = c.dir.path().join("plots");
    report.plot(&out).unwrap();
    for f in [
        cell_size::FRAME_PLOT_FILE,
        cell_size::VARIANCE_PLOT_FILE,
        cell_size::PAGES_PLOT_FILE,
    ] {
        assert!(is_png(&out.join(f)), "{f}");
    }
    let md = report.markdown();
    for word in [
        "Fig. 4.19",
        "Fig. 4.20",
        "Optimal",
        "NC",
        "NP",
        "BOX",
        "| 3.1 |",
    ] {
        assert!(md.contains(word), "{word} missing from\n{md}");
    }
}

#[test]
fn frame_time_follows_one_path() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    let cfg = FrameTimeConfig {
        walk: short_walk(Motion::Fast),
    };
    // Both with the same 1 MB index cache, as in the thesis's figure; BOX without prefetching.
    let boxed = cfg.review(Preset::Box);
    assert_eq!(boxed.index_cache, cfg.review(Preset::Optimal).index_cache);
    assert!(boxed.index_cache.is_some() && boxed.prefetch_k.is_none());

    let report = frame_time::run(&db, &cfg).unwrap();
    assert_eq!(report.rows.len(), SHORT_FRAMES);
    assert!(report
        .rows
        .iter()
        .enumerate()
        .all(|(i, r)| r.frame == i && r.optimal_ms >= 0.0 && r.box_ms >= 0.0));
    assert!(report.rows.windows(2).all(|w| w[0].time < w[1].time));
    assert!(report.rows[0].optimal_queried && report.rows[0].box_queried);
    // A fast walk through a shallow frustum leaves its first disk cell.
    assert!(
        report.rows.iter().skip(1).any(|r| r.box_queried),
        "BOX never queried again"
    );
    assert!(report.summaries.iter().all(|s| s.frames == SHORT_FRAMES));

    let (head, rows) = parse_csv(&report.to_csv(), 0);
    assert_eq!(
        head,
        [
            "frame",
            "time",
            "optimal_ms",
            "box_ms",
            "optimal_queried",
            "box_queried"
        ]
    );
    assert_eq!(rows.len(), SHORT_FRAMES);
    assert!(rows
        .iter()
        .zip(&report.rows)
        .all(|((_, v), r)| v[0] == r.frame as f64 && (v[3] - r.box_ms).abs() < 1e-3));

    let out = c.dir.path().join("plots");
    report.plot(&out).unwrap();
    assert!(is_png(&out.join(frame_time::PLOT_FILE)));
    let md = report.markdown();
    assert!(
        md.contains("Fig. 4.21") && md.contains("| Optimal |") && md.contains("| BOX |"),
        "{md}"
    );
}

#[test]
fn db_size_builds_a_series_once() {
    let dir = tempfile::tempdir().unwrap();
    let cities = dir.path().join("cities");
    let cfg = DbSizeConfig {
        walk: short_walk(Motion::Normal),
        sizes: vec![1200, 300, 600],
        page_size: 1024,
        ..Default::default()
    };
    let report = db_size::run(&cities, &cfg).unwrap();
    // Smallest first, whatever the order asked.
    assert_eq!(
        report.cities.iter().map(|c| c.objects).collect::<Vec<_>>(),
        [300, 600, 1200]
    );
    assert!(report
        .cities
        .iter()
        .all(|c| c.built && c.path.starts_with(&cities)));
    assert_eq!(report.rows.len(), 3 * db_size::PRESETS.len());
    let mut last_pages = 0;
    for city in &report.cities {
        assert_eq!(Database::open(&city.path).unwrap().objects(), city.objects);
        let (o, b) = (
            report.row(city.objects, Preset::Optimal).unwrap(),
            report.row(city.objects, Preset::Box).unwrap(),
        );
        assert!(o.queries > 0 && b.queries > 0, "{o:?} {b:?}");
        assert!(o.mean_search_ms >= 0.0 && b.mean_search_ms >= 0.0 && o.mean_query_ms >= 0.0);
        // Frame 0 always searches on the viewer's thread; BOX never prefetches.
        assert!(
            o.searches_timed >= 1 && o.searches_timed <= o.queries,
            "{o:?}"
        );
        assert_eq!(b.searches_timed, b.queries, "{b:?}");
        assert!(o.index_per_query <= b.index_per_query, "{o:?} {b:?}");
        assert_eq!(o.db_pages, b.db_pages);
        assert!(o.db_pages > last_pages, "a larger city has more pages");
        last_pages = o.db_pages;
    }

    let (head, rows) = parse_csv(&report.to_csv(), 2);
    assert_eq!(&head[..2], ["objects", "configuration"]);
    assert_eq!(rows.len(), report.rows.len());
    for city in &report.cities {
        for p in db_size::PRESETS {
            assert!(rows
                .iter()
                .any(|(t, _)| t[0] == city.objects.to_string() && t[1] == p.name()));
        }
    }
    let out = dir.path().join("plots");
    report.plot(&out).unwrap();
    assert!(
        is_png(&out.join(db_size::TIME_PLOT_FILE)) && is_png(&out.join(db_size::PAGES_PLOT_FILE))
    );
    let md = report.markdown();
    assert!(md.contains("Fig. 4.22") && md.contains("| 1200 |"), "{md}");

    // A second run reuses the city it finds; BOX (no cache, no prefetching) reads the same pages.
    let again = db_size::run(
        &cities,
        &DbSizeConfig {
            sizes: vec![600],
            ..cfg.clone()
        },
    )
    .unwrap();
    assert!(!again.cities[0].built);
    let pages = |r: &db_size::DbSizeReport| r.row(600, Preset::Box).unwrap().index_pages;
    assert_eq!(pages(&again), pages(&report));
}

#[test]
fn csearch_command_writes_every_figure() {
    let c = common::city(
        800,
        4,
        &BuildOptions {
            page_size: 1024,
            ..Default::default()
        },
    );
    let db = c.db.to_str().unwrap();
    let dir = c.dir.path().join("bench");
    let d = dir.to_str().unwrap();
    let small = [
        "--cell",
        "300",
        "--steps",
        "40",
        "--packed-only",
        "--frames",
        "90",
        "--fps",
        "60",
        "--far",
        "150",
    ];
    let mut args = vec![
        "bench", "csearch", db, "--sfs", "1,2", "--sizes", "200,400", "--out", d,
    ];
    args.extend(small);
    let out = flaneur(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in [
        "csearch.csv",
        "csearch.md",
        "csearch-cell-size.csv",
        "csearch-frame-time.csv",
        "csearch-db-size.csv",
        cell_size::FRAME_PLOT_FILE,
        cell_size::VARIANCE_PLOT_FILE,
        cell_size::PAGES_PLOT_FILE,
        frame_time::PLOT_FILE,
        db_size::TIME_PLOT_FILE,
        db_size::PAGES_PLOT_FILE,
    ] {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    let md = std::fs::read_to_string(dir.join("csearch.md")).unwrap();
    for section in ["# csearch", "Fig. 4.19", "Fig. 4.21", "Fig. 4.22"] {
        assert!(md.contains(section), "{section} missing from the summary");
    }
    // The series is built with the benched database's page size, once.
    let cities: Vec<String> = std::fs::read_dir(dir.join("cities"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(cities.len(), 2, "{cities:?}");
    assert!(
        cities.iter().all(|n| n.ends_with("-1024B.flaneur")),
        "{cities:?}"
    );

    // --no-walks: the query-by-query run alone.
    let only = c.dir.path().join("only");
    let mut args = vec![
        "bench",
        "csearch",
        db,
        "--no-walks",
        "--out",
        only.to_str().unwrap(),
    ];
    args.extend(small);
    let out = flaneur(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(only.join("csearch.md").exists() && !only.join("csearch-cell-size.csv").exists());

    // Bad settings stop it before anything is written.
    for bad in [
        ["--sfs", "0.5"],
        ["--sizes", "0"],
        ["--sizes", "300,300"],
        ["--patterns", "normal,fast"],
    ] {
        let none = c.dir.path().join("none");
        let mut args = vec!["bench", "csearch", db, "--out", none.to_str().unwrap()];
        args.extend(bad);
        let out = flaneur(&args);
        assert!(!out.status.success(), "{bad:?} was accepted");
        assert!(
            String::from_utf8_lossy(&out.stderr).contains("error"),
            "{bad:?}"
        );
        assert!(!none.exists(), "{bad:?} wrote files");
    }
}
