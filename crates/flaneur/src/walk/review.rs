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

use std::collections::HashSet;
use std::sync::{mpsc, Mutex};
use std::time::{Duration, Instant};

use glam::Vec3;
use rstar::{primitives::GeomWithData, primitives::Rectangle, RTree as RStar, RTreeObject, AABB};

use super::buffer::{mesh_bytes, Loaded, ObjectBuffer};
use super::cells::{contains_ground, scaled_cell};
use super::path::{CameraPath, Pose};
use super::sink::{FrameFigures, FrameSink, LeftOut, NoSink, Played, Viewer};
use crate::cache::{policy_by_name, BufferPool, CacheStats, Trace};
use crate::database::Database;
use crate::error::{Error, Result};
use crate::geom::{Aabb, Camera, Frustum};
use crate::prefetch::motion::{MotionTrack, ViewerMotion};
use crate::rtree::{Coverlap, History, ObjectEntry, PageSource, QueryResult};
use crate::store::PageKind;

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
    pub const ALL: [Preset; 4] = [Preset::Optimal, Preset::Nc, Preset::Np, Preset::Box];

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
    /// prefetching are never paced (nothing runs beside them).
    pub pace: Option<f32>,
}

/// The thesis's defaults (§4.4): index cache 1 MB with distance-priority LRU, k = 0.8.
pub const DEFAULT_INDEX_CACHE: usize = 1 << 20;
pub const DEFAULT_K: f32 = 0.8;
/// SF: the thesis does not give its default. 1.2 is one of the sizes of its Table 4.2;
/// on the demo city's pattern table (`flaneur bench patterns`) it gave Optimal 4-14 % of
/// BOX's disk I/Os per query, where 1.5 gave a normal walk 24 % and a slow one no query
/// after the first in a minute, while a cell still holds the frustum for 100 m of
/// forward motion.
pub const DEFAULT_SF: f32 = 1.2;
pub const DEFAULT_FAR: f32 = 1000.0;
/// Walks with prefetching play four times faster than real time by default: a
/// minute's path in 15 s, the prefetch thread getting a quarter of a viewer's time.
pub const DEFAULT_PACE: f32 = 4.0;
/// The thesis capped memory at 20 MB for objects of a few hundred bytes on disk; our
/// objects are 20 KB, so the default budget is scaled to hold a disk cell of the demo city.
pub const DEFAULT_MEMORY_BUDGET: usize = 256 << 20;

impl ReviewConfig {
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

