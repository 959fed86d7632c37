//! The VISUAL walk (Shou 2002 §5.8.5) on small cities built with the HDoV-tree: it draws
//! an object far away but visible that REVIEW's box loses, brings cells in by delta,
//! falls back to REVIEW's query outside every viewcell and counts those frames, its
//! next-cell prefetch changes where pages are read but not what is drawn, and a damaged
//! internal LOD is named, or left out and counted for a viewer that walks on.

mod common;

use std::collections::HashSet;

use glam::Vec3;

use flaneur::geom::Camera;
use flaneur::hdov::{Found, HdovOptions};
use flaneur::path::{cell_walk, CameraPath, Pose};
use flaneur::visibility::VisibilityOptions;
use flaneur::walk::review::{Preset, ReviewConfig};
use flaneur::walk::visual::{VisualConfig, VisualReport};
use flaneur::walk::{self, FrameSink, Frames, ObjectBuffer, Playback, Selection};
use flaneur::walk::{Viewer, GROUP_ID};
use flaneur::{BuildOptions, Database, Error};

fn city() -> &'static common::City {
    static CITY: std::sync::OnceLock<common::City> = std::sync::OnceLock::new();
    CITY.get_or_init(|| {
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
    })
}

/// Each frame's drawn ids and eye, as the walk handed them over.
#[derive(Default)]
struct Recorder {
    frames: Vec<(Vec3, Vec<u64>)>,
}

impl FrameSink for Recorder {
    fn frame(
        &mut self,
        _: usize,
        camera: &Camera,
        _: &ObjectBuffer,
        s: &mut Selection<'_>,
    ) -> flaneur::Result<()> {
        let ids = s.culled.iter().map(|o| o.entry.id).collect();
        self.frames.push((camera.position, ids));
        Ok(())
    }
}

/// A viewer along a path that walks on past damaged pages.
struct Tolerant<'a> {
    path: &'a CameraPath,
    damaged: Vec<String>,
}

impl FrameSink for Tolerant<'_> {
    fn frame(
        &mut self,
        _: usize,
        _: &Camera,
        _: &ObjectBuffer,
        _: &mut Selection<'_>,
    ) -> flaneur::Result<()> {
        Ok(())
    }
}

impl Viewer for Tolerant<'_> {
    fn next_pose(&mut self, frame: usize) -> flaneur::Result<Option<Pose>> {
        Ok(self.path.poses.get(frame).copied())
    }
    fn figures(&mut self, f: &flaneur::walk::FrameFigures) {
        self.damaged.extend(f.damaged.iter().cloned());
    }
    fn skips_damaged(&self) -> bool {
        true
    }
}

/// Walks `path` over `db`'s HDoV-tree under `cfg`, drawing nothing, its frames kept.
fn visual_walk(
    db: &Database,
    path: &CameraPath,
    cfg: &VisualConfig,
) -> flaneur::Result<VisualReport> {
    visual_walk_by(db, cfg, &mut Playback::path(path))
}

/// [`visual_walk`], handing each frame to `sink`.
fn visual_walk_sink(
    db: &Database,
    path: &CameraPath,
    cfg: &VisualConfig,
    sink: &mut dyn FrameSink,
) -> flaneur::Result<VisualReport> {
    visual_walk_by(db, cfg, &mut Playback::path(path).drawn_by(sink))
}

/// Walks `db` under `cfg` along the poses `viewer` gives, its frames kept.
fn visual_walk_by(
    db: &Database,
    cfg: &VisualConfig,
    viewer: &mut dyn Viewer,
) -> flaneur::Result<VisualReport> {
    walk::run(db, &cfg.clone().into(), viewer, Frames::Keep)?.try_into()
}

fn unpaced(eta: f32) -> VisualConfig {
    VisualConfig {
        eta,
        pace: None,
        ..VisualConfig::default()
    }
}

