//! What a PVS walk reports: each frame's figures, the walk's in all, and what its client
//! measured beside them.

use std::time::Instant;

use serde::Serialize;

use super::config::PvsPrefetch;
use crate::error::{Error, Result};
use crate::walk::buffer::ObjectBuffer;
use crate::walk::sink::FrameFigures;

/// One frame of a PVS walk.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct PvsFrame {
    /// The frame's index in the walk, from 0.
    pub frame: usize,
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

    /// The frame as one CSV row (no line end), its columns [`PvsFrame::CSV_HEADER`].
    pub fn csv_row(&self) -> String {
        format!(
            "{},{},{},{},{},{},{},{},{}",
            self.frame,
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
    /// [`Frames::Each`](crate::walk::Frames::Each)).
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

/// What a PVS walk's client measured beside its frames.
#[derive(Debug, Default)]
pub(crate) struct PvsRun {
    /// The longest round trip the client measured, frames.
    pub round_trip: u32,
    /// Reads the network failed (never waiting).
    pub failures: crate::walk::threads::load_failures::LoadFailures,
    /// What the loader could not read for damage, each object once, named (never
    /// waiting).
    pub damaged: Vec<String>,
}

/// A PVS frame retrieved at `started`, finished now: its figures and its time, ms.
pub(super) fn finish_timed(pending: Option<(PvsFrame, Instant)>) -> Result<(PvsFrame, f64)> {
    let (frame, started) =
        pending.ok_or_else(|| Error::Invalid("a frame finished before it was retrieved".into()))?;
    Ok((frame, started.elapsed().as_secs_f64() * 1e3))
}

/// What a PVS frame cost, for a display beside the picture; `damaged`, the objects
/// left out since the last frame.
pub(super) fn figures(
    (frame, ms): &(PvsFrame, f64),
    buffer: &ObjectBuffer,
    damaged: Vec<String>,
) -> FrameFigures {
    FrameFigures {
        pages: frame.pages,
        walk_ms: *ms,
        objects_buffered: buffer.len(),
        objects_drawn: frame.drawn,
        visual_misses: frame.visual_misses,
        cell: frame.cell.map_or_else(
            || "outside every viewcell".into(),
            |c| format!("viewcell {c}"),
        ),
        damaged,
        ..Default::default()
    }
}
