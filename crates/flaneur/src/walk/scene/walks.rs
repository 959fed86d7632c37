//! The scene-tree walks' entry points: a path or a viewer in, a report out, the frames
//! kept, handed to a sink, or handed on and forgotten.

use super::config::SceneConfig;
use super::report::SceneFrame;
use super::report::SceneReport;
use super::tally::SceneTally;
use crate::database::Database;
use crate::error::{Error, Result};
use crate::path::{CameraPath, Pose};
use crate::walk::scene::SceneTree;
use crate::walk::sink::{FrameSink, NoSink, Played, Viewer};
use crate::walk::walk_lods::WalkLods;

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
    crate::walk::settings::check_far(cfg.far)?;
    crate::walk::settings::check_screen_tau(cfg.tau)?;
    let mut tally = SceneTally::default();
    super::mode::walk_live(db, tree, cfg, lods, progress, viewer, |f| {
        tally.add(&f, cfg.traversal);
        each(&f)
    })?;
    Ok(SceneReport {
        config: *cfg,
        frames: Vec::new(),
        summary: tally.summary(),
    })
}