    fn validate(&self) -> Result<()> {
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

/// A playback speed must be a positive factor of real time.
pub fn check_pace(pace: f32) -> Result<()> {
    if !(pace.is_finite() && pace > 0.0) {
        return Err(Error::Invalid(format!(
            "playback speed {pace} must be a positive factor of real time"
        )));
    }
    Ok(())
}

// The checks of a walk's settings, shared with the experiments that sweep them.

/// A disk cell's scale factor SF must be at least 1.
pub fn check_sf(sf: f32) -> Result<()> {
    if !(sf.is_finite() && sf >= 1.0) {
        return Err(Error::Invalid(format!(
            "scale factor SF {sf} must be a number of at least 1"
        )));
    }
    Ok(())
}

/// A prefetch factor k must be a non-negative number of seconds.
pub fn check_k(k: f32) -> Result<()> {
    if !(k.is_finite() && k >= 0.0) {
        return Err(Error::Invalid(format!(
            "prefetch factor k {k} must be a non-negative number"
        )));
    }
    Ok(())
}

/// A frustum's depth must be more than a metre.
pub fn check_far(far: f32) -> Result<()> {
    if !(far.is_finite() && far > 1.0) {
        return Err(Error::Invalid(format!(
            "frustum depth {far} must be more than a metre"
        )));
    }
    Ok(())
}

/// A memory budget must be more than 0 bytes.
pub fn check_budget(bytes: usize) -> Result<()> {
    if bytes == 0 {
        return Err(Error::Invalid(
            "the memory budget must be more than 0 bytes".into(),
        ));
    }
    Ok(())
}

/// One frame's figures. Times in milliseconds.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct FrameStats {
    pub frame: usize,
    pub time: f64,
    /// Waiting for a query (synchronous, or a prefetch not yet done).
    pub query_ms: f64,
    /// Reading and decoding meshes on this thread, and adding them to the buffer.
    pub load_ms: f64,
    pub cull_ms: f64,
    pub prep_ms: f64,
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
    pub objects_drawn: usize,
    pub triangles_drawn: u64,
    /// Objects in the view frustum that were not in memory.
    pub visual_misses: usize,
    /// Physical page reads this frame (index and meshes, both threads).
    pub index_pages: u64,
    pub mesh_pages: u64,
    pub buffer_bytes: usize,
    pub evicted: usize,
    /// The latest cell's own objects did not fit the budget.
    pub overflow: bool,
}

/// A whole walk. Frame 0 loads the first disk cell from nothing (the thesis's session
/// start); its time is reported as `initial_load_ms` and left out of the frame-time
/// figures, which describe the walk itself.
#[derive(Clone, Debug, serde::Serialize)]
pub struct WalkSummary {
    pub frames: usize,
    /// Frame 0: the first disk cell, loaded cold.
    pub initial_load_ms: f64,
    /// Index and mesh pages that frame 0's query read: the cold load alone, without what
    /// a prefetch started in that frame read beside it.
    pub initial_load_pages: (u64, u64),
    /// Mean, maximum and variance of the frame time, frames 1 onwards.
    pub mean_frame_ms: f64,
    pub max_frame_ms: f64,
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
    pub index_pages: u64,
    pub mesh_pages: u64,
    /// Index pages per query.
    pub index_pages_per_query: f64,
    /// Index and mesh pages per query: the thesis's "disk I/Os per query".
    pub io_per_query: f64,
    pub visual_misses: u64,
    pub overflow_frames: usize,
    pub peak_buffer_bytes: usize,
    pub index_cache: Option<CacheStats>,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct WalkReport {
    pub config: ReviewConfig,
    pub frames: Vec<FrameStats>,
    pub summary: WalkSummary,
    /// The index cache's accesses, when `record_trace` was set and a cache was used.
    #[serde(skip)]
    pub trace: Option<Trace>,
}

impl WalkReport {
    /// One row per frame.
    pub fn to_csv(&self) -> String {
        let mut s = String::from(
            "frame,time,frame_ms,query_ms,load_ms,cull_ms,prep_ms,queried,sync_query,prefetch_used,prefetch_adopted,objects_loaded,objects_buffered,objects_drawn,triangles_drawn,visual_misses,index_pages,mesh_pages,buffer_bytes,evicted,overflow\n",
        );
        for f in &self.frames {
            s.push_str(&format!(
                "{},{:.4},{:.3},{:.3},{:.3},{:.3},{:.3},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
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
                f.overflow as u8
            ));
        }
        s
    }
}

/// A query's result with its meshes, loaded on the thread that ran it.
struct Fetched {
    cell: Aabb,
    epoch: u64,
    objects: Vec<Loaded>,
    /// What CSearch retrieved for the cell (for the history).
    retrieved: Vec<ObjectEntry>,
    /// Time in the index, and reading meshes, on the thread that fetched.
    query_ms: f64,
    load_ms: f64,
}

struct Request {
    cell: Aabb,
    history: Vec<Aabb>,
    epoch: u64,
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
    walk_live(db, cfg, progress, &mut Played { path, sink })
}

/// [`walk_into`] with the poses coming from `viewer` frame by frame (a person at a
/// window), until it has no more. Poses must come in time order, as a path's do.
pub fn walk_live(
    db: &Database,
    cfg: &ReviewConfig,
    mut progress: impl FnMut(usize),
    viewer: &mut dyn Viewer,
) -> Result<WalkReport> {
    cfg.validate()?;
    let mut track = MotionTrack::default();
    let oracle = Oracle::new(db)?;
    db.reset_io();
    let pool = match &cfg.index_cache {
        Some((policy, bytes)) => Some(BufferPool::new(
            db.store(),
            *bytes,
            policy_by_name(policy)?,
        )?),
        None => None,
    };
    if let (Some(p), true) = (&pool, cfg.record_trace) {
        p.set_trace(true);
    }
    let source: &(dyn PageSource + Sync) = match &pool {
        Some(p) => p,
        None => db.store(),
    };
    // The ids in the object buffer, which no fetch loads again — read when the meshes
    // are, so a prefetch asked for before the viewer's own query skips what it loaded.
    let resident = Mutex::new(HashSet::new());
    let resident = &resident;
    // Objects whose meshes could not be read, when the viewer walks on without them;
    // shared with the prefetch thread, and told of from here (a prefetch that finds
    // one may be dropped as stale).
    let left_out = viewer
        .skips_damaged()
        .then(|| Mutex::new(LeftOut::default()));
    let left_out = left_out.as_ref();
    let (frames, counts) = std::thread::scope(|scope| -> Result<(Vec<FrameStats>, Counts)> {
        let (req_tx, req_rx) = mpsc::channel::<Request>();
        let (res_tx, res_rx) = mpsc::channel::<Result<Fetched>>();
        if cfg.prefetch_k.is_some() {
            scope.spawn(move || {
                for req in req_rx {
                    let fetched = fetch(db, source, cfg.retrieval, &req, (resident, left_out));
                    if res_tx.send(fetched).is_err() {
                        break;
                    }
                }
            });
        } else {
            drop(req_rx);
            drop(res_tx);
        }
        let mut state = Walker {
            db,
            source,
            cfg,
            oracle: &oracle,
            buffer: ObjectBuffer::new(cfg.memory_budget),
            history: History::default(),
            disk_cell: None,
            prefetched: None,
            last_prediction: None,
            epoch: 0,
            in_flight: None,
            req_tx: cfg.prefetch_k.map(|_| req_tx),
            res_rx,
            resident,
            left_out,
            counts: Counts::default(),
        };
        let mut frames = Vec::new();
        let pace = cfg.pace.filter(|_| cfg.prefetch_k.is_some());
        let clock = Instant::now();
        for i in 0.. {
            let Some(pose) = viewer.next_pose(i)? else {
                break;
            };
            track.push(i, pose)?;
            if let (Some(speed), Some(start)) = (pace, track.start()) {
                let due = std::time::Duration::from_secs_f64(
                    ((pose.time - start) / speed as f64).max(0.0),
                );
                if let Some(wait) = due.checked_sub(clock.elapsed()) {
                    std::thread::sleep(wait);
                }
            }
            let f = state.frame(&pose, track.motion(), i, viewer)?;
            viewer.figures(&FrameFigures {
                pages: f.index_pages + f.mesh_pages,
                objects_buffered: f.objects_buffered,
                objects_drawn: f.objects_drawn,
                triangles: f.triangles_drawn,
                visual_misses: f.visual_misses,
                prefetch_queue: state.in_flight.is_some() as usize,
                cache_hit_rate: pool.as_ref().map(|p| p.stats().hit_rate()),
                cell: state.disk_cell.map_or_else(String::new, |c| {
                    format!(
                        "disk cell x {:.0}..{:.0}, z {:.0}..{:.0}",
                        c.min.x, c.max.x, c.min.z, c.max.z
                    )
                }),
                walk_ms: f.frame_ms,
                damaged: left_out
                    .and_then(|l| l.lock().ok().map(|mut l| l.take_untold()))
                    .unwrap_or_default(),
            });
            frames.push(f);
            progress(i);
        }
        if frames.is_empty() {
            return Err(Error::Invalid("the walk had no poses".into()));
        }
        // Closing the request channel ends the prefetch thread.
        state.req_tx = None;
        Ok((frames, state.counts))
    })?;
    let summary = summarize(&frames, counts, pool.as_ref().map(|p| p.stats()));
    let trace = pool
        .as_ref()
        .filter(|_| cfg.record_trace)
        .map(|p| p.take_trace());
    Ok(WalkReport {
        config: cfg.clone(),
        frames,
        summary,
        trace,
    })
}

/// Searches run along a walk, by where their results went.
#[derive(Clone, Copy, Debug, Default)]
struct Counts {
    sync: usize,
    adopted: usize,
    stale: usize,
    /// Index and mesh pages read by frame 0's own query (before any prefetch started).
    initial_load_pages: (u64, u64),
}

struct Walker<'a> {
    db: &'a Database,
    source: &'a (dyn PageSource + Sync),
    cfg: &'a ReviewConfig,
    oracle: &'a Oracle,
    buffer: ObjectBuffer,
    /// Every cell whose objects are all in the buffer (the CSearch history).
    history: History,
    disk_cell: Option<Aabb>,
    /// The latest prefetched cell: its objects are in the buffer, the viewer not yet in it.
    prefetched: Option<Aabb>,
    /// Centre of the latest prefetch asked for from this disk cell.
    last_prediction: Option<Vec3>,
    /// Bumped by every eviction: a result asked for before it may miss objects.
    epoch: u64,
    /// The cell a prefetch is running for.
    in_flight: Option<Aabb>,
    req_tx: Option<mpsc::Sender<Request>>,
    res_rx: mpsc::Receiver<Result<Fetched>>,
    /// The ids in `buffer` (CSearch only: BOX reloads its whole cell by definition).
    resident: &'a Mutex<HashSet<u64>>,
    /// With a viewer that walks on past unreadable objects, those left out.
    left_out: Option<&'a Mutex<LeftOut>>,
    counts: Counts,
}

impl Walker<'_> {
    fn frame(
        &mut self,
        pose: &Pose,
        motion: ViewerMotion,
        i: usize,
        sink: &mut dyn FrameSink,
    ) -> Result<FrameStats> {
        let camera = Camera {
            far: self.cfg.far,
            ..Camera::new(pose.position, pose.yaw, pose.pitch)?
        };
        let frustum = camera.frustum();
        let fcell = frustum.aabb();
        let io_before = self.db.io();
        let start = Instant::now();
        let mut stats = FrameStats {
            frame: i,
            time: pose.time,
            ..Default::default()
        };

        self.collect_prefetch(None, camera.position, &mut stats)?;
        if self.disk_cell.is_none_or(|d| !contains_ground(&d, &fcell)) {
            stats.queried = true;
            if self.prefetched.is_none()
                && self.in_flight.is_some_and(|c| contains_ground(&c, &fcell))
            {
                let t = Instant::now();
                self.collect_prefetch(Some(MAX_PREFETCH_WAIT), camera.position, &mut stats)?;
                stats.query_ms = t.elapsed().as_secs_f64() * 1e3;
            }
            match self.prefetched.filter(|p| contains_ground(p, &fcell)) {
                Some(cell) => {
                    stats.prefetch_used = true;
                    self.enter(cell);
                }
                None => {
                    let cell = self.disk_cell_around(&fcell, fcell.center());
                    let req = self.request(cell);
                    let f = fetch(
                        self.db,
                        self.source,
                        self.cfg.retrieval,
                        &req,
                        (self.resident, self.left_out),
                    )?;
                    self.counts.sync += 1;
                    stats.sync_query = true;
                    stats.query_ms += f.query_ms;
                    stats.load_ms += f.load_ms;
                    let t = Instant::now();
                    // The viewer is in this cell whether or not the budget holds all of it.
                    self.adopt(f, camera.position, &mut stats);
                    self.enter(cell);
                    stats.load_ms += t.elapsed().as_secs_f64() * 1e3;
                }
            }
            if i == 0 {
                let io = self.db.io().since(&io_before);
                self.counts.initial_load_pages = (
                    io.reads_of(PageKind::RtreeNode),
                    io.reads_of(PageKind::Mesh),
                );
            }
        }
        if let Some(k) = self.cfg.prefetch_k {
            self.maybe_prefetch(&camera, &fcell, motion, k);
        }

        stats.objects_buffered = self.buffer.len();
        let t = Instant::now();
        let drawn: Vec<&Loaded> = self
            .buffer
            .iter()
            .filter(|o| frustum.overlaps_aabb(&o.entry.bounds))
            .collect();
        stats.cull_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        stats.objects_drawn = drawn.len();
        stats.triangles_drawn = drawn.iter().map(|o| o.mesh.indices.len() as u64 / 3).sum();
        stats.prep_ms = t.elapsed().as_secs_f64() * 1e3;
        stats.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        stats.visual_misses = self.oracle.misses(&frustum, &fcell, &self.buffer);
        let io = self.db.io().since(&io_before);
        stats.index_pages = io.reads_of(PageKind::RtreeNode);
        stats.mesh_pages = io.reads_of(PageKind::Mesh);
        stats.buffer_bytes = self.buffer.bytes();
        sink.frame(i, &camera, &self.buffer, &drawn)?;
        Ok(stats)
    }

