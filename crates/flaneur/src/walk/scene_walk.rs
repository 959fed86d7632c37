//! Walks over the memory HDoV scene tree (Shou 2002 ch. 6, `flaneur walk DB --mode
//! vsc|pb|conv`): the whole city loaded into a [`SceneTree`] once, then each frame the
//! eye's viewcell found (its VDs brought in through the tree's hash table on a change
//! of cell) and the tree traversed by VSC(η), PB(n) or CONV, view frustum culling in
//! all three; what the traversal chose is what the frame draws.
//!
//! A viewpoint outside every viewcell keeps the VDs of the last cell it was in (the
//! thesis's run-time phase is for viewpoints within the cells); one before any cell
//! is drawn by CONV. Both are counted ([`SceneSummary::frames_outside`],
//! [`SceneSummary::frames_conv`]). Frame time is the walk's own: the VD update, the
//! traversal, bringing the object buffer to what it chose, and culling.
//!
//! ```
//! # fn main() -> flaneur::Result<()> {
//! # let dir = tempfile::tempdir().unwrap();
//! # let (scene, file) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
//! # citygen::write_city(&citygen::CityConfig { objects: 40, ..Default::default() }, &scene)?;
//! # let opts = flaneur::BuildOptions {
//! #     visibility: Some(flaneur::visibility::VisibilityOptions {
//! #         resolution: 8, ..Default::default() }),
//! #     ..Default::default()
//! # };
//! # flaneur::build_from_scene(&scene, &file, &opts)?;
//! use flaneur::walk::scene::{SceneTree, Traversal};
//! use flaneur::{path, walk::scene_walk};
//! let db = flaneur::Database::open(&file)?;
//! let mut tree = SceneTree::load(&db, &flaneur::progress::Silent)?;
//! let poses = path::cell_walk(&db, 30, 0.5, 10.0, 3)?;
//! let cfg = scene_walk::SceneConfig::new(Traversal::Vsc { eta: 0.001 });
//! let report = scene_walk::walk(&db, &mut tree, &poses, &cfg, |_| {})?;
//! assert_eq!(report.frames.len(), 30);
//! # Ok(()) }
//! ```

use serde::Serialize;

use super::scene_tally::SceneTally;
use super::sink::{FrameSink, NoSink, Played, Viewer};
use super::walk_lods::WalkLods;
use crate::database::Database;
use crate::error::{Error, Result};
use crate::hdov::Selection;
use crate::path::{CameraPath, Pose};
use crate::walk::scene::{SceneTree, Traversal};

/// What a scene-tree walk can vary.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct SceneConfig {
    /// The traversal: CONV, VSC(η) or PB(n).
    pub traversal: Traversal,
    /// Depth of the view frustum, metres.
    pub far: f32,
    /// Which rule picks VSC's and PB's representations: ours ([`Selection::Screen`], the
    /// default) holds each to its stored error projecting under [`SceneConfig::tau`]
    /// from the eye (`walk::scene::traverse_screened`); the thesis's
    /// ([`Selection::Thesis`]) for the Table 6.1 reproduction.
    pub selection: Selection,
    /// The screen rule's threshold, a fraction of the viewport within [0, 1): the
    /// viewer's LOD τ (0, full detail, lets no internal LOD pass).
    pub tau: f32,
}

impl SceneConfig {
    /// `traversal` with REVIEW's frustum depth, under our screen rule at the thesis's τ
    /// of 0.1 %.
    pub fn new(traversal: Traversal) -> SceneConfig {
        SceneConfig {
            traversal,
            far: super::settings::DEFAULT_FAR,
            selection: Selection::Screen,
            tau: super::lod_select::DEFAULT_TAU,
        }
    }
}

