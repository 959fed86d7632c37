//! The walk engine's live session (`walk::live`), driven by a scripted viewer instead
//! of a window: the changes a person's keys ask for restart the walk with them, a mode
//! the database cannot show falls back and says so, and failing walks restart until
//! the fifth in a row ends the session.

mod common;

use flaneur::geom::Camera;
use flaneur::path::{street_walk, CameraPath, Pose};
use flaneur::walk::live::{self, Change, LiveViewer};
use flaneur::walk::WalkMode;
use flaneur::walk::{FrameSink, ObjectBuffer, Selection, Viewer};
use flaneur::{BuildOptions, Database, Error, Result};

/// Plays `path` over and over, one walk per entry of `script`: walk `i` lasts
/// `script[i].0` poses, then asks for `script[i].1`; the viewer closes after the last.
/// With `fail_from`, every frame from that walk on fails.
struct Scripted {
    path: CameraPath,
    script: Vec<(usize, Option<Change>)>,
    fail_from: Option<usize>,
    walk: usize,
    played: usize,
    modes: Vec<WalkMode>,
    reports: Vec<String>,
    /// Frames drawn in each walk, and the pages each walk's figures counted.
    frames: Vec<usize>,
    pages: Vec<u64>,
}

impl Scripted {
    fn new(path: CameraPath, script: Vec<(usize, Option<Change>)>) -> Scripted {
        Scripted {
            path,
            script,
            fail_from: None,
            walk: 0,
            played: 0,
            modes: Vec::new(),
            reports: Vec::new(),
            frames: vec![0],
            pages: vec![0],
        }
    }
}

impl FrameSink for Scripted {
    fn frame(
        &mut self,
        _: usize,
        _: &Camera,
        _: &ObjectBuffer,
        s: &mut Selection<'_>,
    ) -> Result<()> {
        if self.fail_from.is_some_and(|f| self.walk >= f) {
            return Err(Error::Invalid("a scripted failure".into()));
        }
        assert_eq!(s.drawn.len(), s.culled.len());
        self.frames[self.walk] += 1;
        Ok(())
    }

    fn lod_tau(&self) -> Option<f32> {
        Some(0.003)
    }
}

impl Viewer for Scripted {
    fn next_pose(&mut self, frame: usize) -> Result<Option<Pose>> {
        let Some(&(poses, _)) = self.script.get(self.walk) else {
            return Ok(None);
        };
        if frame >= poses {
            return Ok(None);
        }
        let pose = self.path.poses[self.played % self.path.poses.len()];
        self.played += 1;
        Ok(Some(Pose {
            time: self.played as f64 / 30.0,
            ..pose
        }))
    }

    fn figures(&mut self, figures: &flaneur::walk::FrameFigures) {
        self.pages[self.walk] += figures.pages + figures.lod_pages;
    }
}

impl LiveViewer for Scripted {
    fn closed(&self) -> bool {
        self.walk + 1 >= self.script.len()
    }

    fn change(&self) -> Option<Change> {
        self.script[self.walk].1
    }

    fn show_mode(&mut self, mode: WalkMode) {
        self.modes.push(mode);
    }

    fn report(&mut self, what: String) {
        self.reports.push(what);
    }

    fn resume(&mut self) {
        self.walk += 1;
        self.frames.push(0);
        self.pages.push(0);
    }
}

fn city() -> (common::City, Database, CameraPath) {
    let city = common::city(120, 5, &BuildOptions::default());
    let db = Database::open(&city.db).unwrap();
    let path = street_walk(&db.bounds(), 200, 1.5, 40, 3).unwrap();
    (city, db, path)
}