#[test]
fn visual_draws_a_far_visible_object_that_reviews_box_loses() {
    let db = Database::open(&city().db).unwrap();
    let path = cell_walk(&db, 200, 1.0, 10.0, 5).unwrap();
    let mut seen = Recorder::default();
    let r = visual_walk_sink(&db, &path, &unpaced(0.0), &mut seen).unwrap();
    assert_eq!(
        r.summary.frames_outside, 0,
        "a cell walk stays in its cells"
    );
    // REVIEW with a box of 60 m: its frustum as deep, its disk cell SF times that.
    let box_m = 60.0;
    let cfg = ReviewConfig {
        far: box_m,
        ..ReviewConfig::preset(Preset::Np)
    };
    let mut boxed = Recorder::default();
    walk::run(
        &db,
        &cfg.clone().into(),
        &mut Playback::path(&path).drawn_by(&mut boxed),
        Frames::Keep,
    )
    .unwrap();
    assert_eq!(seen.frames.len(), boxed.frames.len());
    let bounds: std::collections::HashMap<u64, flaneur::geom::Aabb> =
        city().boxes.iter().copied().collect();
    let mut far_seen = 0;
    for ((eye, visual_ids), (_, review_ids)) in seen.frames.iter().zip(&boxed.frames) {
        let review_ids: HashSet<u64> = review_ids.iter().copied().collect();
        far_seen += visual_ids
            .iter()
            .filter(|id| {
                !review_ids.contains(id)
                    && flaneur::lod::distance_to(&bounds[id], *eye) > box_m * cfg.sf
            })
            .count();
    }
    assert!(
        far_seen > 0,
        "no object beyond REVIEW's box drawn by VISUAL along the walk"
    );
}

#[test]
fn cells_come_in_by_delta_and_each_frame_draws_its_cells_finds() {
    let db = Database::open(&city().db).unwrap();
    let path = cell_walk(&db, 300, 1.5, 10.0, 2).unwrap();
    let mut seen = Recorder::default();
    // The thesis's selection, whose finds `Database::hdov_search` gives.
    let cfg = VisualConfig {
        selection: flaneur::hdov::Selection::Thesis,
        ..unpaced(0.002)
    };
    let r = visual_walk_sink(&db, &path, &cfg, &mut seen).unwrap();
    let s = &r.summary;
    assert!(s.cells_entered >= 3, "{s:?}");
    assert_eq!(s.searches, s.cells_entered + 1);
    // Neighbouring cells see much the same: most finds are already held.
    assert!(s.reused > 0 && s.loaded > 0, "{s:?}");
    let later: usize = r.frames[1..].iter().map(|f| f.loaded).sum();
    assert!(
        later < s.reused,
        "{} loaded after the first cell, {} reused",
        later,
        s.reused
    );
    // What a frame draws is its cell's finds within the frustum, objects or groups.
    for (f, (eye, ids)) in r.frames.iter().zip(&seen.frames) {
        let cell = db.viewcell_at(*eye).unwrap().unwrap();
        assert_eq!(f.cell, Some(cell));
        let found: HashSet<u64> = db
            .hdov_search(cell, 0.002)
            .unwrap()
            .found
            .iter()
            .map(|x| match x {
                Found::Object { entry, .. } => entry.id,
                Found::Node { node, .. } => GROUP_ID | *node as u64,
            })
            .collect();
        assert!(ids.iter().all(|id| found.contains(id)));
        assert_eq!(f.drawn, ids.len());
        assert_eq!(f.objects_found + f.nodes_found, found.len());
    }
    assert!(s.peak_buffer_bytes > 0 && s.tree_pages > 0 && s.model_pages > 0);
}

#[test]
fn outside_every_viewcell_it_falls_back_to_reviews_query_and_counts_the_frames() {
    let db = Database::open(&city().db).unwrap();
    let b = db.bounds();
    let inside = cell_walk(&db, 10, 1.0, 10.0, 3).unwrap();
    // Ten frames in a cell, ten above the roofs, ten back in the cell.
    let mut poses = inside.poses.clone();
    let high = |i: usize, p: &Pose| Pose {
        time: 1.0 + i as f64 * 0.1,
        position: Vec3::new(p.position.x, b.max.y + 40.0, p.position.z),
        ..*p
    };
    let last = *poses.last().unwrap();
    poses.extend((0..10).map(|i| high(i, &last)));
    poses.extend(inside.poses.iter().enumerate().map(|(i, p)| Pose {
        time: 2.0 + i as f64 * 0.1,
        ..*p
    }));
    let path = CameraPath::new(poses).unwrap();
    let r = visual_walk(&db, &path, &unpaced(0.001)).unwrap();
    let s = &r.summary;
    assert_eq!(s.frames_outside, 10, "{s:?}");
    assert_eq!(s.fallback_queries, 1, "one box holds a standing viewer");
    assert!(r.frames[10..20]
        .iter()
        .all(|f| f.cell.is_none() && f.drawn > 0));
    // Back in the cell, it searches again.
    assert!(r.frames[20].searched && r.frames[20].cell.is_some());
}