/// One frame of a scene-tree walk. Times in milliseconds.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SceneFrame {
    /// The frame's index, from 0.
    pub frame: usize,
    /// Its pose's time on the path, seconds.
    pub time: f64,
    /// The viewcell the eye is in; `None` outside every one.
    pub cell: Option<u32>,
    /// Drawn by CONV, no cell having been entered yet.
    pub conv: bool,
    /// Bringing the VDs to a new cell.
    pub update_ms: f64,
    /// The traversal.
    pub traverse_ms: f64,
    /// The walk's whole time for the frame.
    pub frame_ms: f64,
    /// Nodes the traversal visited.
    pub visited: usize,
    /// Nodes drawn (objects and internal nodes).
    pub drawn: usize,
    /// Of those, internal nodes at an internal LOD.
    pub internal: usize,
    /// Triangles drawn.
    pub triangles: u64,
    /// PB: nodes dropped for want of budget.
    pub dropped: usize,
    /// PB: the traversal ran out of attempts and ended, drawing what was active.
    pub ended: bool,
    /// PB: an object whose coarsest representation alone is over the budget (id,
    /// triangles), when the frame met one.
    pub too_big: Option<(u64, u32)>,
    /// Pages read (a new cell's PVS; the tree is in memory).
    pub pages: u64,
}

impl SceneFrame {
    /// The columns of [`SceneFrame::csv_row`].
    pub const CSV_HEADER: &'static str = "frame,time,cell,conv,update_ms,traverse_ms,frame_ms,visited,drawn,internal,triangles,dropped,ended,pages";

    /// The frame as one CSV row (no line end), its columns [`SceneFrame::CSV_HEADER`].
    pub fn csv_row(&self) -> String {
        let f = self;
        format!(
            "{},{:.4},{},{},{:.3},{:.3},{:.3},{},{},{},{},{},{},{}",
            f.frame,
            f.time,
            f.cell.map_or(String::new(), |c| c.to_string()),
            f.conv as u8,
            f.update_ms,
            f.traverse_ms,
            f.frame_ms,
            f.visited,
            f.drawn,
            f.internal,
            f.triangles,
            f.dropped,
            f.ended as u8,
            f.pages
        )
    }
}

/// A scene-tree walk in all; frame 0 left out of the frame-time figures.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SceneSummary {
    /// Frames walked, frame 0 included.
    pub frames: usize,
    /// Mean frame time from frame 1 on, ms.
    pub mean_frame_ms: f64,
    /// Frame time's variance from frame 1 on, ms².
    pub frame_ms_variance: f64,
    /// Longest frame from frame 1 on, ms.
    pub max_frame_ms: f64,
    /// Mean traversal time, ms.
    pub mean_traverse_ms: f64,
    /// Triangles drawn per frame, on average.
    pub mean_triangles: f64,
    /// Nodes visited per frame, on average (Table 6.1's "Nodes").
    pub mean_visited: f64,
    /// Nodes drawn per frame, on average.
    pub mean_drawn: f64,
    /// The most triangles a frame drew.
    pub max_triangles: u64,
    /// Moves into another viewcell.
    pub cells_entered: usize,
    /// Frames outside every viewcell (the last cell's VDs kept).
    pub frames_outside: usize,
    /// Frames drawn by CONV before any cell was entered.
    pub frames_conv: usize,
    /// PB: frames that drew more triangles than the budget.
    pub frames_over_budget: usize,
    /// PB: frames that met an object whose coarsest representation alone is over the
    /// budget.
    pub frames_too_big: usize,
    /// PB: frames whose traversal ran out of attempts and ended early.
    pub frames_ended: usize,
    /// PB: the first frame that met an object whose coarsest representation alone is
    /// over the budget, with the object (id, triangles).
    pub first_too_big: Option<(usize, u64, u32)>,
}

/// What a scene-tree walk did.
#[derive(Clone, Debug, Serialize)]
pub struct SceneReport {
    /// The settings walked.
    pub config: SceneConfig,
    /// Every frame's figures, in order (empty for a walk that handed them on,
    /// [`walk_streamed`]).
    pub frames: Vec<SceneFrame>,
    /// The walk in all.
    pub summary: SceneSummary,
}

impl SceneReport {
    /// PB's budget held on this share of the frames (1 for other traversals).
    pub fn within_budget(&self) -> f64 {
        1.0 - self.summary.frames_over_budget as f64 / self.summary.frames.max(1) as f64
    }

