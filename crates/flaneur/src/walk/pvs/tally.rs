//! A PVS walk's figures, tallied a frame at a time: the same whether the walk keeps its
//! frames or hands each one on and forgets it, in constant memory.

use super::report::PvsRun;
use crate::walk::cells_entered::CellsEntered;
use crate::walk::pvs::{PvsFrame, PvsWalkConfig, PvsWalkReport};

/// What the report needs of the frames seen so far.
#[derive(Clone, Debug, Default)]
pub(crate) struct PvsTally {
    frames: usize,
    inside: usize,
    drawn_inside: f64,
    cells_entered: CellsEntered,
    transactions: usize,
    swaps: usize,
    sent: usize,
    visual_misses: usize,
    pages: u64,
    ms_sum: f64,
    ms_max: f64,
    over_50ms: usize,
    first_complete_frame: Option<usize>,
    misses_after_start: usize,
}

impl PvsTally {
    /// The next frame, and its time on the viewer's thread, ms.
    pub(crate) fn add(&mut self, f: &PvsFrame, ms: f64) {
        if f.cell.is_some() {
            self.inside += 1;
            self.drawn_inside += f.drawn as f64;
            if self.first_complete_frame.is_none() && f.visual_misses == 0 {
                self.first_complete_frame = Some(self.frames);
            }
        }
        if self.first_complete_frame.is_some() {
            self.misses_after_start += f.visual_misses;
        }
        self.cells_entered.add(f.cell);
        self.frames += 1;
        self.transactions += usize::from(f.transaction);
        self.swaps += f.swaps;
        self.sent += f.sent;
        self.visual_misses += f.visual_misses;
        self.pages += f.pages;
        self.ms_sum += ms;
        self.ms_max = self.ms_max.max(ms);
        self.over_50ms += usize::from(ms > 50.0);
    }

    /// The walk's report under `cfg`, with what its client measured; its `frames` empty.
    pub(crate) fn report(&self, cfg: PvsWalkConfig, run: PvsRun) -> PvsWalkReport {
        PvsWalkReport {
            prefetch: cfg.prefetch,
            never_wait: cfg.never_wait,
            frames: Vec::new(),
            walked: self.frames,
            frames_outside: self.frames - self.inside,
            cells_entered: self.cells_entered.count(),
            transactions: self.transactions,
            swaps: self.swaps,
            objects_sent: self.sent,
            visual_misses: self.visual_misses,
            mean_drawn: self.drawn_inside / self.inside.max(1) as f64,
            pages: self.pages,
            mean_frame_ms: self.ms_sum / self.frames.max(1) as f64,
            max_frame_ms: self.ms_max,
            frames_over_50ms: self.over_50ms,
            first_complete_frame: self.first_complete_frame,
            // No complete frame: every miss was after the start.
            visual_misses_after_start: match self.first_complete_frame {
                Some(_) => self.misses_after_start,
                None => self.visual_misses,
            },
            round_trip_frames: run.round_trip,
            failed_loads: run.failures.count,
            last_load_error: run.failures.last,
            damaged: run.damaged,
        }
    }
}