#[test]
fn next_cell_prefetch_moves_the_reads_but_not_what_is_drawn() {
    let db = Database::open(&city().db).unwrap();
    let path = cell_walk(&db, 300, 1.5, 10.0, 2).unwrap();
    let walk = |k: Option<f32>| {
        let cfg = VisualConfig {
            prefetch_k: k,
            // Paced, so that the thread has a viewer's time: ten times real time.
            pace: Some(10.0),
            ..VisualConfig::default()
        };
        let mut seen = Recorder::default();
        let r = visual_walk_sink(&db, &path, &cfg, &mut seen).unwrap();
        (r, seen.frames)
    };
    let (plain, plain_drawn) = walk(None);
    let (ahead, ahead_drawn) = walk(Some(1.0));
    assert_eq!(plain.summary.prefetches, 0);
    assert!(ahead.summary.prefetches >= 1, "{:?}", ahead.summary);
    assert!(ahead.summary.searches < plain.summary.searches);
    for (a, b) in plain_drawn.iter().zip(&ahead_drawn) {
        let (a, b): (HashSet<u64>, HashSet<u64>) =
            (a.1.iter().copied().collect(), b.1.iter().copied().collect());
        assert_eq!(a, b);
    }
}

#[test]
fn a_damaged_internal_lod_is_named_or_left_out_and_counted() {
    let city = city();
    let copy = city.dir.path().join("damaged.flaneur");
    std::fs::copy(&city.db, &copy).unwrap();
    let db = Database::open(&copy).unwrap();
    let eta = 0.05;
    // A cell whose search stops at a node, and a walk that stands in it.
    let (cell, lods) = db
        .hdov()
        .unwrap()
        .unwrap()
        .cells
        .clone()
        .into_iter()
        .find_map(|c| {
            db.hdov_search(c, eta)
                .unwrap()
                .found
                .into_iter()
                .find_map(|f| match f {
                    Found::Node { lods, .. } => Some((c, lods)),
                    _ => None,
                })
        })
        .expect("a cell that finds a node at η = 0.05");
    let grid = &db.visibility().unwrap().unwrap().grid;
    let (row, column) = grid.place(cell);
    let eye = grid.cell_bounds(row, column).center();
    let poses = (0..5)
        .map(|i| Pose {
            time: i as f64 * 0.1,
            position: Vec3::new(eye.x, db.bounds().min.y + 1.7, eye.z),
            yaw: i as f32,
            pitch: 0.0,
        })
        .collect();
    let path = CameraPath::new(poses).unwrap();
    assert_eq!(db.viewcell_at(path.poses[0].position).unwrap(), Some(cell));
    let page_size = db.store().page_size() as u64;
    drop(db);
    let mut bytes = std::fs::read(&copy).unwrap();
    bytes[(lods.first_page * page_size + 40) as usize] ^= 0x5a;
    std::fs::write(&copy, &bytes).unwrap();
    let db = Database::open(&copy).unwrap();
    match visual_walk(&db, &path, &unpaced(eta)) {
        Err(Error::CorruptPage { page, .. }) => assert_eq!(page, lods.first_page),
        other => panic!("expected the damaged page named, got {other:?}"),
    }
    let mut viewer = Tolerant {
        path: &path,
        damaged: Vec::new(),
    };
    let r = visual_walk_by(&db, &unpaced(eta), &mut viewer).unwrap();
    assert_eq!(r.frames.len(), 5);
    assert!(r.summary.left_out >= 1, "{:?}", r.summary);
    assert!(
        viewer.damaged.iter().any(|d| d.contains("HDoV node")),
        "{:?}",
        viewer.damaged
    );
}

#[test]
fn a_database_without_the_tree_says_so() {
    let c = common::city(40, 1, &common::with_visibility());
    let db = Database::open(&c.db).unwrap();
    let path = cell_walk(&db, 5, 1.0, 10.0, 1).unwrap();
    let e = visual_walk(&db, &path, &VisualConfig::default()).unwrap_err();
    assert!(e.to_string().contains("--hdov"), "{e}");
    let bad = VisualConfig {
        eta: f32::NAN,
        ..VisualConfig::default()
    };
    let e = visual_walk(&db, &path, &bad).unwrap_err();
    assert!(e.to_string().contains("η"), "{e}");
}

