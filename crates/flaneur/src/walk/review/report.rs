//! What a REVIEW or BOX walk reports: each frame's figures, and the walk's in all.

use super::config::ReviewConfig;
use crate::cache::{CacheStats, Trace};

/// One frame's figures. Times in milliseconds.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameStats {
    /// The frame's index in the walk, from 0.
    pub frame: usize,
    /// Its pose's time on the path, seconds.
    pub time: f64,
    /// Waiting for a query (synchronous, or a prefetch not yet done).
    pub query_ms: f64,
    /// Reading and decoding meshes on this thread, and adding them to the buffer.
    pub load_ms: f64,
    /// Culling the buffer against the frustum.
    pub cull_ms: f64,
    /// Gathering the figures of the objects drawn.
    pub prep_ms: f64,
    /// The walk's whole time for the frame, from its retrieval to its figures (not
    /// drawing it, nor waiting for the path's clock).
    pub frame_ms: f64,
    /// The viewer moved to a new disk cell on this frame (queried on this thread, or
    /// switched to a prefetched cell).
    pub queried: bool,
    /// A query ran on this frame's thread (the viewer waited for its I/O).
    pub sync_query: bool,
    /// The new disk cell was one prefetched earlier.
    pub prefetch_used: bool,
    /// A prefetch's result reached the buffer on this frame.
    pub prefetch_adopted: bool,
    /// Objects added to the buffer on this frame (by a query or a prefetch).
    pub objects_loaded: usize,
    /// Objects in the buffer after loading, before culling.
    pub objects_buffered: usize,
    /// Objects drawn: those of the buffer in the view frustum.
    pub objects_drawn: usize,
    /// Of those, objects drawn at a coarse stored level while their full mesh comes
    /// (never-wait walks on a database with LODs).
    pub coarse_drawn: usize,
    /// Objects whose full mesh took the place of their coarse level on this frame.
    pub refined: usize,
    /// Their triangles, at the level each is held at (full detail unless coarse).
    pub triangles_drawn: u64,
    /// Objects in the view frustum that were not in memory.
    pub visual_misses: usize,
    /// Physical reads of index pages this frame, on both threads (from the start of
    /// its retrieval, its wait for the path's clock included: a prefetch reads then).
    pub index_pages: u64,
    /// Physical reads of mesh pages this frame, on both threads (as `index_pages`).
    pub mesh_pages: u64,
    /// Physical reads of LOD pages this frame (the coarse levels a never-wait walk
    /// loads first), on every thread (as `index_pages`).
    pub lod_pages: u64,
    /// Bytes the object buffer holds at the end of the frame.
    pub buffer_bytes: usize,
    /// Objects evicted from the buffer on this frame.
    pub evicted: usize,
    /// The latest cell's own objects did not fit the budget.
    pub overflow: bool,
    /// With [`ReviewConfig::never_wait`]: the viewer was outside every cell it held, and
    /// the frame drew what the buffer held while the loader searched for it.
    pub outran: bool,
    /// Objects whose coarse level the loaders found damaged by this frame's end, since
    /// the last frame (named in [`WalkSummary::damaged`]).
    pub damaged: usize,
}

impl FrameStats {
    /// The columns of [`FrameStats::csv_row`].
    pub const CSV_HEADER: &'static str = "frame,time,frame_ms,query_ms,load_ms,cull_ms,prep_ms,queried,sync_query,prefetch_used,prefetch_adopted,objects_loaded,objects_buffered,objects_drawn,triangles_drawn,visual_misses,index_pages,mesh_pages,buffer_bytes,evicted,overflow,outran,coarse_drawn,refined,damaged";

    /// The frame as one CSV row (no line end), its columns [`FrameStats::CSV_HEADER`]:
    /// what a walk writes as each frame ends.
    pub fn csv_row(&self) -> String {
        let f = self;
        format!(
                "{},{:.4},{:.3},{:.3},{:.3},{:.3},{:.3},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                f.frame,
                f.time,
                f.frame_ms,
                f.query_ms,
                f.load_ms,
                f.cull_ms,
                f.prep_ms,
                f.queried as u8,
                f.sync_query as u8,
                f.prefetch_used as u8,
                f.prefetch_adopted as u8,
                f.objects_loaded,
                f.objects_buffered,
                f.objects_drawn,
                f.triangles_drawn,
                f.visual_misses,
                f.index_pages,
                f.mesh_pages,
                f.buffer_bytes,
                f.evicted,
                f.overflow as u8,
                f.outran as u8,
                f.coarse_drawn,
                f.refined,
                f.damaged
            )
    }
}

