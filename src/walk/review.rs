//! The REVIEW walkthrough (Shou 2002 §4.1–4.4), headless: a camera path in, per-frame
//! figures out.
//!
//! Each frame: the frustum cell (the box around the view frustum) is tested against
//! the disk cell; when it leaves, a new disk cell — the frustum cell scaled by SF on
//! the ground, centred on it — is queried with BOX or CSearch, and the meshes it
//! returns are loaded into the object buffer (evicting by Fig. 4.8 when over budget).
//! The buffer is then culled against the frustum (ViewCulling, Fig. 4.15) and the
//! drawn objects' triangles gathered. With prefetching, a background thread queries
//! the cell predicted at F' = F + k·velocity (F: centre of the far clip plane, §4.2.5)
//! before the viewer gets there; index pages go through the index cache when one is
//! configured. The four configurations of §4.4 are presets.
//!
//! Departures, named: a prefetch is started when the frustum cell, grown by one
//! second of motion, would leave the disk cell (the thesis says "when approaching the
//! boundary"); a prefetched result is used only if no eviction happened since it was
//! asked for (an eviction restarts the CSearch history, so an older complement could
//! miss objects); BOX reloads every object of its cell (the thesis's BOX has "no
//! optimization").

use std::sync::mpsc;
use std::time::Instant;

use glam::Vec3;
use rstar::{primitives::GeomWithData, primitives::Rectangle, RTree as RStar, RTreeObject, AABB};

use super::buffer::{mesh_bytes, Loaded, ObjectBuffer};
use super::cells::{contains_ground, scaled_cell};
use super::motion::CameraPath;
use crate::cache::{policy_by_name, BufferPool, CacheStats, Trace};
use crate::database::Database;
use crate::error::{Error, Result};
use crate::geom::{Aabb, Camera, Frustum};
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
    /// Prefetch factor k; `None` disables prefetching.
    pub prefetch_k: Option<f32>,
    /// Scale factor SF: the disk cell is SF times the frustum cell on the ground.
    pub sf: f32,
    /// Object buffer budget, bytes.
    pub memory_budget: usize,
    /// Depth of the view frustum, metres (the thesis: 1 km).
    pub far: f32,
    /// Record the index cache's access trace (for replaying other policies and sizes).
    pub record_trace: bool,
}

/// The thesis's defaults (§4.4): index cache 1 MB with distance-priority LRU, k = 0.8.
pub const DEFAULT_INDEX_CACHE: usize = 1 << 20;
pub const DEFAULT_K: f32 = 0.8;
pub const DEFAULT_SF: f32 = 1.5;
pub const DEFAULT_FAR: f32 = 1000.0;
/// The thesis capped memory at 20 MB for objects of a few hundred bytes on disk; our
/// objects are 20 KB, so the default budget is scaled to hold a disk cell of the demo city.
pub const DEFAULT_MEMORY_BUDGET: usize = 512 << 20;

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
        };
        match p {
            Preset::Optimal => base,
            Preset::Nc => ReviewConfig { index_cache: None, ..base },
            Preset::Np => ReviewConfig { prefetch_k: None, ..base },
            Preset::Box => ReviewConfig { retrieval: Retrieval::Box, index_cache: None, prefetch_k: None, ..base },
        }
    }

    fn validate(&self) -> Result<()> {
        check_sf(self.sf)?;
        if let Some(k) = self.prefetch_k {
            check_k(k)?;
        }
        check_far(self.far)?;
        check_budget(self.memory_budget)
    }
}

/// The checks of a walk's settings, shared with the experiments that sweep them.
pub(crate) fn check_sf(sf: f32) -> Result<()> {
    if !(sf.is_finite() && sf >= 1.0) {
        return Err(Error::Invalid(format!("scale factor SF {sf} must be a number of at least 1")));
    }
    Ok(())
}

pub(crate) fn check_k(k: f32) -> Result<()> {
    if !(k.is_finite() && k >= 0.0) {
        return Err(Error::Invalid(format!("prefetch factor k {k} must be a non-negative number")));
    }
    Ok(())
}

pub(crate) fn check_far(far: f32) -> Result<()> {
    if !(far.is_finite() && far > 1.0) {
        return Err(Error::Invalid(format!("frustum depth {far} must be more than a metre")));
    }
    Ok(())
}