    fn disk_cell_around(&self, fcell: &Aabb, center: Vec3) -> Aabb {
        scaled_cell(&self.db.bounds(), fcell, center, self.cfg.sf)
    }

    /// The viewer is now in `cell`, whose objects are all in the buffer.
    fn enter(&mut self, cell: Aabb) {
        self.disk_cell = Some(cell);
        self.prefetched = None;
        self.last_prediction = None;
    }

    fn request(&self, cell: Aabb) -> Request {
        let mut history = self.history.clone();
        history.filter(&cell);
        Request {
            cell,
            history: history.cells(),
            epoch: self.epoch,
        }
    }

    /// Takes a finished prefetch into the buffer; with `wait`, blocks for the running one
    /// that long at most.
    fn collect_prefetch(
        &mut self,
        wait: Option<Duration>,
        eye: Vec3,
        stats: &mut FrameStats,
    ) -> Result<()> {
        if self.in_flight.is_none() {
            return Ok(());
        }
        let stopped = || Error::Invalid("the prefetch thread stopped".into());
        let got = match wait {
            Some(limit) => match self.res_rx.recv_timeout(limit) {
                Ok(r) => r,
                Err(mpsc::RecvTimeoutError::Timeout) => return Ok(()),
                Err(mpsc::RecvTimeoutError::Disconnected) => return Err(stopped()),
            },
            None => match self.res_rx.try_recv() {
                Ok(r) => r,
                Err(mpsc::TryRecvError::Empty) => return Ok(()),
                Err(mpsc::TryRecvError::Disconnected) => return Err(stopped()),
            },
        };
        self.in_flight = None;
        let fetched = got?;
        if fetched.epoch != self.epoch {
            // An eviction came between: the complement it computed may miss objects.
            self.counts.stale += 1;
            return Ok(());
        }
        let t = Instant::now();
        self.counts.adopted += 1;
        stats.prefetch_adopted = true;
        let cell = fetched.cell;
        if self.adopt(fetched, eye, stats) {
            self.prefetched = Some(cell);
        }
        stats.load_ms += t.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }

