//! The REVIEW mode (Shou 2002 §4.1–4.4): the retrieval of a REVIEW or BOX walk, one
//! frame at a time for the walk session. Each frame the frustum cell is tested against
//! the disk cell; when it leaves, the cell prefetched for it is taken if it holds the
//! frustum, or a new disk cell is searched (BOX or CSearch against the history) on the
//! viewer's thread; a prefetch of the cell predicted from the viewer's motion
//! (`prefetch::motion`) is started on the prefetch thread when the frustum nears the
//! disk cell's edge. The settings, figures and departures are `walk::review`'s.
//!
//! A never-wait walk ([`ReviewConfig::never_wait`], ours) has a second loader thread, the
//! viewer's own lane: where the thesis's viewer searches for itself when it outruns the
//! prefetch, this one queues the search there, ahead of whatever the prefetch lane is
//! doing, and draws what the buffer holds meanwhile. Every search asks for its meshes'
//! pages together, so that over HTTP they come in parallel. On a database with LODs the
//! viewer's lane loads each object's coarsest stored level (a few pages) and a third
//! thread then fetches the full meshes, whenever the viewer's lane is idle, and puts
//! them in place of the coarse ones. A coarse level that cannot be read for damage
//! costs its object's coarse level alone: the object comes at full detail, and is named
//! (`damage`) in the frame's figures and the walk's summary. What the loaders were still
//! reading when the walk ended is waited for, and its failures counted.

use std::collections::HashSet;
use std::sync::atomic::AtomicBool;
use std::sync::{mpsc, Mutex};
use std::time::{Duration, Instant};

use glam::Vec3;

use super::counts::Counts;
use super::loader::{fetch, Answer, Fetched, Request, SharedSets};
use crate::cache::{BufferPool, Lookahead};
use crate::database::Database;
use crate::error::{Error, Result};
use crate::geom::{Aabb, Camera, Frustum};
use crate::prefetch::motion::{MotionTrack, ViewerMotion};
use crate::rtree::{BoxIndex, History, ObjectEntry};
use crate::store::{IoStats, PageKind, PageSource};
use crate::walk::buffer::ObjectBuffer;
use crate::walk::cells::{contains_ground, scaled_cell};
use crate::walk::review::{FrameStats, Retrieval, ReviewConfig};
use crate::walk::session::{Culled, FrameAt, Mode};
use crate::walk::settings::DEFAULT_K;
use crate::walk::sink::{FrameFigures, LeftOut};
use crate::walk::threads::damage::{DamageCursor, Damaged};
use crate::walk::threads::load_order::take_part;
use crate::walk::threads::pace::wait_until_due;
use crate::walk::threads::receive::receive;
use crate::walk::threads::refining::Refined;

/// A loader thread: the prefetch's, or the viewer's own (never-wait walks only).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Lane {
    Ahead = 0,
    Now = 1,
}

/// The REVIEW mode: disk cells searched with BOX or CSearch, prefetched on a thread.
pub(super) struct Review<'a> {
    db: &'a Database,
    source: &'a (dyn PageSource + Sync),
    cfg: &'a ReviewConfig,
    /// Every object's box: the ground truth of the visual misses.
    boxes: &'a BoxIndex,
    /// The index cache, when the walk has one (for its hit rate).
    pool: Option<&'a BufferPool<'a>>,
    /// Every cell whose objects are all in the buffer (the CSearch history).
    history: History,
    disk_cell: Option<Aabb>,
    /// The latest prefetched cell: its objects are in the buffer, the viewer not yet in it.
    prefetched: Option<Aabb>,
    /// The latest cell the viewer's own lane loaded, not yet entered (never-wait walks).
    arrived: Option<Aabb>,
    /// Centre of the latest prefetch asked for from this disk cell.
    last_prediction: Option<Vec3>,
    /// Bumped by every eviction: a result asked for before it may miss objects.
    epoch: u64,
    /// The cell each lane is loading, by [`Lane`].
    in_flight: [Option<Aabb>; 2],
    /// Each lane's requests, by [`Lane`]: the prefetch's when the walk prefetches, the
    /// viewer's own when it never waits.
    lanes: [Option<mpsc::Sender<Request>>; 2],
    res_rx: mpsc::Receiver<(Lane, Answer)>,
    /// The refining thread's jobs (objects drawn coarse) and what it loaded.
    fine_tx: Option<mpsc::Sender<Vec<ObjectEntry>>>,
    refined_rx: mpsc::Receiver<Refined>,
    /// The loaders' time per search, real seconds, smoothed (never-wait walks).
    latency_s: Option<f64>,
    /// The ids in `buffer` (CSearch only: BOX reloads its whole cell by definition).
    resident: &'a Mutex<HashSet<u64>>,
    /// With a viewer that walks on past unreadable objects, those left out.
    left_out: Option<&'a Mutex<LeftOut>>,
    /// Coarse levels the loaders found damaged, and how far the frames have counted and
    /// the viewer been told of them.
    damaged: &'a Mutex<Damaged>,
    damage_seen: DamageCursor,
    counts: Counts,
    /// The viewer's poses so far, for its motion.
    track: MotionTrack,
    /// The path's clock runs this many times faster than real time (prefetching only).
    pace: Option<f32>,
    clock: Instant,
    /// The frame retrieved and not yet finished.
    pending: Option<Pending>,
}

