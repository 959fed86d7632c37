//! A VISUAL walk's summary, tallied a frame at a time: the same whether the walk keeps
//! its frames or hands each one on and forgets it, in constant memory.

use super::report::{VisualFrame, VisualSummary};
use crate::cache::CacheStats;
use crate::walk::cells_entered::CellsEntered;
use crate::walk::frame_times::FrameTimesTally;

/// What the summary needs of the frames seen so far.
#[derive(Clone, Debug, Default)]
pub(crate) struct VisualTally {
    frames: usize,
    initial_load_ms: f64,
    times: FrameTimesTally,
    cells_entered: CellsEntered,
    searches: usize,
    search_ms: f64,
    /// Figures summed over frames, named as the summary's.
    sum: VisualSummary,
    drawn: f64,
    triangles: f64,
}

impl VisualTally {
    /// The next frame.
    pub(crate) fn add(&mut self, f: &VisualFrame) {
        if self.frames == 0 {
            self.initial_load_ms = f.frame_ms;
        }
        self.cells_entered.add(f.cell);
        if f.cell.is_some() && f.visual_misses == 0 && self.sum.first_complete_frame.is_none() {
            self.sum.first_complete_frame = Some(self.frames);
        }
        if self.sum.first_complete_frame.is_some() {
            self.sum.visual_misses_after_start += f.visual_misses;
        }
        self.frames += 1;
        self.times.add(f.frame_ms);
        if f.searched {
            self.searches += 1;
            self.search_ms += f.search_ms;
        }
        self.drawn += f.drawn as f64;
        self.triangles += f.triangles_drawn as f64;
        let s = &mut self.sum;
        s.prefetches += usize::from(f.prefetch_adopted);
        s.prefetches_used += usize::from(f.prefetch_used);
        s.frames_outside += usize::from(f.cell.is_none());
        s.fallback_queries += usize::from(f.fallback_query);
        s.tree_pages += f.tree_pages;
        s.model_pages += f.model_pages;
        s.other_pages += f.other_pages;
        s.loaded += f.loaded;
        s.reused += f.reused;
        s.left_out += f.left_out;
        s.peak_buffer_bytes = s.peak_buffer_bytes.max(f.buffer_bytes);
        s.visual_misses += f.visual_misses;
        s.coarse_draws += f.coarse;
    }

    /// The walk's summary, with the node cache's figures.
    pub(crate) fn summary(&self, node_cache: Option<CacheStats>) -> VisualSummary {
        let times = self.times.times();
        let all = self.frames.max(1) as f64;
        VisualSummary {
            frames: self.frames,
            initial_load_ms: self.initial_load_ms,
            mean_frame_ms: times.mean,
            max_frame_ms: times.max,
            frame_ms_variance: times.variance,
            frames_over_50ms: times.over_50ms,
            cells_entered: self.cells_entered.count(),
            searches: self.searches,
            mean_search_ms: if self.searches == 0 {
                0.0
            } else {
                self.search_ms / self.searches as f64
            },
            mean_drawn: self.drawn / all,
            mean_triangles: self.triangles / all,
            node_cache,
            failed_loads: 0,
            last_load_error: None,
            ..self.sum.clone()
        }
    }
}