#[test]
fn a_change_restarts_the_walk_with_it_and_a_mode_the_database_lacks_falls_back() {
    let (_city, db, path) = city();
    let mut viewer = Scripted::new(
        path,
        vec![
            (20, Some(Change::Mode(WalkMode::Box))),
            (20, Some(Change::Budget(0.5))),
            (20, Some(Change::Mode(WalkMode::Pvs))),
            (20, None),
        ],
    );
    live::run(&db, WalkMode::Review, &mut viewer).unwrap();
    // Review, then Box; Pvs asked of a database without visibility shows Review.
    assert_eq!(
        viewer.modes,
        [
            WalkMode::Review,
            WalkMode::Box,
            WalkMode::Pvs,
            WalkMode::Review
        ]
    );
    // The budget the walk started with, kept across the change of mode, then halved
    // and said in MiB.
    let budget =
        flaneur::walk::review::ReviewConfig::preset(flaneur::walk::review::Preset::Optimal)
            .memory_budget;
    assert_eq!(viewer.reports.len(), 2, "{:?}", viewer.reports);
    assert_eq!(
        viewer.reports[0],
        format!(
            "object buffer budget {:.0} MiB",
            budget as f64 / 2.0 / 1048576.0
        )
    );
    assert!(
        viewer.reports[1].contains("has no visibility data"),
        "{:?}",
        viewer.reports
    );
    // Every walk drew its poses, and read pages: the first one from a cold start.
    assert_eq!(viewer.frames, [20, 20, 20, 20]);
    assert!(viewer.pages[0] > 0, "{:?}", viewer.pages);
}

#[test]
fn failing_walks_restart_until_the_fifth_in_a_row_ends_the_session() {
    let (_city, db, path) = city();
    let mut viewer = Scripted::new(path, vec![(10, None); 8]);
    viewer.fail_from = Some(1);
    let e = live::run(&db, WalkMode::Review, &mut viewer).unwrap_err();
    assert!(e.to_string().contains("failed five times running"), "{e}");
    // One good walk, then five failed ones, each told of.
    assert_eq!(viewer.walk, 5, "{:?}", viewer.reports);
    assert_eq!(viewer.frames[0], 10);
    let told: Vec<_> = viewer
        .reports
        .iter()
        .filter(|r| r.starts_with("the walk stopped: ") && r.contains("a scripted failure"))
        .collect();
    assert_eq!(told.len(), 5, "{:?}", viewer.reports);
}

#[test]
fn visual_and_the_scene_tree_walk_live_and_visual_falls_back_to_pvs_without_the_tree() {
    let with_tree = common::city(
        120,
        5,
        &BuildOptions {
            hdov: Some(flaneur::hdov::HdovOptions::default()),
            ..common::with_visibility()
        },
    );
    let db = Database::open(&with_tree.db).unwrap();
    let path = flaneur::path::cell_walk(&db, 60, 1.0, 10.0, 2).unwrap();
    let mut viewer = Scripted::new(
        path.clone(),
        vec![
            (30, Some(Change::Mode(WalkMode::Pvs))),
            (30, Some(Change::Mode(WalkMode::Vsc))),
            (30, Some(Change::Mode(WalkMode::Pb))),
            (30, Some(Change::Mode(WalkMode::Conv))),
            (30, None),
        ],
    );
    live::run(&db, WalkMode::Visual, &mut viewer).unwrap();
    let modes = [
        WalkMode::Visual,
        WalkMode::Pvs,
        WalkMode::Vsc,
        WalkMode::Pb,
        WalkMode::Conv,
    ];
    assert_eq!(viewer.modes, modes);
    // The scene tree is loaded once, when VSC is first shown, and said so.
    assert_eq!(viewer.reports.len(), 1, "{:?}", viewer.reports);
    assert!(viewer.reports[0].contains("loading the scene tree"));
    assert_eq!(viewer.frames, [30; 5]);
    assert!(viewer.pages[0] > 0, "{:?}", viewer.pages);

    // Without the tree: PVS, said so.
    let without = common::city(60, 5, &common::with_visibility());
    let db = Database::open(&without.db).unwrap();
    let path = flaneur::path::cell_walk(&db, 20, 1.0, 10.0, 2).unwrap();
    let mut viewer = Scripted::new(path, vec![(10, None)]);
    live::run(&db, WalkMode::Visual, &mut viewer).unwrap();
    assert_eq!(viewer.modes, [WalkMode::Visual, WalkMode::Pvs]);
    assert!(
        viewer.reports[0].contains("no HDoV-tree"),
        "{:?}",
        viewer.reports
    );
}