    fn maybe_prefetch(&mut self, camera: &Camera, fcell: &Aabb, motion: ViewerMotion, k: f32) {
        let (Some(tx), Some(disk)) = (&self.req_tx, self.disk_cell) else {
            return;
        };
        if self.in_flight.is_some() {
            return;
        }
        // Will the frustum cell leave the disk cell (and the cell already prefetched)
        // within the look-ahead?
        let soon = motion.frustum_cell(camera, LOOKAHEAD_S);
        let ahead = fcell.union(&soon);
        if contains_ground(&disk, &ahead)
            || self.prefetched.is_some_and(|p| contains_ground(&p, &ahead))
        {
            return;
        }
        // The cell must hold the frustum from when the viewer leaves the disk cell (any
        // time within the look-ahead) to k seconds on: a cell around the prediction alone
        // would be missed whenever k·velocity passes the cell's margin.
        let predicted = motion.predicted_cell(camera, fcell, k);
        let center = predicted.center();
        let cell = self.disk_cell_around(&predicted, center);
        // Ask again from the same disk cell only once the prediction has moved by a
        // quarter of the cell: that bounds the prefetches per cell.
        if let Some(last) = self.last_prediction {
            let quarter = cell.extent() * 0.25;
            if (center.x - last.x).abs() < quarter.x && (center.z - last.z).abs() < quarter.z {
                return;
            }
        }
        let req = self.request(cell);
        if tx.send(req).is_ok() {
            self.in_flight = Some(cell);
            self.last_prediction = Some(center);
        }
    }

