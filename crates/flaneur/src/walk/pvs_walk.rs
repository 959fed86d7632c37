//! The PVS walk (`flaneur walk DB --mode pvs`): a camera path over a database built with
//! `--visibility`, the viewer drawing its current viewcell's PVS while a client
//! prefetches neighbours' PVS rows with SNP or PBNP (Zheng 2007 ch. 7) from the stored
//! table, every page read counted.
//!
//! A pose whose eye is in no walkable cell (above a roof, off the grid) draws nothing
//! new and asks for nothing: the client keeps what it holds and the frame counts as
//! outside. That is the walk's choice; the prefetcher itself refuses such positions.
//!
//! Drawn ([`walk_pvs_into`] with a renderer), the objects the client holds are loaded
//! into an object buffer as they arrive and dropped when it evicts them, and each frame
//! draws the current cell's PVS (the last cell's, outside cells) within the frustum.
//! Those mesh reads are the renderer's: a frame's page count is taken before them.
//!
//! Never waiting ([`PvsWalkConfig::never_wait`], ours): the client runs on a loader
//! thread of its own, which reads the rows and meshes it asks for while the viewer's
//! thread only takes what has arrived, so a slow disk or a round trip over HTTP shows as
//! visual misses, never as a long frame. The client's round trip is then measured in
//! frames, and LANP ([`PvsPrefetch::Lanp`]) looks as far ahead as the viewer may go in
//! it (`prefetch::pvs::Lanp`).
//!
//! Here: the settings, the entry points and the figures a walk reports. The frame loop
//! is the walk session's (`walk/session.rs`), the client the PVS mode's
//! (`walk/mode/pvs.rs`; never waiting, `walk/mode/pvs_never_wait.rs` and its loader
//! `walk/mode/pvs_loader.rs`).

use serde::Serialize;

use crate::database::Database;
use crate::error::{Error, Result};
use crate::path::{CameraPath, Pose};
use crate::prefetch::pvs::{Lanp, Pbnp, PrefetchArea, Snp};
use crate::walk::pvs_tally::PvsTally;
use crate::walk::sink::Played;
use crate::walk::walk_lods::WalkLods;
use crate::walk::{FrameSink, NoSink, Viewer};

/// Which neighbours the client prefetches.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum PvsPrefetch {
    /// All eight on every cell change.
    Snp,
    /// Those the viewer leans towards, by the region of its cell it is in.
    Pbnp {
        /// The width of the side and corner regions, a fraction of the cell's side in
        /// (0, 0.5] ([`DEFAULT_BORDER`](crate::prefetch::pvs::DEFAULT_BORDER): 0.25).
        border: f64,
    },
    /// PBNP's cells and every cell the viewer may reach before an answer comes, at its
    /// measured speed and round trip (ours, `prefetch::pvs::Lanp`).
    Lanp {
        /// PBNP's border, as above.
        border: f64,
    },
}

impl PvsPrefetch {
    /// The rule's name, as the CLI's `--prefetch` spells it: `snp`, `pbnp` or `lanp`.
    pub fn name(&self) -> &'static str {
        match self {
            PvsPrefetch::Snp => "snp",
            PvsPrefetch::Pbnp { .. } => "pbnp",
            PvsPrefetch::Lanp { .. } => "lanp",
        }
    }

    /// The rule itself. LANP is taken to start standing still: until the viewer has
    /// moved it looks as far as PBNP. An error for a border outside (0, 0.5].
    pub fn rule(&self) -> Result<Box<dyn PrefetchArea + Sync>> {
        Ok(match *self {
            PvsPrefetch::Snp => Box::new(Snp),
            PvsPrefetch::Pbnp { border } => Box::new(Pbnp::new(border)?),
            PvsPrefetch::Lanp { border } => Box::new(Lanp::new(border, 0.0)?),
        })
    }
}

/// How a PVS walk runs: its prefetching rule, and whether the viewer waits on reads.
/// A [`PvsPrefetch`] alone is a waiting, unpaced walk, as the thesis's.
///
/// ```
/// use flaneur::walk::pvs_walk::{PvsPrefetch, PvsWalkConfig};
/// let cfg = PvsWalkConfig::never_waiting(PvsPrefetch::Lanp { border: 0.25 });
/// assert!(cfg.never_wait && cfg.pace == Some(4.0));
/// assert!(cfg.validate().is_ok());
/// let thesis: PvsWalkConfig = PvsPrefetch::Snp.into();
/// assert!(!thesis.never_wait && thesis.pace.is_none());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PvsWalkConfig {
    /// Which neighbours the client prefetches.
    pub prefetch: PvsPrefetch,
    /// The viewer's thread never waits on a read (ours): the client and its reads run
    /// on a loader thread, and each frame draws what has arrived.
    pub never_wait: bool,
    /// The path's clock runs this many times faster than real time: a never-wait
    /// walk's loader works in real time, so frames are played at their poses' times
    /// over this. `None`: frames back to back.
    pub pace: Option<f32>,
}

impl From<PvsPrefetch> for PvsWalkConfig {
    fn from(prefetch: PvsPrefetch) -> PvsWalkConfig {
        PvsWalkConfig {
            prefetch,
            never_wait: false,
            pace: None,
        }
    }
}

impl PvsWalkConfig {
    /// A never-wait walk with `prefetch`, played at
    /// [`DEFAULT_PACE`](crate::walk::settings::DEFAULT_PACE) times real time.
    pub fn never_waiting(prefetch: PvsPrefetch) -> PvsWalkConfig {
        PvsWalkConfig {
            prefetch,
            never_wait: true,
            pace: Some(crate::walk::settings::DEFAULT_PACE),
        }
    }