#[test]
fn visual_vs_review_misses_nothing_visible_where_reviews_small_box_does() {
    use flaneur_bench::visual_vs_review::{self, VisualVsReviewConfig};
    let db = Database::open(&city().db).unwrap();
    let cfg = VisualVsReviewConfig {
        frames: 150,
        etas: vec![0.0, 0.001],
        boxes: vec![60.0],
        sessions: vec!["normal".into(), "back-forth".into()],
        pace: 50.0,
        ..Default::default()
    };
    let mut ticks = 0;
    let r = visual_vs_review::run(&db, &cfg, |_, _| ticks += 1).unwrap();
    // Per session: each η, VISUAL with the prefetch, and each box.
    assert_eq!(r.rows.len(), 2 * 4);
    assert_eq!(ticks, r.rows.len());
    let v0 = r.row("normal", "visual", 0.0).unwrap();
    assert_eq!(
        v0.mean_missed, 0.0,
        "η = 0 draws every visible object in view"
    );
    let review = r.row("normal", "review", 60.0).unwrap();
    assert!(review.mean_missed > 0.0, "{review:?}");
    assert!(r.rows.iter().all(|x| x.pages > 0 && x.queries >= 1));
    // The frame series of the normal session, one per walk, for Figs. 5.24–5.25.
    assert_eq!(r.series.len(), 4);
    assert!(r.series.iter().all(|(_, ms)| ms.len() == cfg.frames));

    // The command writes its report.
    let out = city().dir.path().join("vvr");
    let o = common::flaneur(&[
        "bench",
        "visual-vs-review",
        city().db.to_str().unwrap(),
        "--frames",
        "60",
        "--etas",
        "0.001",
        "--boxes",
        "60",
        "--sessions",
        "normal",
        "--pace",
        "50",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "visual-vs-review.csv",
        "visual-vs-review.md",
        "visual-vs-review-frames.csv",
        "visual-vs-review-frames.png",
        "visual-vs-review-eta.png",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
}

/// Each frame's objects' DoVs as handed to LOD selection.
#[derive(Default)]
struct Dovs(Vec<(u64, Option<f32>)>);

impl FrameSink for Dovs {
    fn frame(
        &mut self,
        _: usize,
        _: &Camera,
        _: &ObjectBuffer,
        s: &mut Selection<'_>,
    ) -> flaneur::Result<()> {
        self.0.extend(s.culled.iter().map(|o| (o.entry.id, o.dov)));
        Ok(())
    }
}

#[test]
fn with_dov_tau_objects_hand_their_dov_to_lod_selection_and_groups_none() {
    let db = Database::open(&city().db).unwrap();
    let path = cell_walk(&db, 60, 1.5, 10.0, 2).unwrap();
    let walk = |dov_tau: bool| {
        let cfg = VisualConfig {
            dov_tau,
            ..unpaced(0.002)
        };
        let mut seen = Dovs::default();
        visual_walk_sink(&db, &path, &cfg, &mut seen).unwrap();
        seen.0
    };
    let with = walk(true);
    assert!(!with.is_empty());
    for (id, dov) in &with {
        if id & GROUP_ID != 0 {
            assert_eq!(*dov, None);
        } else {
            assert!(dov.is_some_and(|d| d > 0.0), "object {id}: {dov:?}");
        }
    }
    assert!(walk(false).iter().all(|(_, d)| d.is_none()));
}

/// What LOD selection drew of each object against the level VISUAL loaded it at.
struct Levels {
    finer: usize,
    coarser_or_same: usize,
}

impl FrameSink for Levels {
    fn frame(
        &mut self,
        _: usize,
        _: &Camera,
        _: &ObjectBuffer,
        s: &mut Selection<'_>,
    ) -> flaneur::Result<()> {
        for (d, o) in s.drawn.iter().zip(s.culled) {
            if d.level == flaneur::walk::lod_select::REFINED {
                continue;
            }
            if d.level < o.level {
                self.finer += 1;
            } else {
                self.coarser_or_same += 1;
            }
        }
        Ok(())
    }

    fn lod_tau(&self) -> Option<f32> {
        Some(0.001)
    }
}

#[test]
fn finer_by_tau_lets_lod_selection_draw_near_objects_finer_than_eq_5_6() {
    let db = Database::open(&city().db).unwrap();
    let path = cell_walk(&db, 80, 1.5, 10.0, 2).unwrap();
    let walk = |finer_by_tau: bool| {
        let cfg = VisualConfig {
            finer_by_tau,
            selection: flaneur::hdov::Selection::Thesis,
            ..unpaced(0.0)
        };
        let mut seen = Levels {
            finer: 0,
            coarser_or_same: 0,
        };
        visual_walk_sink(&db, &path, &cfg, &mut seen).unwrap();
        (seen.finer, seen.coarser_or_same)
    };
    let (finer, _) = walk(false);
    assert_eq!(finer, 0, "never finer than loaded without the option");
    let (finer, rest) = walk(true);
    assert!(
        finer > 0,
        "no object drawn finer than eq. 5.6's level ({rest} others)"
    );
}