    /// Takes a query's objects into the buffer and its cell into the history, evicting
    /// by Fig. 4.8 when over budget. False if the budget could not hold all of the
    /// cell's objects beside the viewer's (then the cell is not in the history, so a
    /// later search fetches what was dropped).
    fn adopt(&mut self, fetched: Fetched, eye: Vec3, stats: &mut FrameStats) -> bool {
        let cell = fetched.cell;
        if self.cfg.retrieval == Retrieval::Box {
            // BOX keeps exactly its cell.
            self.buffer = ObjectBuffer::new(self.cfg.memory_budget);
        }
        stats.objects_loaded += fetched.objects.len();
        for o in fetched.objects {
            self.buffer.insert(o);
        }
        self.history.filter(&cell);
        self.history.record(cell, &fetched.retrieved);
        let mut complete = true;
        if self.buffer.over_budget() {
            // Keep the cell the viewer is in as well as the new one (a prefetch lands
            // before the viewer gets there).
            let keep: Vec<Aabb> = self
                .disk_cell
                .filter(|d| *d != cell)
                .into_iter()
                .chain([cell])
                .collect();
            let overlapping = |b: &ObjectBuffer, c: &Aabb| -> Vec<ObjectEntry> {
                b.iter()
                    .map(|o| o.entry)
                    .filter(|o| o.bounds.overlaps(c))
                    .collect()
            };
            let whole: Vec<usize> = keep
                .iter()
                .map(|c| overlapping(&self.buffer, c).len())
                .collect();
            let e = self.buffer.evict_outside_all(&keep, eye);
            stats.evicted += e.evicted;
            stats.overflow |= e.overflow;
            // Restart the history at the cells whose objects the buffer still holds in
            // full: a cell that lost some to the budget must not hide them from a search.
            self.history.clear();
            for (c, n) in keep.iter().zip(whole) {
                let kept = overlapping(&self.buffer, c);
                if kept.len() == n {
                    self.history.record(*c, &kept);
                } else if *c == cell {
                    complete = false;
                }
            }
            self.epoch += 1;
            if self.prefetched.is_some_and(|p| p != cell) {
                self.prefetched = None;
            }
        }
        if self.cfg.retrieval == Retrieval::CSearch {
            if let Ok(mut ids) = self.resident.lock() {
                *ids = self.buffer.iter().map(|o| o.entry.id).collect();
            }
        }
        complete
    }
}