/// Where a REVIEW mode's requests go and its answers come from: each lane's requests
/// (by [`Lane`]), the lanes' answers, the refining thread's jobs and what it loaded.
pub(super) struct Channels {
    pub(super) lanes: [Option<mpsc::Sender<Request>>; 2],
    pub(super) res_rx: mpsc::Receiver<(Lane, Answer)>,
    pub(super) fine_tx: Option<mpsc::Sender<Vec<ObjectEntry>>>,
    pub(super) refined_rx: mpsc::Receiver<Refined>,
}

impl<'a> Review<'a> {
    /// The mode at the walk's start, its index read through `source` (`pool`, when the
    /// walk has an index cache), its loaders reached through `channels`.
    pub(super) fn new(
        (db, source, cfg): (&'a Database, &'a (dyn PageSource + Sync), &'a ReviewConfig),
        boxes: &'a BoxIndex,
        pool: Option<&'a BufferPool<'a>>,
        (resident, left_out, damaged): SharedSets<'a>,
        channels: Channels,
    ) -> Review<'a> {
        Review {
            db,
            source,
            cfg,
            boxes,
            pool,
            history: History::default(),
            disk_cell: None,
            prefetched: None,
            arrived: None,
            last_prediction: None,
            epoch: 0,
            in_flight: [None, None],
            lanes: channels.lanes,
            res_rx: channels.res_rx,
            fine_tx: channels.fine_tx,
            refined_rx: channels.refined_rx,
            latency_s: None,
            resident,
            left_out,
            damaged,
            damage_seen: DamageCursor::default(),
            counts: Counts::default(),
            track: MotionTrack::default(),
            pace: cfg
                .pace
                .filter(|_| cfg.prefetch_k.is_some() || cfg.never_wait),
            clock: Instant::now(),
            pending: None,
        }
    }

    /// The walk has ended: its loaders' channels closed (which ends their threads, once
    /// they have read what they were reading), their last answers taken, and the
    /// searches' counts returned.
    pub(super) fn close(mut self, refining: bool) -> Counts {
        self.lanes = [None, None];
        self.fine_tx = None;
        self.take_last_answers(refining);
        self.counts
    }
}

/// A frame between its retrieval and its culling.
pub(super) struct Pending {
    stats: FrameStats,
    frustum: Frustum,
    fcell: Aabb,
    io_before: IoStats,
    start: Instant,
}