    /// Checks the rule's border and the pace (finite, above 0).
    pub fn validate(&self) -> Result<()> {
        self.prefetch.rule()?;
        match self.pace {
            Some(p) if !(p.is_finite() && p > 0.0) => Err(Error::Invalid(format!(
                "a PVS walk's pace must be a finite number of times real time above 0, not {p}"
            ))),
            _ => Ok(()),
        }
    }
}

/// One frame of a PVS walk.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PvsFrame {
    /// The viewcell the eye is in, if walkable.
    pub cell: Option<u32>,
    /// Objects drawn: the current cell's PVS (0 outside cells).
    pub drawn: usize,
    /// Whether a prefetch transaction ran.
    pub transaction: bool,
    /// Objects it sent the client.
    pub sent: usize,
    /// Its cache swaps: entries of the client's cache (a viewcell's PVS each) replaced
    /// to make room.
    pub swaps: usize,
    /// Objects of the current cell's PVS the frame lacks: waiting, on entering a cell,
    /// those the client did not hold; never waiting, at every frame, those not yet
    /// arrived (all of them while the cell's row has not).
    pub visual_misses: usize,
    /// Pages read during the frame (visibility pages included; never waiting, by the
    /// loader too).
    pub pages: u64,
    /// Never waiting: objects whose coarse level the loader found damaged, learnt of on
    /// this frame (named in [`PvsWalkReport::damaged`]).
    pub damaged: usize,
}

impl PvsFrame {
    /// The columns of [`PvsFrame::csv_row`].
    pub const CSV_HEADER: &'static str =
        "frame,cell,drawn,transaction,sent,swaps,visual_misses,pages,damaged";

    /// Frame `index` as one CSV row (no line end), its columns [`PvsFrame::CSV_HEADER`].
    pub fn csv_row(&self, index: usize) -> String {
        format!(
            "{index},{},{},{},{},{},{},{},{}",
            self.cell.map_or(String::new(), |c| c.to_string()),
            self.drawn,
            self.transaction as u8,
            self.sent,
            self.swaps,
            self.visual_misses,
            self.pages,
            self.damaged
        )
    }
}

/// What a PVS walk did, frame by frame and in all.
#[derive(Clone, Debug, Serialize)]
pub struct PvsWalkReport {
    /// The prefetching rule walked.
    pub prefetch: PvsPrefetch,
    /// Whether the viewer's thread never waited on a read.
    pub never_wait: bool,
    /// Every frame's figures, in order (empty for a walk that handed them on,
    /// [`walk_pvs_streamed`]).
    pub frames: Vec<PvsFrame>,
    /// Frames walked.
    pub walked: usize,
    /// Frames whose eye was in no walkable viewcell.
    pub frames_outside: usize,
    /// Moves into a viewcell other than the last frame's.
    pub cells_entered: usize,
    /// Prefetch transactions run.
    pub transactions: usize,
    /// Cache swaps, summed over frames ([`PvsFrame::swaps`]).
    pub swaps: usize,
    /// Objects sent the client, summed over frames.
    pub objects_sent: usize,
    /// Visual misses, summed over frames ([`PvsFrame::visual_misses`]).
    pub visual_misses: usize,
    /// Objects drawn per frame inside walkable cells, on average.
    pub mean_drawn: f64,
    /// Pages read, summed over frames.
    pub pages: u64,
    /// The viewer's thread's time per frame, from taking the pose to culling, ms, on
    /// average.
    pub mean_frame_ms: f64,
    /// The longest frame on the viewer's thread, ms.
    pub max_frame_ms: f64,
    /// Frames that took the viewer's thread over 50 ms.
    pub frames_over_50ms: usize,
    /// The first frame inside a walkable cell without a visual miss.
    pub first_complete_frame: Option<usize>,
    /// Visual misses after that frame: what the prefetching missed once the start's
    /// first cell had arrived (the whole sum when no frame was complete).
    pub visual_misses_after_start: usize,
    /// The longest round trip the client measured, frames from asking to holding (0
    /// when waiting: every answer comes in the frame that asks).
    pub round_trip_frames: u32,
    /// Loads that failed on the network and were asked for again (never waiting).
    pub failed_loads: usize,
    /// The last of those failures.
    pub last_load_error: Option<String>,
    /// What the walk could not read for damage and went on without, each object once,
    /// in words that name its page (never waiting: coarse levels, their objects loaded
    /// at full detail instead; a waiting walk stops at damage). A headless walk with
    /// any fails at its end.
    pub damaged: Vec<String>,
}

impl PvsWalkReport {
    /// Objects sent per transaction.
    pub fn objects_per_transaction(&self) -> f64 {
        self.objects_sent as f64 / self.transactions.max(1) as f64
    }
}

/// Walks `path` over `db`'s precomputed visibility as `cfg` says (a [`PvsPrefetch`]
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
/// use flaneur::{path::cell_poses, walk::{pvs_walk, NoSink}};
/// let db = flaneur::Database::open(&path)?;
/// let poses = cell_poses(&db, 200, 0.05, 30.0, 1)?;
/// let mut rows = 0;
/// let report = pvs_walk::walk_pvs_streamed(
///     &db,
///     poses,
///     pvs_walk::PvsPrefetch::Snp,
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
    let run = super::mode::pvs::walk_live(db, cfg, lods, tick, viewer, |(f, ms)| {
        tally.add(&f, ms);
        each(index, &f)?;
        index += 1;
        Ok(())
    })?;
    Ok(tally.report(cfg, run))
}
