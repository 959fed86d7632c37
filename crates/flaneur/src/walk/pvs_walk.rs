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
//! Here: the settings, the entry points and the figures a walk reports. The frame loop
//! is the walk session's (`walk/session.rs`), the client the PVS mode's
//! (`walk/mode/pvs.rs`).

use serde::Serialize;

use crate::database::Database;
use crate::error::Result;
use crate::walk::lod_select::WalkLods;
use crate::walk::path::CameraPath;
use crate::walk::sink::Played;
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
}

impl PvsPrefetch {
    /// The rule's name, as the CLI's `--prefetch` spells it: `snp` or `pbnp`.
    pub fn name(&self) -> &'static str {
        match self {
            PvsPrefetch::Snp => "snp",
            PvsPrefetch::Pbnp { .. } => "pbnp",
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
    /// On entering a cell, objects of its PVS the client did not hold.
    pub visual_misses: usize,
    /// Pages read during the frame (visibility pages included).
    pub pages: u64,
}

/// What a PVS walk did, frame by frame and in all.
#[derive(Clone, Debug, Serialize)]
pub struct PvsWalkReport {
    /// The prefetching rule walked.
    pub prefetch: PvsPrefetch,
    /// Every frame's figures, in order.
    pub frames: Vec<PvsFrame>,
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
}

impl PvsWalkReport {
    /// Objects sent per transaction.
    pub fn objects_per_transaction(&self) -> f64 {
        self.objects_sent as f64 / self.transactions.max(1) as f64
    }
}

/// Walks `path` over `db`'s precomputed visibility with `prefetch`, calling `tick`
/// after each frame.
pub fn walk_pvs(
    db: &Database,
    path: &CameraPath,
    prefetch: PvsPrefetch,
    tick: impl FnMut(usize),
) -> Result<PvsWalkReport> {
    walk_pvs_into(db, path, prefetch, tick, &mut NoSink)
}

/// [`walk_pvs`], handing each frame to `sink` (a renderer).
pub fn walk_pvs_into(
    db: &Database,
    path: &CameraPath,
    prefetch: PvsPrefetch,
    tick: impl FnMut(usize),
    sink: &mut dyn FrameSink,
) -> Result<PvsWalkReport> {
    walk_pvs_live(db, prefetch, tick, &mut Played { path, sink })
}

/// [`walk_pvs_into`] with the poses coming from `viewer` frame by frame (a person at a
/// window), until it has no more.
pub fn walk_pvs_live(
    db: &Database,
    prefetch: PvsPrefetch,
    tick: impl FnMut(usize),
    viewer: &mut dyn Viewer,
) -> Result<PvsWalkReport> {
    walk_pvs_live_with(db, prefetch, &mut WalkLods::new(db), tick, viewer)
}

/// [`walk_pvs_live`] with LOD selection `lods` kept from an earlier walk (one before it
/// at the same window), so that what it read and refined stays so.
pub(crate) fn walk_pvs_live_with<'db>(
    db: &'db Database,
    prefetch: PvsPrefetch,
    lods: &mut WalkLods<'db>,
    tick: impl FnMut(usize),
    viewer: &mut dyn Viewer,
) -> Result<PvsWalkReport> {
    let frames = super::mode::pvs::walk_live(db, prefetch, lods, tick, viewer)?;
    let inside: Vec<&PvsFrame> = frames.iter().filter(|f| f.cell.is_some()).collect();
    let cells_entered = frames
        .windows(2)
        .filter(|w| w[1].cell.is_some() && w[1].cell != w[0].cell)
        .count();
    Ok(PvsWalkReport {
        prefetch,
        frames_outside: frames.len() - inside.len(),
        cells_entered,
        transactions: frames.iter().filter(|f| f.transaction).count(),
        swaps: frames.iter().map(|f| f.swaps).sum(),
        objects_sent: frames.iter().map(|f| f.sent).sum(),
        visual_misses: frames.iter().map(|f| f.visual_misses).sum(),
        mean_drawn: inside.iter().map(|f| f.drawn as f64).sum::<f64>() / inside.len().max(1) as f64,
        pages: frames.iter().map(|f| f.pages).sum(),
        frames,
    })
}