impl Mode for Review<'_> {
    type Frame = FrameStats;

    fn memory_budget(&self) -> usize {
        self.cfg.memory_budget
    }

    fn retrieve(&mut self, at: FrameAt<'_>, buffer: &mut ObjectBuffer) -> Result<Option<Camera>> {
        let (i, pose) = (at.index, at.pose);
        self.track.push(i, *pose)?;
        // Counted from before the wait for the clock: what the prefetch thread reads
        // meanwhile is this frame's.
        let io_before = self.db.io();
        if let (Some(speed), Some(start)) = (self.pace, self.track.start()) {
            wait_until_due(pose.time, start, speed, self.clock);
        }
        let motion = self.track.motion();
        let camera = at.camera(Some(self.cfg.far))?;
        let frustum = camera.frustum();
        let fcell = frustum.aabb();
        let start = Instant::now();
        let mut stats = FrameStats {
            frame: i,
            time: pose.time,
            ..Default::default()
        };

        self.collect_prefetch(None, camera.position, buffer, &mut stats)?;
        self.take_refined(buffer, &mut stats)?;
        if let Some(pool) = self.pool {
            pool.look_ahead(&self.lookahead(&camera, &fcell, motion));
        }
        if self.cfg.never_wait {
            self.retrieve_queued(&camera, &fcell, &mut stats);
        } else if self.disk_cell.is_none_or(|d| !contains_ground(&d, &fcell)) {
            stats.queried = true;
            if self.prefetched.is_none()
                && self.in_flight[Lane::Ahead as usize].is_some_and(|c| contains_ground(&c, &fcell))
            {
                let t = Instant::now();
                self.collect_prefetch(
                    Some(MAX_PREFETCH_WAIT),
                    camera.position,
                    buffer,
                    &mut stats,
                )?;
                stats.query_ms = t.elapsed().as_secs_f64() * 1e3;
            }
            match self.prefetched.filter(|p| contains_ground(p, &fcell)) {
                Some(cell) => {
                    stats.prefetch_used = true;
                    self.enter(cell);
                }
                None => {
                    let cell = self.disk_cell_around(&fcell, fcell.center());
                    let req = self.request(cell, false, None);
                    let f = fetch(
                        self.db,
                        self.source,
                        self.cfg.retrieval,
                        &req,
                        (self.resident, self.left_out, self.damaged),
                        &AtomicBool::new(false),
                        &mut |_| {},
                    )?;
                    self.counts.sync += 1;
                    stats.sync_query = true;
                    stats.query_ms += f.query_ms;
                    stats.load_ms += f.load_ms;
                    let t = Instant::now();
                    // The viewer is in this cell whether or not the budget holds all of it.
                    self.adopt(f, camera.position, buffer, &mut stats);
                    self.enter(cell);
                    stats.load_ms += t.elapsed().as_secs_f64() * 1e3;
                }
            }
        }
        if stats.queried && i == 0 {
            let io = self.db.io().since(&io_before);
            self.counts.initial_load_pages = (
                io.reads_of(PageKind::RtreeNode),
                io.reads_of(PageKind::Mesh),
            );
        }
        if let Some(k) = self.cfg.prefetch_k {
            self.maybe_prefetch(&camera, &fcell, motion, k);
        }

        stats.objects_buffered = buffer.len();
        self.pending = Some(Pending {
            stats,
            frustum,
            fcell,
            io_before,
            start,
        });
        Ok(Some(camera))
    }

    fn finish(&mut self, culled: &Culled<'_>, buffer: &ObjectBuffer) -> Result<FrameStats> {
        let Pending {
            mut stats,
            frustum,
            fcell,
            io_before,
            start,
        } = self
            .pending
            .take()
            .ok_or_else(|| Error::Invalid("a frame finished before it was retrieved".into()))?;
        stats.cull_ms = culled.ms;
        let t = Instant::now();
        stats.objects_drawn = culled.drawn.len();
        stats.coarse_drawn = culled.drawn.iter().filter(|o| o.level > 0).count();
        stats.triangles_drawn = culled
            .drawn
            .iter()
            .map(|o| o.mesh.indices.len() as u64 / 3)
            .sum();
        stats.prep_ms = t.elapsed().as_secs_f64() * 1e3;
        stats.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        stats.visual_misses = self
            .boxes
            .missing(&frustum, &fcell, |id| buffer.contains(id));
        let io = self.db.io().since(&io_before);
        stats.index_pages = io.reads_of(PageKind::RtreeNode);
        stats.mesh_pages = io.reads_of(PageKind::Mesh);
        stats.lod_pages = io.reads_of(PageKind::Lod);
        stats.buffer_bytes = buffer.bytes();
        stats.damaged = self.damage_seen.count_new(self.damaged);
        Ok(stats)
    }

    fn figures(&mut self, f: &FrameStats, _: &ObjectBuffer) -> FrameFigures {
        FrameFigures {
            pages: f.index_pages + f.mesh_pages,
            // The session adds what LOD selection read.
            lod_pages: 0,
            objects_buffered: f.objects_buffered,
            objects_drawn: f.objects_drawn,
            triangles: f.triangles_drawn,
            visual_misses: f.visual_misses,
            prefetch_queue: self.in_flight.iter().flatten().count(),
            cache_hit_rate: self.pool.map(|p| p.stats().hit_rate()),
            cell: self.disk_cell.map_or_else(String::new, |c| {
                format!(
                    "disk cell x {:.0}..{:.0}, z {:.0}..{:.0}",
                    c.min.x, c.max.x, c.min.z, c.max.z
                )
            }),
            walk_ms: f.frame_ms,
            damaged: self
                .left_out
                .and_then(|l| l.lock().ok().map(|mut l| l.take_untold()))
                .unwrap_or_default()
                .into_iter()
                .chain(self.damage_seen.take_untold(self.damaged))
                .collect(),
            // The session adds what reading over HTTP cost, what the stream did, and
            // what is straight ahead.
            remote: None,
            streamed: None,
            looking_at: None,
        }
    }
}

