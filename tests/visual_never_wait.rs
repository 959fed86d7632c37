//! The VISUAL walk that never waits on a read: the HDoV-tree's searches and the finds'
//! meshes read on a loader thread, the viewer drawing what has arrived, coarse levels
//! first; locally and over HTTP from nginx, through a server that goes away, and from
//! the command line.

mod common;
#[path = "common/http.rs"]
mod servers;

use flaneur::geom::Camera;
use flaneur::hdov::HdovOptions;
use flaneur::path::{cell_walk, CameraPath};
use flaneur::visibility::VisibilityOptions;
use flaneur::walk::visual::{VisualConfig, VisualReport};
use flaneur::walk::{self, FrameSink, Frames, ObjectBuffer, Playback, Selection};
use flaneur::{BuildOptions, Database};
use servers::Nginx;

/// A small city with LODs (so that finds come coarse first) and the HDoV-tree.
fn city(seed: u64) -> common::City {
    common::city(
        150,
        seed,
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

/// The last frame's drawn finds, each with the level it was drawn at.
#[derive(Default)]
struct LastDrawn(Vec<(u64, usize)>);

impl FrameSink for LastDrawn {
    fn frame(
        &mut self,
        _: usize,
        _: &Camera,
        _: &ObjectBuffer,
        s: &mut Selection<'_>,
    ) -> flaneur::Result<()> {
        self.0 = s.culled.iter().map(|o| (o.entry.id, o.level)).collect();
        self.0.sort_unstable();
        Ok(())
    }
}

fn config(never_wait: bool, prefetch_k: Option<f32>) -> VisualConfig {
    VisualConfig {
        never_wait,
        prefetch_k,
        pace: Some(1.0),
        ..VisualConfig::default()
    }
}

fn walk(db: &Database, path: &CameraPath, cfg: &VisualConfig) -> (VisualReport, LastDrawn) {
    let mut last = LastDrawn::default();
    let r = walk::run(
        db,
        &cfg.clone().into(),
        &mut Playback::path(path).drawn_by(&mut last),
        Frames::Keep,
    )
    .unwrap()
    .try_into()
    .unwrap();
    (r, last)
}

/// What must hold of a never-wait walk against the waiting walk of the same path
/// without a prefetch: the same cells frame by frame, no search on the viewer's thread,
/// nothing failed, and the last frame complete, drawing its cell's finds at the levels
/// the waiting walk draws them at. (A waiting walk that prefetches may end drawing some
/// finds at the level the prefetched cell wanted; a never-wait walk gives the viewer's
/// cell the say.)
fn check_against_waiting(
    (r, last): &(VisualReport, LastDrawn),
    (waits, waits_last): &(VisualReport, LastDrawn),
) {
    assert!(r.config.never_wait && !waits.config.never_wait);
    let cells = |r: &VisualReport| r.frames.iter().map(|f| f.cell).collect::<Vec<_>>();
    assert_eq!(cells(r), cells(waits));
    let s = &r.summary;
    assert_eq!(s.searches, 0, "a search on the viewer's thread");
    assert_eq!(s.failed_loads, 0, "{:?}", s.last_load_error);
    let end = r.frames.last().unwrap();
    assert!(end.cell.is_some());
    assert_eq!((end.visual_misses, end.coarse), (0, 0), "{end:?}");
    assert!(!waits_last.0.is_empty());
    assert_eq!(last.0, waits_last.0);
    assert!(s.first_complete_frame.is_some());
    assert!(s.visual_misses >= s.visual_misses_after_start);
    // The waiting walk misses nothing: it reads what a frame needs before drawing it.
    assert_eq!(waits.summary.visual_misses, 0);
}

#[test]
fn a_never_wait_visual_walk_draws_what_arrives_and_ends_as_the_waiting_walk() {
    let c = city(31);
    let db = Database::open(&c.db).unwrap();
    let path = common::walk_then_stand(&db);
    let waits = walk(&db, &path, &config(false, None));
    for k in [None, Some(0.8)] {
        let r = walk(&db, &path, &config(true, k));
        check_against_waiting(&r, &waits);
        // Every find came coarse before it came at its level, where it has coarse levels.
        assert!(r.0.summary.model_pages > waits.0.summary.model_pages);
    }
}

#[test]
fn a_never_wait_visual_walk_over_http_ends_as_the_local_one() {
    let c = city(32);
    let server = Nginx::start(c.dir.path());
    let local = Database::open(&c.db).unwrap();
    let path = common::walk_then_stand(&local);
    let waits = walk(&local, &path, &config(false, None));
    let db = Database::open_url(&server.url("city.flaneur")).unwrap();
    let r = walk(&db, &path, &config(true, Some(0.8)));
    check_against_waiting(&r, &waits);
    assert!(db.remote_stats().unwrap().requests > 2);
}

#[test]
fn a_never_wait_visual_walk_goes_on_without_its_server_and_says_so() {
    let c = city(33);
    let mut server = Nginx::start(c.dir.path());
    let url = server.url("city.flaneur");
    let db = Database::open_url_with(&url, &servers::impatient()).unwrap();
    // The viewcells and the tree's head are read while the server is up; then it goes,
    // and no search or mesh can be.
    let path = cell_walk(&db, 30, 1.0, 30.0, 3).unwrap();
    db.hdov_head().unwrap();
    server.stop();
    let cfg = VisualConfig {
        pace: Some(4.0),
        ..config(true, Some(0.8))
    };
    let (r, _) = walk(&db, &path, &cfg);
    assert_eq!(r.frames.len(), 30);
    let s = &r.summary;
    assert!(s.failed_loads >= 1);
    let said = s.last_load_error.as_deref().unwrap();
    assert!(said.contains(&url), "{said}");
    assert!(s.first_complete_frame.is_none() && s.visual_misses > 0);
    assert!(r.frames.iter().all(|f| f.drawn == 0));
}

#[test]
fn the_cli_walks_visual_never_waiting_and_benches_it_over_http() {
    let c = city(34);
    let db = c.db.to_str().unwrap();
    let csv = c.dir.path().join("frames.csv");
    let out = common::flaneur(&[
        "walk",
        db,
        "--mode",
        "visual",
        "--never-wait",
        "--next-cell-prefetch",
        "0.8",
        "--frames",
        "60",
        "--speed",
        "8",
        "--csv",
        csv.to_str().unwrap(),
    ]);
    let said = common::succeeded(&out);
    assert!(said.contains("never waits on a read"), "{said}");
    assert!(said.contains("searches 0 on the viewer's thread"), "{said}");
    let rows = common::Csv::read(&csv);
    assert_eq!(rows.rows.len(), 60);
    assert!(rows.rows.iter().any(|r| rows.num(r, "visual_misses") > 0.0));

    let dir = c.dir.path().join("bench");
    let out = common::flaneur(&[
        "bench",
        "visual-http",
        db,
        "--frames",
        "60",
        "--speed",
        "8",
        "--rtts",
        "0,40",
        "--patterns",
        "normal",
        "--out",
        dir.to_str().unwrap(),
    ]);
    common::succeeded(&out);
    for f in [
        flaneur_bench::visual_http::PLOT,
        "visual-http.csv",
        "visual-http.md",
    ] {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    let csv = common::Csv::read(&dir.join("visual-http.csv"));
    let sources: Vec<&str> = csv.rows.iter().map(|r| csv.get(r, "source")).collect();
    assert_eq!(sources, ["local-waiting", "local", "http", "http"]);
    for r in &csv.rows {
        let n = |name: &str| csv.num(r, name);
        assert_eq!(n("failed_loads"), 0.0, "{r:?}");
        // Only a walk that waits searches on the viewer's thread.
        if csv.get(r, "source") != "local-waiting" {
            assert_eq!(n("searches_on_viewer"), 0.0, "{r:?}");
        }
        if csv.get(r, "source") == "http" {
            assert!(n("requests") > 0.0 && n("bytes") > 0.0, "{r:?}");
        }
    }
    let out = common::flaneur(&["bench", "visual-http", db, "--eta", "nan", "--out", "x"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--eta") && err.contains("not a finite number"),
        "{err}"
    );
}