    /// What PB's budget could not hold, in words: the first object whose coarsest
    /// representation alone is over it. `None` when none was met.
    pub fn too_big(&self) -> Option<String> {
        let Traversal::Pb { budget } = self.config.traversal else {
            return None;
        };
        let (frame, id, t) = self.summary.first_too_big?;
        Some(format!(
            "object {id}'s coarsest representation alone has {t} triangles, over the budget of {budget} (first on frame {frame}, {} frames in all)",
            self.summary.frames_too_big
        ))
    }
}

/// Walks `path` over `tree` (loaded from `db`) under `cfg`; `progress` is told each
/// frame.
pub fn walk(
    db: &Database,
    tree: &mut SceneTree,
    path: &CameraPath,
    cfg: &SceneConfig,
    progress: impl FnMut(usize),
) -> Result<SceneReport> {
    walk_into(db, tree, path, cfg, progress, &mut NoSink)
}

/// [`walk`], handing each frame to `sink`.
pub fn walk_into(
    db: &Database,
    tree: &mut SceneTree,
    path: &CameraPath,
    cfg: &SceneConfig,
    progress: impl FnMut(usize),
    sink: &mut dyn FrameSink,
) -> Result<SceneReport> {
    if path.poses.is_empty() {
        return Err(Error::Invalid("the camera path has no poses".into()));
    }
    walk_live(db, tree, cfg, progress, &mut Played::path(path, sink))
}

/// [`walk_into`] with the poses coming from `viewer`.
pub fn walk_live(
    db: &Database,
    tree: &mut SceneTree,
    cfg: &SceneConfig,
    progress: impl FnMut(usize),
    viewer: &mut dyn Viewer,
) -> Result<SceneReport> {
    walk_live_with(db, tree, cfg, &mut WalkLods::new(db), progress, viewer)
}

/// [`walk_into`] in constant memory, for a walk of any length: the poses come from
/// `poses` as the walk needs them (each checked as a [`CameraPath`]'s are), and each
/// frame's figures go to `each` as the frame ends, and are not kept. The report's
/// `frames` is empty; its summary is whole, and the same as [`walk_into`]'s.
pub fn walk_streamed(
    db: &Database,
    tree: &mut SceneTree,
    poses: impl Iterator<Item = Pose>,
    cfg: &SceneConfig,
    progress: impl FnMut(usize),
    sink: &mut dyn FrameSink,
    each: &mut dyn FnMut(&SceneFrame) -> Result<()>,
) -> Result<SceneReport> {
    walk_each(
        db,
        tree,
        cfg,
        &mut WalkLods::new(db),
        progress,
        &mut Played::streamed(poses, sink),
        each,
    )
}

/// [`walk_live`] with LOD selection `lods` kept from an earlier walk.
pub(crate) fn walk_live_with<'db>(
    db: &'db Database,
    tree: &mut SceneTree,
    cfg: &SceneConfig,
    lods: &mut WalkLods<'db>,
    progress: impl FnMut(usize),
    viewer: &mut dyn Viewer,
) -> Result<SceneReport> {
    let mut frames = Vec::new();
    let mut report = walk_each(db, tree, cfg, lods, progress, viewer, &mut |f| {
        frames.push(f.clone());
        Ok(())
    })?;
    report.frames = frames;
    Ok(report)
}

/// The walk, each frame handed to `each` and tallied, none kept.
fn walk_each<'db>(
    db: &'db Database,
    tree: &mut SceneTree,
    cfg: &SceneConfig,
    lods: &mut WalkLods<'db>,
    progress: impl FnMut(usize),
    viewer: &mut dyn Viewer,
    each: &mut dyn FnMut(&SceneFrame) -> Result<()>,
) -> Result<SceneReport> {
    cfg.traversal.validate()?;
    super::settings::check_far(cfg.far)?;
    super::visual::check_screen_tau(cfg.tau)?;
    let mut tally = SceneTally::default();
    super::mode::scene::walk_live(db, tree, cfg, lods, progress, viewer, |f| {
        tally.add(&f, cfg.traversal);
        each(&f)
    })?;
    Ok(SceneReport {
        config: *cfg,
        frames: Vec::new(),
        summary: tally.summary(),
    })
}