/// How far ahead, in seconds of the viewer's motion, a prefetch is started: when the
/// frustum would leave the disk cell within this time.
const LOOKAHEAD_S: f32 = 1.0;

/// How long the viewer waits for a prefetch under way that holds its frustum before it
/// queries for itself: a turn's prefetch can be a whole new cell, longer than a frame
/// has, where the viewer's own complement against the cells it holds is small.
const MAX_PREFETCH_WAIT: Duration = Duration::from_millis(10);

/// Runs one query and loads the meshes of what it returned.
fn fetch(
    db: &Database,
    source: &(dyn PageSource + Sync),
    retrieval: Retrieval,
    req: &Request,
    (resident, left_out): (&Mutex<HashSet<u64>>, Option<&Mutex<LeftOut>>),
) -> Result<Fetched> {
    let t = Instant::now();
    let result: QueryResult = match retrieval {
        Retrieval::Box => db.tree().range(source, &req.cell)?,
        Retrieval::CSearch => {
            db.tree()
                .csearch_with(source, &req.cell, &req.history, Coverlap::default())?
        }
    };
    let query_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let mut objects = Vec::with_capacity(result.objects.len());
    for entry in &result.objects {
        if resident.lock().is_ok_and(|r| r.contains(&entry.id))
            || left_out.is_some_and(|l| l.lock().is_ok_and(|l| l.contains(entry.id)))
        {
            continue;
        }
        let mesh = match (db.mesh(entry), left_out) {
            (Ok(m), _) => m,
            (Err(e), Some(l)) => {
                if let Ok(mut l) = l.lock() {
                    l.leave_out(entry.id, &e);
                }
                continue;
            }
            (Err(e), None) => return Err(e),
        };
        objects.push(Loaded {
            entry: *entry,
            bytes: mesh_bytes(&mesh),
            mesh: std::sync::Arc::new(mesh),
        });
    }
    let load_ms = t.elapsed().as_secs_f64() * 1e3;
    Ok(Fetched {
        cell: req.cell,
        epoch: req.epoch,
        objects,
        retrieved: result.objects,
        query_ms,
        load_ms,
    })
}

