//! The REVIEW walkthrough (Shou 2002 §4.1–4.4), headless: a camera path in, per-frame
//! figures out.
//!
//! Each frame: the frustum cell (the box around the view frustum) is tested against
//! the disk cell; when it leaves, a new disk cell — the frustum cell scaled by SF on
//! the ground, centred on it — is queried with BOX or CSearch, and the meshes it
//! returns are loaded into the object buffer (evicting by Fig. 4.8 when over budget).
//! The buffer is then culled against the frustum (ViewCulling, Fig. 4.15) and the
//! drawn objects' triangles gathered. With prefetching, a background thread queries
//! the cell predicted at F' = F + k·velocity (F: centre of the far clip plane, §4.2.5:
//! the disk cell of the frustum moved by k seconds of the viewer's motion) before the
//! viewer gets there; index pages go through the index cache when one is
//! configured. The four configurations of §4.4 are presets.
//!
//! Here: REVIEW's settings, the entry points and the figures a walk reports; the
//! defaults and checks every walk shares are `walk::settings`'.
//! The frame loop is the walk session's (`walk/session.rs`), the retrieval the REVIEW
//! mode's (`walk/mode/review.rs`), the motion prediction `prefetch::motion`'s.
//!
//! Prefetching follows Fig. 4.11: the prefetched cell C2 is searched (CSearch against
//! the history) while the viewer is still in C1, and its objects go into the buffer as
//! soon as they arrive, its cell into the history; when the frustum cell leaves C1 and
//! C2 holds it, C2 becomes the disk cell with no I/O on the viewer's thread. If the
//! prediction was wrong, the viewer's own query is a CSearch against C1 and C2 both.
//!
//! Departures, named: a prefetch is started when the frustum cell, grown by one
//! second of motion, would leave the disk cell (the thesis says "when approaching the
//! boundary"); the predicted cell holds the frusta from now to k seconds ahead, and
//! the frusta the viewer turns through on the way when it is turning (the thesis
//! predicts the translation only, and a turning viewer leaves such a cell every few
//! degrees); it is asked again from the same disk cell only when the prediction has
//! moved by a quarter of a cell; a prefetched result is dropped if an eviction happened
//! since it was asked for (an eviction restarts the CSearch history, so an older
//! complement could miss objects); BOX reloads every object of its cell (the thesis's
//! BOX has "no optimization") and has no prefetching. A walk with prefetching is paced
//! to the path's clock (by default four times faster than real time, see
//! [`ReviewConfig::pace`]): unpaced, the frames of a headless walk take microseconds and
//! the prefetch thread never gets the time a viewer would give it. Frame 0 loads the
//! first cell from nothing and is reported apart from the walk's frame times.

use super::settings::{
    check_budget, check_far, check_k, check_pace, check_sf, DEFAULT_FAR, DEFAULT_K,
    DEFAULT_MEMORY_BUDGET, DEFAULT_PACE, DEFAULT_SF,
};
use super::sink::{FrameSink, NoSink, Played, Viewer};
use super::walk_lods::WalkLods;
use crate::cache::{CacheStats, Trace};
use crate::database::Database;
use crate::error::{Error, Result};
use crate::path::{CameraPath, Pose};

/// How a walk retrieves objects.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Retrieval {
    /// Plain range queries; every query reloads its whole cell.
    Box,
    /// Complement queries: only what the cell adds.
    CSearch,
}

/// The configurations of the thesis's experiments (§4.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Preset {
    /// CSearch + index cache + prefetching.
    Optimal,
    /// No index cache.
    Nc,
    /// No prefetching.
    Np,
    /// Plain BOX queries, nothing else.
    Box,
}

impl Preset {
    /// Every configuration, in the thesis's order.
    pub const ALL: [Preset; 4] = [Preset::Optimal, Preset::Nc, Preset::Np, Preset::Box];

    /// The configuration's name, as the CLI spells it and [`str::parse`] reads it:
    /// `optimal`, `nc`, `np` or `box`.
    pub fn name(&self) -> &'static str {
        match self {
            Preset::Optimal => "optimal",
            Preset::Nc => "nc",
            Preset::Np => "np",
            Preset::Box => "box",
        }
    }
}

impl std::str::FromStr for Preset {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Preset, String> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name() == s.to_ascii_lowercase())
            .ok_or_else(|| format!("unknown configuration '{s}' (optimal, nc, np, box)"))
    }
}