impl Review<'_> {
    fn disk_cell_around(&self, fcell: &Aabb, center: Vec3) -> Aabb {
        scaled_cell(&self.db.bounds(), fcell, center, self.cfg.sf)
    }

    /// What the index cache is told of the searches to come, from the motion so far:
    /// the disk cell a search this frame would ask for, the one a prefetch would ask
    /// for (around the predicted cell k seconds ahead, §4.2.5), then disk cells around
    /// the frusta further along the motion, soonest first; and the cells the history
    /// holds, which a complement search skips.
    fn lookahead(&self, camera: &Camera, fcell: &Aabb, motion: ViewerMotion) -> Lookahead {
        let k = self.cfg.prefetch_k.unwrap_or(DEFAULT_K);
        let mut cells = vec![self.disk_cell_around(fcell, fcell.center()), {
            let predicted = motion.predicted_cell(camera, fcell, k);
            self.disk_cell_around(&predicted, predicted.center())
        }];
        for step in 2..=LOOKAHEAD_STEPS {
            let ahead = motion.frustum_cell(camera, k * step as f32);
            cells.push(self.disk_cell_around(&ahead, ahead.center()));
        }
        Lookahead {
            cells,
            held: self.history.cells(),
        }
    }

    /// The viewer is now in `cell`, whose objects are all in the buffer.
    fn enter(&mut self, cell: Aabb) {
        self.disk_cell = Some(cell);
        self.prefetched = None;
        self.arrived = None;
        self.last_prediction = None;
    }

    fn request(&self, cell: Aabb, coarse: bool, priority: Option<(Vec3, Vec3)>) -> Request {
        let mut history = self.history.clone();
        history.filter(&cell);
        Request {
            cell,
            coarse,
            history: history.cells(),
            epoch: self.epoch,
            priority,
        }
    }

    /// Where a never-wait walk's loads start from: the camera's eye and aim.
    fn priority(&self, camera: &Camera) -> Option<(Vec3, Vec3)> {
        self.cfg
            .never_wait
            .then(|| (camera.position, camera.forward()))
    }

    /// A never-wait frame's retrieval: enter a loaded cell that holds the frustum, or
    /// queue the viewer's own search for one on its lane and draw what the buffer holds.
    fn retrieve_queued(&mut self, camera: &Camera, fcell: &Aabb, stats: &mut FrameStats) {
        if self.disk_cell.is_some_and(|d| contains_ground(&d, fcell)) {
            return;
        }
        if let Some(cell) = self.prefetched.filter(|p| contains_ground(p, fcell)) {
            stats.queried = true;
            stats.prefetch_used = true;
            self.enter(cell);
            return;
        }
        if let Some(cell) = self.arrived.filter(|p| contains_ground(p, fcell)) {
            stats.queried = true;
            self.enter(cell);
            return;
        }
        stats.outran = true;
        if self
            .in_flight
            .iter()
            .flatten()
            .any(|c| contains_ground(c, fcell))
        {
            return;
        }
        let (now, Some(tx)) = (Lane::Now as usize, &self.lanes[Lane::Now as usize]) else {
            return;
        };
        if self.in_flight[now].is_some() {
            // The lane is still loading a cell the viewer has left: take it, then ask.
            return;
        }
        let cell = self.disk_cell_around(fcell, fcell.center());
        let req = self.request(cell, self.fine_tx.is_some(), self.priority(camera));
        if tx.send(req).is_ok() {
            self.in_flight[now] = Some(cell);
            self.counts.queued += 1;
        }
    }

    /// Takes a finished prefetch into the buffer; with `wait`, blocks for the running one
    /// that long at most.
    fn collect_prefetch(
        &mut self,
        wait: Option<Duration>,
        eye: Vec3,
        buffer: &mut ObjectBuffer,
        stats: &mut FrameStats,
    ) -> Result<()> {
        let mut wait = wait;
        while self.in_flight.iter().any(Option::is_some) {
            let Some((lane, answer)) = receive(&self.res_rx, wait.take())? else {
                return Ok(());
            };
            let got = match answer {
                Answer::Part { epoch, objects } => {
                    // Counted as loaded with the whole result.
                    if epoch == self.epoch {
                        take_part(objects, buffer);
                    }
                    continue;
                }
                Answer::Done(got) => got,
            };
            self.in_flight[lane as usize] = None;
            let fetched = match got {
                Ok(f) => f,
                // The cell is asked for again when the viewer still needs it.
                Err(e) => {
                    self.go_without(e)?;
                    continue;
                }
            };
            let took = (fetched.query_ms + fetched.load_ms) / 1e3;
            self.latency_s = Some(self.latency_s.map_or(took, |l| 0.7 * l + 0.3 * took));
            if fetched.epoch != self.epoch {
                // An eviction came between: the complement it computed may miss objects.
                self.counts.stale += 1;
                continue;
            }
            let t = Instant::now();
            self.counts.adopted += 1;
            stats.prefetch_adopted = true;
            let cell = fetched.cell;
            if self.adopt(fetched, eye, buffer, stats) {
                match lane {
                    Lane::Ahead => self.prefetched = Some(cell),
                    Lane::Now => self.arrived = Some(cell),
                }
            }
            stats.load_ms += t.elapsed().as_secs_f64() * 1e3;
        }
        Ok(())
    }

    /// A load's error: a never-wait walk goes on past one that failed on the network,
    /// counting it and keeping its words for the summary; any other ends the walk.
    fn go_without(&mut self, e: Error) -> Result<()> {
        match e {
            Error::Remote { .. } if self.cfg.never_wait => {
                self.counts.failed += 1;
                self.counts.last_failure = Some(e.to_string());
                Ok(())
            }
            e => Err(e),
        }
    }

    /// What the loaders were still reading when the walk ended, taken as they finish
    /// (the walk's scope waits for them in any case): their failures counted and their
    /// damage named, so that a walk that ends while its loads still fail says so. Only
    /// once the request channels are closed (and, when `refining`, the refining lane's).
    fn take_last_answers(&mut self, refining: bool) {
        while let Ok((_, answer)) = self.res_rx.recv() {
            match answer {
                Answer::Part { .. } => {}
                Answer::Done(Ok(f)) if f.unloaded > 0 => {
                    self.counts.failed += 1;
                    self.counts.last_failure = f.failure;
                }
                Answer::Done(Ok(_)) => {}
                Answer::Done(Err(e)) => self.failed_late(e),
            }
        }
        if refining {
            while let Ok(got) = self.refined_rx.recv() {
                if let Err(e) = got {
                    self.failed_late(e);
                }
            }
        }
    }

    /// A load that failed after the walk's last frame: on the network, counted with
    /// the others; anything else, named with the damage.
    fn failed_late(&mut self, e: Error) {
        match e {
            Error::Remote { .. } | Error::RemoteChanged { .. } => {
                self.counts.failed += 1;
                self.counts.last_failure = Some(e.to_string());
            }
            e => {
                if let Ok(mut d) = self.damaged.lock() {
                    d.note_words(e.to_string());
                }
            }
        }
    }

    /// Puts the full meshes the refining thread has loaded in place of their coarse
    /// levels, where the objects are still held and the budget has room.
    fn take_refined(&mut self, buffer: &mut ObjectBuffer, stats: &mut FrameStats) -> Result<()> {
        if self.fine_tx.is_none() {
            return Ok(());
        }
        while let Some(got) = receive(&self.refined_rx, None)? {
            let finer = match got {
                Ok(f) => f,
                // The objects stay coarse.
                Err(e) => {
                    self.go_without(e)?;
                    continue;
                }
            };
            for o in finer {
                stats.refined += usize::from(buffer.refine(o));
            }
        }
        Ok(())
    }

    fn maybe_prefetch(&mut self, camera: &Camera, fcell: &Aabb, motion: ViewerMotion, k: f32) {
        let ahead_lane = Lane::Ahead as usize;
        let (Some(tx), Some(disk)) = (&self.lanes[ahead_lane], self.disk_cell) else {
            return;
        };
        if self.in_flight[ahead_lane].is_some() {
            return;
        }
        // A never-wait walk looks as far ahead as its loads take (in the path's seconds),
        // with a margin: a prefetch asked later would land after the viewer.
        let (lookahead, k) = match (self.cfg.never_wait, self.latency_s) {
            (true, Some(lat)) => {
                let path_s = (lat * f64::from(self.pace.unwrap_or(1.0)) * LATENCY_MARGIN) as f32;
                (LOOKAHEAD_S.max(path_s), k.max(path_s))
            }
            _ => (LOOKAHEAD_S, k),
        };
        // Will the frustum cell leave the disk cell (and the cell already prefetched)
        // within the look-ahead?
        let soon = motion.frustum_cell(camera, lookahead);
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
        let req = self.request(cell, false, self.priority(camera));
        if tx.send(req).is_ok() {
            self.in_flight[ahead_lane] = Some(cell);
            self.last_prediction = Some(center);
        }
    }

    /// Takes a query's objects into the buffer and its cell into the history, evicting
    /// by Fig. 4.8 when over budget. False if the budget could not hold all of the
    /// cell's objects beside the viewer's, or the network failed to bring some (then the
    /// cell is not in the history, so a later search fetches what is missing: a
    /// never-wait viewer asks for the cell again at once, as it has not arrived).
    fn adopt(
        &mut self,
        fetched: Fetched,
        eye: Vec3,
        buffer: &mut ObjectBuffer,
        stats: &mut FrameStats,
    ) -> bool {
        let cell = fetched.cell;
        if self.cfg.retrieval == Retrieval::Box {
            // BOX keeps exactly its cell.
            *buffer = ObjectBuffer::new(self.cfg.memory_budget);
        }
        stats.objects_loaded += fetched.objects.len();
        let coarse: Vec<ObjectEntry> = fetched
            .objects
            .iter()
            .filter(|o| o.level > 0)
            .map(|o| o.entry)
            .collect();
        for o in fetched.objects {
            buffer.insert(o);
        }
        if let (Some(tx), false) = (&self.fine_tx, coarse.is_empty()) {
            let _ = tx.send(coarse);
        }
        let held_whole = fetched.unloaded == 0;
        if !held_whole {
            self.counts.failed += 1;
            self.counts.last_failure = fetched.failure;
        }
        self.history.filter(&cell);
        if held_whole {
            self.history.record(cell, &fetched.retrieved);
        }
        let mut complete = held_whole;
        if buffer.over_budget() {
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
            let whole: Vec<usize> = keep.iter().map(|c| overlapping(buffer, c).len()).collect();
            let e = buffer.evict_outside_all(&keep, eye);
            stats.evicted += e.evicted;
            stats.overflow |= e.overflow;
            // Restart the history at the cells whose objects the buffer still holds in
            // full: a cell that lost some to the budget must not hide them from a search.
            self.history.clear();
            for (c, n) in keep.iter().zip(whole) {
                let kept = overlapping(buffer, c);
                if kept.len() == n && (held_whole || *c != cell) {
                    self.history.record(*c, &kept);
                } else if *c == cell {
                    complete = false;
                }
            }
            self.epoch += 1;
            if self.prefetched.is_some_and(|p| p != cell) {
                self.prefetched = None;
            }
            if self.arrived.is_some_and(|p| p != cell) {
                self.arrived = None;
            }
        }
        if self.cfg.retrieval == Retrieval::CSearch {
            if let Ok(mut ids) = self.resident.lock() {
                *ids = buffer.iter().map(|o| o.entry.id).collect();
            }
        }
        complete
    }
}

/// Predicted searches the index cache is told of, each k seconds of motion further
/// than the one before (the first two: this frame's and the next prefetch's).
const LOOKAHEAD_STEPS: usize = 4;

/// How far ahead, in seconds of the viewer's motion, a prefetch is started: when the
/// frustum would leave the disk cell within this time.
const LOOKAHEAD_S: f32 = 1.0;

/// How long the viewer waits for a prefetch under way that holds its frustum before it
/// queries for itself: a turn's prefetch can be a whole new cell, longer than a frame
/// has, where the viewer's own complement against the cells it holds is small.
const MAX_PREFETCH_WAIT: Duration = Duration::from_millis(10);

/// A never-wait walk starts a prefetch this many load times before the viewer would
/// need it: a load's time varies by the size of the cell's complement.
const LATENCY_MARGIN: f64 = 2.0;