/// A whole walk. Frame 0 loads the first disk cell from nothing (the thesis's session
/// start); its time is reported as `initial_load_ms` and left out of the frame-time
/// figures, which describe the walk itself.
#[derive(Clone, Debug, serde::Serialize)]
pub struct WalkSummary {
    /// Frames walked, frame 0 included.
    pub frames: usize,
    /// Frame 0: the first disk cell, loaded cold.
    pub initial_load_ms: f64,
    /// Index and mesh pages that frame 0's query read: the cold load alone, without what
    /// a prefetch started in that frame read beside it.
    pub initial_load_pages: (u64, u64),
    /// The mean frame time ([`FrameStats::frame_ms`]), frames 1 onwards.
    pub mean_frame_ms: f64,
    /// The longest frame time, frames 1 onwards.
    pub max_frame_ms: f64,
    /// The frame time's variance, frames 1 onwards, ms².
    pub frame_ms_variance: f64,
    /// Frames (from 1 on) over 50 ms, the thesis's real-time limit.
    pub frames_over_50ms: usize,
    /// Index searches run, on either thread (each reads pages: the thesis's "query").
    pub queries: usize,
    /// Searches on the frame thread: the viewer waited for them.
    pub sync_queries: usize,
    /// Prefetch results taken into the buffer.
    pub prefetches_adopted: usize,
    /// Prefetch results thrown away because an eviction came between.
    pub prefetches_stale: usize,
    /// Moves to a new disk cell.
    pub cell_changes: usize,
    /// Moves to a new disk cell that had been prefetched.
    pub prefetches_used: usize,
    /// Index pages read, all frames.
    pub index_pages: u64,
    /// Mesh pages read, all frames.
    pub mesh_pages: u64,
    /// LOD pages read, all frames (never-wait walks' coarse levels).
    pub lod_pages: u64,
    /// Index pages per query.
    pub index_pages_per_query: f64,
    /// Index and mesh pages per query: the thesis's "disk I/Os per query".
    pub io_per_query: f64,
    /// Visual misses, summed over frames ([`FrameStats::visual_misses`]).
    pub visual_misses: u64,
    /// Frames on which the latest cell's own objects did not fit the budget.
    pub overflow_frames: usize,
    /// The most bytes the object buffer held at the end of a frame.
    pub peak_buffer_bytes: usize,
    /// The index cache's figures over the walk, when it had one.
    pub index_cache: Option<CacheStats>,
    /// With [`ReviewConfig::never_wait`]: searches the viewer queued on the loader
    /// instead of running them (counted among the adopted and dropped results).
    pub queued_queries: usize,
    /// Frames on which the viewer was outside every cell it held
    /// ([`FrameStats::outran`]).
    pub frames_outran: usize,
    /// Objects drawn coarse while their full mesh came, summed over frames
    /// ([`FrameStats::coarse_drawn`]).
    pub coarse_draws: u64,
    /// Full meshes put in place of coarse levels.
    pub refined: usize,
    /// The first frame with no visual miss: when the walk first drew all it should.
    pub first_complete_frame: Option<usize>,
    /// With [`ReviewConfig::never_wait`]: loads that failed on the network (and were
    /// asked for again), and the last of their errors.
    pub failed_loads: usize,
    /// The last failed load's error.
    pub last_load_error: Option<String>,
    /// What the walk could not read for damage and went on without, each object once,
    /// in words that name its page (a never-wait walk's coarse levels, its objects
    /// loaded at full detail instead; a waiting walk stops at damage instead). A
    /// headless walk with any fails at its end.
    pub damaged: Vec<String>,
}

/// What a REVIEW or BOX walk did: its settings, every frame's figures, their summary.
#[derive(Clone, Debug, serde::Serialize)]
pub struct WalkReport {
    /// The settings walked.
    pub config: ReviewConfig,
    /// Every frame's figures, in order (empty for a walk that handed them on,
    /// [`Frames::Each`](crate::walk::Frames::Each)).
    pub frames: Vec<FrameStats>,
    /// The walk's figures in all.
    pub summary: WalkSummary,
    /// The index cache's accesses, when `record_trace` was set and a cache was used.
    #[serde(skip)]
    pub trace: Option<Trace>,
}

impl WalkReport {
    /// One row per frame, under [`FrameStats::CSV_HEADER`].
    pub fn to_csv(&self) -> String {
        crate::walk::frame_csv::table(FrameStats::CSV_HEADER, &self.frames, FrameStats::csv_row)
    }
}