/// Ground truth for visual misses: every object's box, in memory, outside the counted
/// store reads.
struct Oracle {
    tree: RStar<GeomWithData<Rectangle<[f32; 3]>, u64>>,
}

impl Oracle {
    fn new(db: &Database) -> Result<Oracle> {
        let all = db.range(&db.bounds())?.objects;
        Ok(Oracle {
            tree: RStar::bulk_load(
                all.iter()
                    .map(|o| {
                        GeomWithData::new(
                            Rectangle::from_corners(
                                o.bounds.min.to_array(),
                                o.bounds.max.to_array(),
                            ),
                            o.id,
                        )
                    })
                    .collect(),
            ),
        })
    }

    fn misses(&self, frustum: &Frustum, fcell: &Aabb, buffer: &ObjectBuffer) -> usize {
        let q = AABB::from_corners(fcell.min.to_array(), fcell.max.to_array());
        self.tree
            .locate_in_envelope_intersecting(&q)
            .filter(|g| !buffer.contains(g.data))
            .filter(|g| {
                let e = g.geom().envelope();
                frustum.overlaps_aabb(&Aabb {
                    min: Vec3::from(e.lower()),
                    max: Vec3::from(e.upper()),
                })
            })
            .count()
    }
}

fn summarize(frames: &[FrameStats], counts: Counts, cache: Option<CacheStats>) -> WalkSummary {
    let walk = frames.get(1..).unwrap_or_default();
    let n = walk.len().max(1) as f64;
    let mean = walk.iter().map(|f| f.frame_ms).sum::<f64>() / n;
    let queries = counts.sync + counts.adopted + counts.stale;
    let index_pages: u64 = frames.iter().map(|f| f.index_pages).sum();
    let mesh_pages: u64 = frames.iter().map(|f| f.mesh_pages).sum();
    let per_query = |pages: u64| {
        if queries == 0 {
            0.0
        } else {
            pages as f64 / queries as f64
        }
    };
    WalkSummary {
        frames: frames.len(),
        initial_load_ms: frames.first().map_or(0.0, |f| f.frame_ms),
        initial_load_pages: counts.initial_load_pages,
        mean_frame_ms: mean,
        max_frame_ms: walk.iter().map(|f| f.frame_ms).fold(0.0, f64::max),
        frame_ms_variance: walk
            .iter()
            .map(|f| (f.frame_ms - mean).powi(2))
            .sum::<f64>()
            / n,
        frames_over_50ms: walk.iter().filter(|f| f.frame_ms > 50.0).count(),
        queries,
        sync_queries: counts.sync,
        prefetches_adopted: counts.adopted,
        prefetches_stale: counts.stale,
        cell_changes: frames.iter().filter(|f| f.queried).count(),
        prefetches_used: frames.iter().filter(|f| f.prefetch_used).count(),
        index_pages,
        mesh_pages,
        index_pages_per_query: per_query(index_pages),
        io_per_query: per_query(index_pages + mesh_pages),
        visual_misses: frames.iter().map(|f| f.visual_misses as u64).sum(),
        overflow_frames: frames.iter().filter(|f| f.overflow).count(),
        peak_buffer_bytes: frames.iter().map(|f| f.buffer_bytes).max().unwrap_or(0),
        index_cache: cache,
    }
}
