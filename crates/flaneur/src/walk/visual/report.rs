//! What a VISUAL walk reports: each frame's figures, and the walk's in all.

use super::config::VisualConfig;
use crate::cache::CacheStats;
use serde::Serialize;

/// One frame of a VISUAL walk. Times in milliseconds.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct VisualFrame {
    /// The frame's index, from 0.
    pub frame: usize,
    /// Its pose's time on the path, seconds.
    pub time: f64,
    /// The viewcell the eye is in; `None` outside every one (the fallback's frame).
    pub cell: Option<u32>,
    /// The tree was searched for this frame's cell on the viewer's thread.
    pub searched: bool,
    /// The new cell's finds were a prefetch's, already loaded.
    pub prefetch_used: bool,
    /// A prefetch's finds reached the buffer on this frame.
    pub prefetch_adopted: bool,
    /// Outside every viewcell, the fallback's spatial query ran on this frame.
    pub fallback_query: bool,
    /// Objects the current cell's search found (or the fallback's query).
    pub objects_found: usize,
    /// Nodes it found at an internal LOD.
    pub nodes_found: usize,
    /// Finds read on this frame's thread (new, or at another level).
    pub loaded: usize,
    /// Finds the cell wanted that the buffer already held at their level (delta).
    pub reused: usize,
    /// Finds dropped, the new cell not finding them.
    pub dropped: usize,
    /// Finds left out, their pages unreadable (a viewer that walks on).
    pub left_out: usize,
    /// What the frame draws: finds in the frustum.
    pub drawn: usize,
    /// Their triangles.
    pub triangles_drawn: u64,
    /// Searching the tree on this thread.
    pub search_ms: f64,
    /// Reading and decoding finds' meshes on this thread.
    pub load_ms: f64,
    /// Culling against the frustum.
    pub cull_ms: f64,
    /// The walk's whole time for the frame (not drawing it, nor waiting for the clock).
    pub frame_ms: f64,
    /// Pages of the tree read this frame (nodes and V-pages), on both threads.
    pub tree_pages: u64,
    /// Pages of models read (meshes, LOD levels and internal LODs), on both threads.
    pub model_pages: u64,
    /// Other pages (the viewcells' table, the fallback's R-tree), on both threads.
    pub other_pages: u64,
    /// Bytes the buffer holds at the end of the frame.
    pub buffer_bytes: usize,
    /// A walk that never waits: the cell's finds the buffer held at no level (all of
    /// them while its search had not come back); 0 outside every viewcell.
    pub visual_misses: usize,
    /// A walk that never waits: the cell's finds held coarser than they deserve.
    pub coarse: usize,
}

/// A VISUAL walk in all. Frame 0 loads the first cell cold and is left out of the
/// frame-time figures, as REVIEW's is.
#[derive(Clone, Debug, Default, Serialize)]
pub struct VisualSummary {
    /// Frames walked, frame 0 included.
    pub frames: usize,
    /// Frame 0's time, ms.
    pub initial_load_ms: f64,
    /// Mean frame time from frame 1 on, ms.
    pub mean_frame_ms: f64,
    /// Longest frame from frame 1 on, ms.
    pub max_frame_ms: f64,
    /// Frame time's variance from frame 1 on, ms².
    pub frame_ms_variance: f64,
    /// Frames from 1 on over 50 ms.
    pub frames_over_50ms: usize,
    /// Moves into another viewcell.
    pub cells_entered: usize,
    /// Searches on the viewer's thread.
    pub searches: usize,
    /// Searches the prefetch thread ran.
    pub prefetches: usize,
    /// Cells entered whose finds a prefetch had loaded.
    pub prefetches_used: usize,
    /// Mean time of a search on the viewer's thread, ms (Fig. 5.27a).
    pub mean_search_ms: f64,
    /// Frames outside every viewcell, drawn by the fallback.
    pub frames_outside: usize,
    /// The fallback's spatial queries.
    pub fallback_queries: usize,
    /// Pages read, by kind, over the walk.
    pub tree_pages: u64,
    /// Model pages (meshes, levels, internal LODs).
    pub model_pages: u64,
    /// Other pages (viewcells' table, the fallback's R-tree).
    pub other_pages: u64,
    /// Finds loaded on the viewer's thread, and reused from the buffer.
    pub loaded: usize,
    /// Finds reused, summed over cell changes.
    pub reused: usize,
    /// Finds left out as unreadable.
    pub left_out: usize,
    /// Objects and groups drawn per frame, on average.
    pub mean_drawn: f64,
    /// Triangles drawn per frame, on average.
    pub mean_triangles: f64,
    /// The most bytes the buffer held at a frame's end.
    pub peak_buffer_bytes: usize,
    /// The node cache's figures, when it had one.
    pub node_cache: Option<CacheStats>,
    /// A walk that never waits: frames' visual misses, summed over the walk.
    pub visual_misses: usize,
    /// The first frame in a viewcell that misses nothing (a walk that never waits).
    pub first_complete_frame: Option<usize>,
    /// Visual misses from the first complete frame on.
    pub visual_misses_after_start: usize,
    /// Finds drawn coarser than they deserve, summed over frames.
    pub coarse_draws: usize,
    /// Reads the network failed, each asked for again (a walk that never waits).
    pub failed_loads: usize,
    /// The last failed read's words.
    pub last_load_error: Option<String>,
}

/// What a VISUAL walk did: its settings, every frame's figures, their summary.
#[derive(Clone, Debug, Serialize)]
pub struct VisualReport {
    /// The settings walked.
    pub config: VisualConfig,
    /// Every frame's figures, in order (empty for a walk that handed them on,
    /// [`Frames::Each`](crate::walk::Frames::Each)).
    pub frames: Vec<VisualFrame>,
    /// The walk in all.
    pub summary: VisualSummary,
}

impl VisualReport {
    /// One row per frame, under [`VisualFrame::CSV_HEADER`].
    pub fn to_csv(&self) -> String {
        crate::walk::frame_csv::table(VisualFrame::CSV_HEADER, &self.frames, VisualFrame::csv_row)
    }
}

impl VisualFrame {
    /// The columns of [`VisualFrame::csv_row`].
    pub const CSV_HEADER: &'static str = "frame,time,cell,searched,prefetch_used,prefetch_adopted,fallback_query,objects_found,nodes_found,loaded,reused,dropped,left_out,drawn,triangles_drawn,search_ms,load_ms,cull_ms,frame_ms,tree_pages,model_pages,other_pages,buffer_bytes,visual_misses,coarse";

    /// The frame as one CSV row (no line end), its columns [`VisualFrame::CSV_HEADER`].
    pub fn csv_row(&self) -> String {
        let f = self;
        format!(
            "{},{:.4},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.3},{:.3},{:.3},{:.3},{},{},{},{},{},{}",
            f.frame,
            f.time,
            f.cell.map_or(String::new(), |c| c.to_string()),
            f.searched as u8,
            f.prefetch_used as u8,
            f.prefetch_adopted as u8,
            f.fallback_query as u8,
            f.objects_found,
            f.nodes_found,
            f.loaded,
            f.reused,
            f.dropped,
            f.left_out,
            f.drawn,
            f.triangles_drawn,
            f.search_ms,
            f.load_ms,
            f.cull_ms,
            f.frame_ms,
            f.tree_pages,
            f.model_pages,
            f.other_pages,
            f.buffer_bytes,
            f.visual_misses,
            f.coarse
        )
    }
}