pub(crate) fn check_budget(bytes: usize) -> Result<()> {
    if bytes == 0 {
        return Err(Error::Invalid("the memory budget must be more than 0 bytes".into()));
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
    /// Reading and decoding meshes on this thread.
    pub load_ms: f64,
    pub cull_ms: f64,
    pub prep_ms: f64,
    pub frame_ms: f64,
    /// A disk cell was queried on this frame (by this thread or taken from a prefetch).
    pub queried: bool,
    pub prefetch_used: bool,
    pub objects_loaded: usize,
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

/// A whole walk.
#[derive(Clone, Debug, serde::Serialize)]
pub struct WalkSummary {
    pub frames: usize,
    pub mean_frame_ms: f64,
    pub max_frame_ms: f64,
    pub frame_ms_variance: f64,
    /// Frames over 50 ms, the thesis's real-time limit.
    pub frames_over_50ms: usize,
    pub queries: usize,
    pub prefetches_used: usize,
    pub index_pages: u64,
    pub mesh_pages: u64,
    /// Index pages per query.
    pub index_pages_per_query: f64,
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
            "frame,time,frame_ms,query_ms,load_ms,cull_ms,prep_ms,queried,prefetch_used,objects_loaded,objects_drawn,triangles_drawn,visual_misses,index_pages,mesh_pages,buffer_bytes,evicted,overflow\n",
        );
        for f in &self.frames {
            s.push_str(&format!(
                "{},{:.4},{:.3},{:.3},{:.3},{:.3},{:.3},{},{},{},{},{},{},{},{},{},{},{}\n",
                f.frame,
                f.time,
                f.frame_ms,
                f.query_ms,
                f.load_ms,
                f.cull_ms,
                f.prep_ms,
                f.queried as u8,
                f.prefetch_used as u8,
                f.objects_loaded,
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
    skip: std::collections::HashSet<u64>,
}

/// Walks `path` through `db` under `cfg`; `progress` is told each finished frame.
pub fn walk(db: &Database, path: &CameraPath, cfg: &ReviewConfig, mut progress: impl FnMut(usize)) -> Result<WalkReport> {
    cfg.validate()?;
    if path.poses.is_empty() {
        return Err(Error::Invalid("the camera path has no poses".into()));
    }
    let oracle = Oracle::new(db)?;
    db.reset_io();
    let pool = match &cfg.index_cache {
        Some((policy, bytes)) => Some(BufferPool::new(db.store(), *bytes, policy_by_name(policy)?)?),
        None => None,
    };
    if let (Some(p), true) = (&pool, cfg.record_trace) {
        p.set_trace(true);
    }
    let source: &(dyn PageSource + Sync) = match &pool {
        Some(p) => p,
        None => db.store(),
    };
    let frames = std::thread::scope(|scope| -> Result<Vec<FrameStats>> {
        let (req_tx, req_rx) = mpsc::channel::<Request>();
        let (res_tx, res_rx) = mpsc::channel::<Result<Fetched>>();
        if cfg.prefetch_k.is_some() {
            scope.spawn(move || {
                for req in req_rx {
                    let fetched = fetch(db, source, cfg.retrieval, &req);
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
            epoch: 0,
            in_flight: None,
            ready: None,
            req_tx: cfg.prefetch_k.map(|_| req_tx),
            res_rx,
        };
        let mut frames = Vec::with_capacity(path.poses.len());
        for i in 0..path.poses.len() {
            frames.push(state.frame(path, i)?);
            progress(i);
        }
        // Closing the request channel ends the prefetch thread.
        state.req_tx = None;
        Ok(frames)
    })?;
    let summary = summarize(&frames, pool.as_ref().map(|p| p.stats()));
    let trace = pool.as_ref().filter(|_| cfg.record_trace).map(|p| p.take_trace());
    Ok(WalkReport { config: cfg.clone(), frames, summary, trace })
}

struct Walker<'a> {
    db: &'a Database,
    source: &'a (dyn PageSource + Sync),
    cfg: &'a ReviewConfig,
    oracle: &'a Oracle,
    buffer: ObjectBuffer,
    history: History,
    disk_cell: Option<Aabb>,
    epoch: u64,
    /// The cell a prefetch is running for.
    in_flight: Option<Aabb>,
    ready: Option<Fetched>,
    req_tx: Option<mpsc::Sender<Request>>,
    res_rx: mpsc::Receiver<Result<Fetched>>,
}

impl Walker<'_> {
    fn frame(&mut self, path: &CameraPath, i: usize) -> Result<FrameStats> {
        let pose = path.poses[i];
        let camera = Camera { far: self.cfg.far, ..Camera::new(pose.position, pose.yaw, pose.pitch)? };
        let frustum = camera.frustum();
        let fcell = frustum.aabb();
        let io_before = self.db.io();
        let start = Instant::now();
        let mut stats = FrameStats { frame: i, time: pose.time, ..Default::default() };

        self.collect_prefetch(false)?;
        if self.disk_cell.is_none_or(|d| !contains_ground(&d, &fcell)) {
            stats.queried = true;
            let t = Instant::now();
            let fetched = match self.take_prefetch_for(&fcell)? {
                Some(f) => {
                    stats.prefetch_used = true;
                    stats.query_ms = t.elapsed().as_secs_f64() * 1e3;
                    f
                }
                None => {
                    let cell = self.disk_cell_around(&fcell, fcell.center());
                    let req = self.request(cell);
                    let f = fetch(self.db, self.source, self.cfg.retrieval, &req)?;
                    stats.query_ms = f.query_ms;
                    stats.load_ms = f.load_ms;
                    f
                }
            };
            stats.objects_loaded = fetched.objects.len();
            let t = Instant::now();
            self.adopt(fetched, camera.position, &mut stats);
            stats.load_ms += t.elapsed().as_secs_f64() * 1e3;
        }
        if let Some(k) = self.cfg.prefetch_k {
            self.maybe_prefetch(&camera, &fcell, path.velocity_at(i), k);
        }

        let t = Instant::now();
        let drawn: Vec<&Loaded> = self.buffer.iter().filter(|o| frustum.overlaps_aabb(&o.entry.bounds)).collect();
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
        Ok(stats)
    }

    fn disk_cell_around(&self, fcell: &Aabb, center: Vec3) -> Aabb {
        scaled_cell(&self.db.bounds(), fcell, center, self.cfg.sf)
    }

    fn request(&self, cell: Aabb) -> Request {
        let mut history = self.history.clone();
        history.filter(&cell);
        let skip = match self.cfg.retrieval {
            Retrieval::Box => Default::default(),
            Retrieval::CSearch => self.buffer.iter().map(|o| o.entry.id).collect(),
        };
        Request { cell, history: history.cells(), epoch: self.epoch, skip }
    }

    /// Takes a finished (or, if it covers the frustum cell, a running) prefetch.
    fn take_prefetch_for(&mut self, fcell: &Aabb) -> Result<Option<Fetched>> {
        if self.ready.as_ref().is_some_and(|f| !contains_ground(&f.cell, fcell) || f.epoch != self.epoch) {
            self.ready = None;
        }
        if self.ready.is_none() && self.in_flight.is_some_and(|c| contains_ground(&c, fcell)) {
            self.collect_prefetch(true)?;
        }
        Ok(self.ready.take().filter(|f| contains_ground(&f.cell, fcell) && f.epoch == self.epoch))
    }

    /// Moves a finished prefetch into `ready`; with `wait`, blocks for the running one.
    fn collect_prefetch(&mut self, wait: bool) -> Result<()> {
        if self.in_flight.is_none() {
            return Ok(());
        }
        let got = if wait {
            Some(self.res_rx.recv().map_err(|_| Error::Invalid("the prefetch thread stopped".into())))
        } else {
            match self.res_rx.try_recv() {
                Ok(r) => Some(Ok(r)),
                Err(mpsc::TryRecvError::Empty) => None,
                Err(mpsc::TryRecvError::Disconnected) => Some(Err(Error::Invalid("the prefetch thread stopped".into()))),
            }
        };
        if let Some(r) = got {
            self.in_flight = None;
            self.ready = Some(r??);
        }
        Ok(())
    }

    fn maybe_prefetch(&mut self, camera: &Camera, fcell: &Aabb, velocity: Vec3, k: f32) {
        let (Some(tx), Some(disk)) = (&self.req_tx, self.disk_cell) else { return };
        if self.in_flight.is_some() || self.ready.as_ref().is_some_and(|f| f.epoch == self.epoch) {
            return;
        }
        // Will the frustum cell leave the disk cell within a second?
        let ahead = Aabb { min: fcell.min.min(fcell.min + velocity), max: fcell.max.max(fcell.max + velocity) };
        if contains_ground(&disk, &ahead) {
            return;
        }
        let predicted = camera.far_center() + velocity * k;
        let center = Vec3::new(predicted.x, fcell.center().y, predicted.z);
        let cell = self.disk_cell_around(fcell, center);
        let req = self.request(cell);
        if tx.send(req).is_ok() {
            self.in_flight = Some(cell);
        }
    }

    fn adopt(&mut self, fetched: Fetched, eye: Vec3, stats: &mut FrameStats) {
        let cell = fetched.cell;
        if self.cfg.retrieval == Retrieval::Box {
            // BOX keeps exactly its cell.
            self.buffer = ObjectBuffer::new(self.cfg.memory_budget);
        }
        for o in fetched.objects {
            self.buffer.insert(o);
        }
        self.history.filter(&cell);
        self.history.record(cell, &fetched.retrieved);
        self.disk_cell = Some(cell);
        if self.buffer.over_budget() {
            let e = self.buffer.evict_outside(&cell, eye);
            stats.evicted = e.evicted;
            stats.overflow = e.overflow;
            // Restart the history at the cell whose objects the buffer now holds.
            let kept: Vec<ObjectEntry> = self.buffer.iter().map(|o| o.entry).collect();
            self.history.clear();
            self.history.record(cell, &kept);
            self.epoch += 1;
            self.ready = None;
        }
    }
}

/// Runs one query and loads the meshes of what it returned.
fn fetch(db: &Database, source: &(dyn PageSource + Sync), retrieval: Retrieval, req: &Request) -> Result<Fetched> {
    let t = Instant::now();
    let result: QueryResult = match retrieval {
        Retrieval::Box => db.tree().range(source, &req.cell)?,
        Retrieval::CSearch => db.tree().csearch_with(source, &req.cell, &req.history, Coverlap::default())?,
    };
    let query_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let mut objects = Vec::with_capacity(result.objects.len());
    for entry in &result.objects {
        if req.skip.contains(&entry.id) {
            continue;
        }
        let mesh = db.mesh(entry)?;
        objects.push(Loaded { entry: *entry, bytes: mesh_bytes(&mesh), mesh: std::sync::Arc::new(mesh) });
    }
    let load_ms = t.elapsed().as_secs_f64() * 1e3;
    Ok(Fetched { cell: req.cell, epoch: req.epoch, objects, retrieved: result.objects, query_ms, load_ms })
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
                    .map(|o| GeomWithData::new(Rectangle::from_corners(o.bounds.min.to_array(), o.bounds.max.to_array()), o.id))
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
                frustum.overlaps_aabb(&Aabb { min: Vec3::from(e.lower()), max: Vec3::from(e.upper()) })
            })
            .count()
    }
}

fn summarize(frames: &[FrameStats], cache: Option<CacheStats>) -> WalkSummary {
    let n = frames.len().max(1) as f64;
    let mean = frames.iter().map(|f| f.frame_ms).sum::<f64>() / n;
    let queries = frames.iter().filter(|f| f.queried).count();
    let index_pages: u64 = frames.iter().map(|f| f.index_pages).sum();
    WalkSummary {
        frames: frames.len(),
        mean_frame_ms: mean,
        max_frame_ms: frames.iter().map(|f| f.frame_ms).fold(0.0, f64::max),
        frame_ms_variance: frames.iter().map(|f| (f.frame_ms - mean).powi(2)).sum::<f64>() / n,
        frames_over_50ms: frames.iter().filter(|f| f.frame_ms > 50.0).count(),
        queries,
        prefetches_used: frames.iter().filter(|f| f.prefetch_used).count(),
        index_pages,
        mesh_pages: frames.iter().map(|f| f.mesh_pages).sum(),
        index_pages_per_query: if queries == 0 { 0.0 } else { index_pages as f64 / queries as f64 },
        visual_misses: frames.iter().map(|f| f.visual_misses as u64).sum(),
        overflow_frames: frames.iter().filter(|f| f.overflow).count(),
        peak_buffer_bytes: frames.iter().map(|f| f.buffer_bytes).max().unwrap_or(0),
        index_cache: cache,
    }
}
