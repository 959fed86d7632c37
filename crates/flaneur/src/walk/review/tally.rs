//! A REVIEW walk's summary, tallied a frame at a time: the same figures whether the
//! walk keeps its frames or hands each one on and forgets it, in constant memory.

use super::counts::Counts;
use super::report::{FrameStats, WalkSummary};
use crate::cache::CacheStats;
use crate::walk::frame_times::FrameTimesTally;

/// What the summary needs of the frames seen so far.
#[derive(Clone, Debug, Default)]
pub(crate) struct ReviewTally {
    frames: usize,
    initial_load_ms: f64,
    times: FrameTimesTally,
    index_pages: u64,
    mesh_pages: u64,
    lod_pages: u64,
    cell_changes: usize,
    prefetches_used: usize,
    visual_misses: u64,
    overflow_frames: usize,
    peak_buffer_bytes: usize,
    frames_outran: usize,
    coarse_draws: u64,
    refined: usize,
    first_complete_frame: Option<usize>,
}

impl ReviewTally {
    /// The next frame.
    pub(crate) fn add(&mut self, f: &FrameStats) {
        if self.frames == 0 {
            self.initial_load_ms = f.frame_ms;
        }
        if self.first_complete_frame.is_none() && f.visual_misses == 0 {
            self.first_complete_frame = Some(self.frames);
        }
        self.frames += 1;
        self.times.add(f.frame_ms);
        self.index_pages += f.index_pages;
        self.mesh_pages += f.mesh_pages;
        self.lod_pages += f.lod_pages;
        self.cell_changes += usize::from(f.queried);
        self.prefetches_used += usize::from(f.prefetch_used);
        self.visual_misses += f.visual_misses as u64;
        self.overflow_frames += usize::from(f.overflow);
        self.peak_buffer_bytes = self.peak_buffer_bytes.max(f.buffer_bytes);
        self.frames_outran += usize::from(f.outran);
        self.coarse_draws += f.coarse_drawn as u64;
        self.refined += f.refined;
    }

    /// Frames seen.
    pub(crate) fn frames(&self) -> usize {
        self.frames
    }

    /// The walk's summary from its frames and its searches.
    pub(crate) fn summary(&self, counts: Counts, cache: Option<CacheStats>) -> WalkSummary {
        let times = self.times.times();
        let queries = counts.sync + counts.adopted + counts.stale;
        let per_query = |pages: u64| {
            if queries == 0 {
                0.0
            } else {
                pages as f64 / queries as f64
            }
        };
        WalkSummary {
            frames: self.frames,
            initial_load_ms: self.initial_load_ms,
            initial_load_pages: counts.initial_load_pages,
            mean_frame_ms: times.mean,
            max_frame_ms: times.max,
            frame_ms_variance: times.variance,
            frames_over_50ms: times.over_50ms,
            queries,
            sync_queries: counts.sync,
            prefetches_adopted: counts.adopted,
            prefetches_stale: counts.stale,
            cell_changes: self.cell_changes,
            prefetches_used: self.prefetches_used,
            index_pages: self.index_pages,
            mesh_pages: self.mesh_pages,
            lod_pages: self.lod_pages,
            index_pages_per_query: per_query(self.index_pages),
            io_per_query: per_query(self.index_pages + self.mesh_pages),
            visual_misses: self.visual_misses,
            overflow_frames: self.overflow_frames,
            peak_buffer_bytes: self.peak_buffer_bytes,
            index_cache: cache,
            queued_queries: counts.queued,
            frames_outran: self.frames_outran,
            coarse_draws: self.coarse_draws,
            refined: self.refined,
            first_complete_frame: self.first_complete_frame,
            failed_loads: counts.failed,
            last_load_error: counts.last_failure,
            damaged: Vec::new(),
        }
    }
}
