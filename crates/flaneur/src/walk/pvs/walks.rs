//! The PVS walk's entry points: a path or a viewer in, a report out, the frames kept,
//! handed to a sink, or handed on and forgotten.

use super::config::PvsWalkConfig;
use super::report::PvsFrame;
use super::report::PvsWalkReport;
use super::tally::PvsTally;
use crate::database::Database;
use crate::error::Result;
use crate::path::{CameraPath, Pose};
use crate::walk::sink::Played;
use crate::walk::walk_lods::WalkLods;
use crate::walk::{FrameSink, NoSink, Viewer};

/// Walks `path` over `db`'s precomputed visibility as `cfg` says (a [`PvsPrefetch`](super::PvsPrefetch)
/// alone: waiting, as the thesis), calling `tick` after each frame.
pub fn walk_pvs(
    db: &Database,
    path: &CameraPath,
    cfg: impl Into<PvsWalkConfig>,
    tick: impl FnMut(usize),
) -> Result<PvsWalkReport> {
    walk_pvs_into(db, path, cfg, tick, &mut NoSink)
}

/// [`walk_pvs`], handing each frame to `sink` (a renderer).
pub fn walk_pvs_into(
    db: &Database,
    path: &CameraPath,
    cfg: impl Into<PvsWalkConfig>,
    tick: impl FnMut(usize),
    sink: &mut dyn FrameSink,
) -> Result<PvsWalkReport> {
    walk_pvs_live(db, cfg, tick, &mut Played::path(path, sink))
}

/// [`walk_pvs_into`] with the poses coming from `viewer` frame by frame (a person at a
/// window), until it has no more.
pub fn walk_pvs_live(
    db: &Database,
    cfg: impl Into<PvsWalkConfig>,
    tick: impl FnMut(usize),
    viewer: &mut dyn Viewer,
) -> Result<PvsWalkReport> {
    walk_pvs_live_with(db, cfg.into(), &mut WalkLods::new(db), tick, viewer)
}

/// [`walk_pvs_into`] in constant memory, for a walk of any length: the poses come from
/// `poses` as the walk needs them (each checked as a [`CameraPath`]'s are), and each
/// frame's figures go to `each` as the frame ends, and are not kept. The report's
/// `frames` is empty; its figures are whole, and the same as [`walk_pvs_into`]'s.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # citygen::write_city(&citygen::CityConfig { objects: 40, ..Default::default() }, &scene)?;
/// # let mut opts = flaneur::BuildOptions::default();
/// # opts.visibility = Some(flaneur::visibility::VisibilityOptions { cell_size: 40.0, ..Default::default() });
/// # flaneur::build_from_scene(&scene, &path, &opts)?;
/// use flaneur::{path::cell_poses, walk::{pvs, NoSink}};
/// let db = flaneur::Database::open(&path)?;
/// let poses = cell_poses(&db, 200, 0.05, 30.0, 1)?;
/// let mut rows = 0;
/// let report = pvs::walk_pvs_streamed(
///     &db,
///     poses,
///     pvs::PvsPrefetch::Snp,
///     |_| {},
///     &mut NoSink,
///     &mut |_, _| {
///         rows += 1;
///         Ok(())
///     },
/// )?;
/// assert!(report.frames.is_empty());
/// assert_eq!((report.walked, rows), (200, 200));
/// # Ok(()) }
/// ```
pub fn walk_pvs_streamed(
    db: &Database,
    poses: impl Iterator<Item = Pose>,
    cfg: impl Into<PvsWalkConfig>,
    tick: impl FnMut(usize),
    sink: &mut dyn FrameSink,
    each: &mut dyn FnMut(usize, &PvsFrame) -> Result<()>,
) -> Result<PvsWalkReport> {
    walk_pvs_each(
        db,
        cfg.into(),
        &mut WalkLods::new(db),
        tick,
        &mut Played::streamed(poses, sink),
        each,
    )
}

/// [`walk_pvs_live`] with LOD selection `lods` kept from an earlier walk (one before it
/// at the same window), so that what it read and refined stays so.
pub(crate) fn walk_pvs_live_with<'db>(
    db: &'db Database,
    cfg: PvsWalkConfig,
    lods: &mut WalkLods<'db>,
    tick: impl FnMut(usize),
    viewer: &mut dyn Viewer,
) -> Result<PvsWalkReport> {
    let mut frames = Vec::new();
    let mut report = walk_pvs_each(db, cfg, lods, tick, viewer, &mut |_, f| {
        frames.push(*f);
        Ok(())
    })?;
    report.frames = frames;
    Ok(report)
}

/// The walk, each frame handed to `each` (with its index) and tallied, none kept.
fn walk_pvs_each<'db>(
    db: &'db Database,
    cfg: PvsWalkConfig,
    lods: &mut WalkLods<'db>,
    tick: impl FnMut(usize),
    viewer: &mut dyn Viewer,
    each: &mut dyn FnMut(usize, &PvsFrame) -> Result<()>,
) -> Result<PvsWalkReport> {
    cfg.validate()?;
    let mut tally = PvsTally::default();
    let mut index = 0;
    let run = super::run::walk_live(db, cfg, lods, tick, viewer, |(f, ms)| {
        tally.add(&f, ms);
        each(index, &f)?;
        index += 1;
        Ok(())
    })?;
    Ok(tally.report(cfg, run))
}