/// Everything a walk can vary.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ReviewConfig {
    /// How a new disk cell's objects are retrieved: BOX or CSearch.
    pub retrieval: Retrieval,
    /// Index cache: policy name and budget in bytes.
    pub index_cache: Option<(String, usize)>,
    /// Prefetch factor k, seconds: the prefetched cell is the disk cell of the frustum
    /// moved by k·velocity, whose far-plane centre is F' = F + k·velocity (§4.2.5; the
    /// thesis gives no unit). `None` disables prefetching.
    pub prefetch_k: Option<f32>,
    /// Scale factor SF: the disk cell is SF times the frustum cell on the ground.
    pub sf: f32,
    /// Object buffer budget, bytes.
    pub memory_budget: usize,
    /// Depth of the view frustum, metres (the thesis: 1 km).
    pub far: f32,
    /// Record the index cache's access trace (for replaying other policies and sizes).
    pub record_trace: bool,
    /// Play the path's clock this many times faster than real time, so that the
    /// prefetch thread has the time a viewer would give it (scaled down: a speed-up
    /// only handicaps prefetching). `None` runs frames back to back, as fast as the CPU
    /// goes: prefetches then rarely finish before the viewer arrives. Walks without
    /// prefetching are never paced (nothing runs beside them), unless they never wait.
    pub pace: Option<f32>,
    /// Ours: the viewer's thread never waits on a read. When the viewer outruns its
    /// prefetch, its own search is queued on a loader thread of its own, ahead of any
    /// prefetch, and the frame draws what the buffer holds (its misses counted); the
    /// prefetch horizon grows with the loader's measured latency; a load that fails on
    /// the network is counted and asked for again, and the walk goes on. `false` is the
    /// thesis's walk: the viewer searches for itself, waiting for its reads.
    pub never_wait: bool,
}

/// The thesis's index cache (§4.4): 1 MB, with distance-priority LRU.
pub const DEFAULT_INDEX_CACHE: usize = 1 << 20;
impl ReviewConfig {
    /// The configuration `p` of §4.4 at the walks' defaults (`walk::settings`): CSearch
    /// with the index cache and prefetching for `Optimal`, less the cache (`Nc`) or
    /// prefetching (`Np`), and plain BOX with neither (`Box`).
    pub fn preset(p: Preset) -> ReviewConfig {
        let cache = Some(("dplru".to_string(), DEFAULT_INDEX_CACHE));
        let base = ReviewConfig {
            retrieval: Retrieval::CSearch,
            index_cache: cache,
            prefetch_k: Some(DEFAULT_K),
            sf: DEFAULT_SF,
            memory_budget: DEFAULT_MEMORY_BUDGET,
            far: DEFAULT_FAR,
            record_trace: false,
            pace: Some(DEFAULT_PACE),
            never_wait: false,
        };
        match p {
            Preset::Optimal => base,
            Preset::Nc => ReviewConfig {
                index_cache: None,
                ..base
            },
            Preset::Np => ReviewConfig {
                prefetch_k: None,
                ..base
            },
            Preset::Box => ReviewConfig {
                retrieval: Retrieval::Box,
                index_cache: None,
                prefetch_k: None,
                ..base
            },
        }
    }

    pub(crate) fn validate(&self) -> Result<()> {
        check_sf(self.sf)?;
        if let Some(k) = self.prefetch_k {
            check_k(k)?;
            if self.retrieval == Retrieval::Box {
                return Err(Error::Invalid(
                    "BOX retrieval has no prefetching (the thesis's BOX has no optimisation): leave k unset".into(),
                ));
            }
        }
        check_far(self.far)?;
        if let Some(p) = self.pace {
            check_pace(p)?;
        }
        check_budget(self.memory_budget)
    }
}

/// One frame's figures. Times in milliseconds.
#[derive(Clone, Debug, Default, serde::Serialize)]
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
    /// Every frame's figures, in order.
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
        super::frame_csv::table(FrameStats::CSV_HEADER, &self.frames, FrameStats::csv_row)
    }
}

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
    super::mode::review::walk_each(
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
    super::mode::review::walk_live(db, cfg, lods, progress, viewer)
}

/// Searches run along a walk, by where their results went.
#[derive(Clone, Debug, Default)]
pub(crate) struct Counts {
    pub sync: usize,
    pub adopted: usize,
    pub stale: usize,
    /// Searches the viewer queued on the loader (never-wait walks).
    pub queued: usize,
    /// Loads that failed on the network, and the last error.
    pub failed: usize,
    pub last_failure: Option<String>,
    /// Index and mesh pages read by frame 0's own query (before any prefetch started).
    pub initial_load_pages: (u64, u64),
}
