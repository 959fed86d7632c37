//! The VISUAL walk's entry points: a path or a viewer in, a report out, the frames
//! kept, handed to a sink, or handed on and forgotten.

use super::config::VisualConfig;
use super::report::VisualFrame;
use super::report::VisualReport;
use super::tally::VisualTally;
use crate::database::Database;
use crate::error::{Error, Result};
use crate::path::{CameraPath, Pose};
use crate::walk::sink::{FrameSink, NoSink, Played, Viewer};
use crate::walk::walk_lods::WalkLods;

/// Walks `path` over `db`'s HDoV-tree under `cfg`; `progress` is told each finished
/// frame. An error for a database without an HDoV-tree.
pub fn walk(
    db: &Database,
    path: &CameraPath,
    cfg: &VisualConfig,
    progress: impl FnMut(usize),
) -> Result<VisualReport> {
    walk_into(db, path, cfg, progress, &mut NoSink)
}

/// [`walk`], handing each frame to `sink` (a renderer) once its figures are taken.
pub fn walk_into(
    db: &Database,
    path: &CameraPath,
    cfg: &VisualConfig,
    progress: impl FnMut(usize),
    sink: &mut dyn FrameSink,
) -> Result<VisualReport> {
    if path.poses.is_empty() {
        return Err(Error::Invalid("the camera path has no poses".into()));
    }
    walk_live(db, cfg, progress, &mut Played::path(path, sink))
}

/// [`walk_into`] with the poses coming from `viewer` frame by frame, until it has no
/// more. Poses must come in time order.
pub fn walk_live(
    db: &Database,
    cfg: &VisualConfig,
    progress: impl FnMut(usize),
    viewer: &mut dyn Viewer,
) -> Result<VisualReport> {
    walk_live_with(db, cfg, &mut WalkLods::new(db), progress, viewer)
}

/// [`walk_into`] in constant memory, for a walk of any length: the poses come from
/// `poses` as the walk needs them (each checked as a [`CameraPath`]'s are), and each
/// frame's figures go to `each` as the frame ends, and are not kept. The report's
/// `frames` is empty; its summary is whole, and the same as [`walk_into`]'s. A walk that
/// never waits ([`VisualConfig::never_wait`]) is the exception: a frame's misses are
/// known only once its cell's finds have come, so it keeps its frames, and hands them
/// to `each` as it ends.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # citygen::write_city(&citygen::CityConfig { objects: 40, ..Default::default() }, &scene)?;
/// # let mut opts = flaneur::BuildOptions::default();
/// # opts.visibility = Some(flaneur::visibility::VisibilityOptions { cell_size: 40.0, ..Default::default() });
/// # opts.hdov = Some(flaneur::hdov::HdovOptions::default());
/// # flaneur::build_from_scene(&scene, &path, &opts)?;
/// use flaneur::{path::cell_poses, walk::{visual, NoSink}};
/// let db = flaneur::Database::open(&path)?;
/// let poses = cell_poses(&db, 100, 0.5, 30.0, 1)?;
/// let mut rows = 0;
/// let cfg = visual::VisualConfig::default();
/// let report = visual::walk_streamed(&db, poses, &cfg, |_| {}, &mut NoSink, &mut |_| {
///     rows += 1;
///     Ok(())
/// })?;
/// assert!(report.frames.is_empty());
/// assert_eq!((report.summary.frames, rows), (100, 100));
/// # Ok(()) }
/// ```
pub fn walk_streamed(
    db: &Database,
    poses: impl Iterator<Item = Pose>,
    cfg: &VisualConfig,
    progress: impl FnMut(usize),
    sink: &mut dyn FrameSink,
    each: &mut dyn FnMut(&VisualFrame) -> Result<()>,
) -> Result<VisualReport> {
    walk_each(
        db,
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
    cfg: &VisualConfig,
    lods: &mut WalkLods<'db>,
    progress: impl FnMut(usize),
    viewer: &mut dyn Viewer,
) -> Result<VisualReport> {
    let mut frames = Vec::new();
    let mut report = walk_each(db, cfg, lods, progress, viewer, &mut |f| {
        frames.push(f.clone());
        Ok(())
    })?;
    report.frames = frames;
    Ok(report)
}

/// The walk, each frame handed to `each` and tallied, none kept.
fn walk_each<'db>(
    db: &'db Database,
    cfg: &VisualConfig,
    lods: &mut WalkLods<'db>,
    progress: impl FnMut(usize),
    viewer: &mut dyn Viewer,
    each: &mut dyn FnMut(&VisualFrame) -> Result<()>,
) -> Result<VisualReport> {
    let mut tally = VisualTally::default();
    let (node_cache, run) = super::run::walk_live(db, cfg, lods, progress, viewer, |f| {
        tally.add(&f);
        each(&f)
    })?;
    let mut summary = tally.summary(node_cache);
    summary.failed_loads = run.failures.count;
    summary.last_load_error = run.failures.last;
    Ok(VisualReport {
        config: cfg.clone(),
        frames: Vec::new(),
        summary,
    })
}
