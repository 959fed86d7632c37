//! The REVIEW and BOX walks' entry points: a path or a viewer in, a report out, the
//! frames kept, handed to a sink, or handed on and forgotten.

use super::config::ReviewConfig;
use super::report::FrameStats;
use super::report::WalkReport;
use crate::database::Database;
use crate::error::{Error, Result};
use crate::path::{CameraPath, Pose};
use crate::walk::sink::{FrameSink, NoSink, Played, Viewer};
use crate::walk::walk_lods::WalkLods;

/// Walks `path` through `db` under `cfg`; `progress` is told each finished frame.
pub fn walk(
    db: &Database,
    path: &CameraPath,
    cfg: &ReviewConfig,
    progress: impl FnMut(usize),
) -> Result<WalkReport> {
    walk_into(db, path, cfg, progress, &mut NoSink)
}

/// [`walk`], handing each frame's selection to `sink` (a renderer) once the frame's
/// statistics are taken, so that drawing is not counted in them.
pub fn walk_into(
    db: &Database,
    path: &CameraPath,
    cfg: &ReviewConfig,
    progress: impl FnMut(usize),
    sink: &mut dyn FrameSink,
) -> Result<WalkReport> {
    if path.poses.is_empty() {
        return Err(Error::Invalid("the camera path has no poses".into()));
    }
    walk_live(db, cfg, progress, &mut Played::path(path, sink))
}

/// [`walk_into`] in constant memory, for a walk of any length: the poses come from
/// `poses` as the walk needs them (each checked as a [`CameraPath`]'s are), and each
/// frame's figures go to `each` as the frame ends, and are not kept. The report's
/// `frames` is empty; its summary is whole, and the same as [`walk_into`]'s.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # citygen::write_city(&citygen::CityConfig { objects: 60, ..Default::default() }, &scene)?;
/// # flaneur::build_from_scene(&scene, &path, &flaneur::BuildOptions::default())?;
/// use flaneur::{path::motion, walk::{review, NoSink}};
/// let db = flaneur::Database::open(&path)?;
/// let poses = motion::poses(&db.bounds(), motion::Motion::Normal, 300, 30.0, 1)?;
/// let mut rows = 0;
/// let cfg = review::ReviewConfig::preset(review::Preset::Box);
/// let report = review::walk_streamed(&db, poses, &cfg, |_| {}, &mut NoSink, &mut |_| {
///     rows += 1;
///     Ok(())
/// })?;
/// assert!(report.frames.is_empty());
/// assert_eq!((report.summary.frames, rows), (300, 300));
/// # Ok(()) }
/// ```
pub fn walk_streamed(
    db: &Database,
    poses: impl Iterator<Item = Pose>,
    cfg: &ReviewConfig,
    progress: impl FnMut(usize),
    sink: &mut dyn FrameSink,
    each: &mut dyn FnMut(&FrameStats) -> Result<()>,
) -> Result<WalkReport> {
    super::run::walk_each(
        db,
        cfg,
        &mut WalkLods::new(db),
        progress,
        &mut Played::streamed(poses, sink),
        each,
    )
}

/// [`walk_into`] with the poses coming from `viewer` frame by frame (a person at a
/// window), until it has no more. Poses must come in time order, as a path's do.
pub fn walk_live(
    db: &Database,
    cfg: &ReviewConfig,
    progress: impl FnMut(usize),
    viewer: &mut dyn Viewer,
) -> Result<WalkReport> {
    walk_live_with(db, cfg, &mut WalkLods::new(db), progress, viewer)
}

/// [`walk_live`] with LOD selection `lods` kept from an earlier walk (one before it at
/// the same window), so that what it read and refined stays so.
pub(crate) fn walk_live_with<'db>(
    db: &'db Database,
    cfg: &ReviewConfig,
    lods: &mut WalkLods<'db>,
    progress: impl FnMut(usize),
    viewer: &mut dyn Viewer,
) -> Result<WalkReport> {
    let mut frames = Vec::new();
    let mut report = super::run::walk_each(db, cfg, lods, progress, viewer, &mut |f| {
        frames.push(f.clone());
        Ok(())
    })?;
    report.frames = frames;
    Ok(report)
}
