//! The VISUAL mode (Shou 2002 §5.8.5): the retrieval of a VISUAL walk, one frame at a
//! time for the walk session. Each frame the eye's viewcell is found; on a change of
//! cell the HDoV-tree is searched (or a prefetch's finds taken) and the finds brought
//! into the buffer by delta; outside every cell, REVIEW's BOX query of a disk cell
//! instead. The next-cell prefetch (ours) runs on a thread of its own. The settings,
//! figures and departures are `walk::visual`'s.

use std::collections::{HashMap, HashSet};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use super::pace::wait_until_due;
use super::visual_never_wait::NeverWaitRun;
use crate::cache::{policy_by_name, BufferPool, CacheStats};
use crate::database::Database;
use crate::error::{Error, Result};
use crate::geom::DEFAULT_FOV;
use crate::geom::{Aabb, Camera};
use crate::hdov::{Found, Loader, NodeErrors, Scheme, ScreenRule, Selection};
use crate::prefetch::motion::MotionTrack;
use crate::rtree::ObjectEntry;
use crate::scene::Mesh;
use crate::store::{IoStats, PageKind};
use crate::walk::buffer::{Loaded, ObjectBuffer, GROUP_ID};
use crate::walk::cells::{contains_ground, scaled_cell, viewcell_holding};
use crate::walk::mode::receive::receive;
use crate::walk::session::{self, Culled, Drawable, FrameAt, Mode};
use crate::walk::sink::{FrameFigures, LeftOut, Viewer};
use crate::walk::visual::{faint_tau_scale, screen_test, VisualConfig, VisualFrame};
use crate::walk::walk_lods::WalkLods;

/// How long the viewer waits for a prefetch of the cell it enters before it searches
/// for itself, as REVIEW's does.
const MAX_PREFETCH_WAIT: Duration = Duration::from_millis(10);

/// One find of a search (or of the fallback's query), at the level it deserves.
#[derive(Clone, Debug)]
pub(super) struct Piece {
    /// Its id in the buffer: the object's, or the node's with [`GROUP_ID`].
    pub key: u64,
    pub level: usize,
    pub found: Found,
}

/// A prefetched cell's finds, and the meshes the thread read for them.
struct Prefetched {
    cell: u32,
    pieces: Vec<Piece>,
    loaded: Vec<Loaded>,
    /// Finds it could not read (a viewer that walks on), with why.
    failed: Vec<(u64, Error)>,
}

/// What the prefetch thread is asked: a cell, and what the buffer held at which level.
struct Request {
    cell: u32,
    held: HashMap<u64, usize>,
}

/// A VISUAL walk under `cfg` with the poses coming from `viewer`: the walk session with
/// the VISUAL mode. Each frame's figures go to `each` as the frame ends (a never-wait
/// walk's at its end, their misses counted then); the node cache's figures are returned.
pub(crate) fn walk_live<'db>(
    db: &'db Database,
    cfg: &VisualConfig,
    lods: &mut WalkLods<'db>,
    progress: impl FnMut(usize),
    viewer: &mut dyn Viewer,
    mut each: impl FnMut(VisualFrame) -> Result<()>,
) -> Result<(Option<CacheStats>, NeverWaitRun)> {
    cfg.validate()?;
    let head = db.hdov_head()?;
    let scheme = match cfg.scheme {
        Some(s) if head.schemes.iter().any(|t| t.0 == s) => s,
        Some(s) => {
            return Err(Error::Invalid(format!(
                "{} has no {} scheme of its HDoV-tree (rebuild with --hdov {})",
                db.store().path().display(),
                s.name(),
                s.name()
            )))
        }
        None => head.smallest_scheme()?,
    };
    let pool = match &cfg.node_cache {
        Some((policy, bytes)) => Some(BufferPool::new(
            db.store(),
            *bytes,
            policy_by_name(policy)?,
        )?),
        None => None,
    };
    let tolerant = viewer.skips_damaged();
    let search = Searcher {
        db,
        eta: cfg.eta,
        scheme,
        pool: pool.as_ref(),
        tolerant,
        dov_tau: cfg.dov_tau,
        finer_of: cfg.finer_of(),
        selection: cfg.selection,
        tau: cfg.tau,
        faint_tau: cfg.faint_tau,
        errors: NodeErrors::default(),
    };
    let search = &search;
    db.reset_io();
    let mut walked = 0;
    let mut counted = |f: VisualFrame| {
        walked += 1;
        each(f)
    };
    if cfg.never_wait {
        let run = super::visual_never_wait::walk_live(
            db,
            cfg,
            search,
            lods,
            progress,
            viewer,
            &mut counted,
        )?;
        if walked == 0 {
            return Err(Error::Invalid("the walk had no poses".into()));
        }
        return Ok((pool.as_ref().map(BufferPool::stats), run));
    }
    std::thread::scope(|scope| -> Result<()> {
        let (req_tx, req_rx) = mpsc::channel::<Request>();
        let (res_tx, res_rx) = mpsc::channel::<Result<Prefetched>>();
        if cfg.prefetch_k.is_some() {
            scope.spawn(move || {
                let mut loader = db.hdov_loader();
                for req in req_rx {
                    let got = search.prefetch(&mut loader, &req);
                    if res_tx.send(got).is_err() {
                        break;
                    }
                }
            });
        } else {
            drop(req_rx);
            drop(res_tx);
        }
        let mut mode = Visual {
            db,
            cfg,
            search,
            loader: db.hdov_loader(),
            current: None,
            drawable: Vec::new(),
            found: (0, 0),
            fallback_cell: None,
            prefetched: None,
            in_flight: None,
            asked: None,
            req_tx: cfg.prefetch_k.map(|_| req_tx),
            res_rx,
            left_out: tolerant.then(LeftOut::default),
            track: MotionTrack::default(),
            clock: Instant::now(),
            pending: None,
        };
        let walk = session::run_each(&mut mode, viewer, lods, progress, &mut counted);
        mode.req_tx = None;
        walk
    })?;
    if walked == 0 {
        return Err(Error::Invalid("the walk had no poses".into()));
    }
    Ok((
        pool.as_ref().map(BufferPool::stats),
        NeverWaitRun::default(),
    ))
}

/// A cell's finds at their levels, those whose level could not be read (with why),
/// and the search's time, ms.
pub(super) struct Finds {
    pub pieces: Vec<Piece>,
    pub failed: Vec<(u64, Error)>,
    pub ms: f64,
}

/// What both threads search with.
pub(super) struct Searcher<'a> {
    pub db: &'a Database,
    pub eta: f32,
    pub scheme: Scheme,
    pub pool: Option<&'a BufferPool<'a>>,
    pub tolerant: bool,
    /// Whether objects carry their DoV to LOD selection.
    pub dov_tau: bool,
    /// Whether LOD selection draws objects at the finer of the level they were loaded
    /// at (eq. 5.6's) and the screen-space one.
    pub finer_of: bool,
    /// The rule that picks nodes' internal LODs, and the τ the screen rule holds them to.
    pub selection: Selection,
    pub tau: f32,
    /// τ's stretch for an object of DoV at most η under the screen rule.
    pub faint_tau: f32,
    /// The nodes' internal LODs' stored errors read so far (the screen rule's).
    pub errors: NodeErrors,
}

impl Searcher<'_> {
    /// The finds of `cell`, each at the level `loader` says it deserves (those whose
    /// level could not be read left apart when tolerant; otherwise the error).
    pub(super) fn finds(&self, loader: &mut Loader<'_>, cell: u32) -> Result<Finds> {
        let t = Instant::now();
        let screen = self.screen_rule(cell)?;
        let result = self.db.hdov_search_screened(
            cell,
            self.eta,
            Some(self.scheme),
            self.pool,
            screen.as_ref(),
        )?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        loader.learn(&result.found);
        let mut pieces = Vec::with_capacity(result.found.len());
        // A node whose errors could not be read was searched past (tolerant only): its
        // objects are found instead, and the damage told.
        let mut failed: Vec<(u64, Error)> = self
            .errors
            .take_damaged()
            .into_iter()
            .map(|(node, e)| (GROUP_ID | node as u64, e))
            .collect();
        for found in result.found {
            let key = key_of(&found)?;
            match loader.level(&found) {
                Ok(level) => {
                    let level = self.screened(&found, level, screen.as_ref());
                    pieces.push(Piece { key, level, found })
                }
                Err(e) if self.tolerant => failed.push((key, e)),
                Err(e) => return Err(e),
            }
        }
        Ok(Finds { pieces, failed, ms })
    }

    /// The screen rule from `cell`, under ours; `None` under the thesis's selection.
    fn screen_rule(&self, cell: u32) -> Result<Option<ScreenRule<'_>>> {
        Ok(match self.selection {
            Selection::Thesis => None,
            Selection::Screen => Some(ScreenRule {
                test: screen_test(self.db, cell, self.tau, DEFAULT_FOV)?,
                errors: &self.errors,
                tolerant: self.tolerant,
            }),
        })
    }

    /// The level a find is read at: the loader's (eqs. 5.5–5.6), or for a node under the
    /// screen rule the finer of that and the coarsest internal LOD whose error passes
    /// (the search stopped there because one does; levels count from 1).
    fn screened(&self, found: &Found, level: usize, screen: Option<&ScreenRule<'_>>) -> usize {
        let (Some(rule), Found::Node { node, mbr, .. }) = (screen, found) else {
            return level;
        };
        match self.errors.known(*node) {
            Some(errors) => match rule.test.coarsest_fit(&errors, mbr) {
                Some(fit) => level.min(fit + 1),
                None => level,
            },
            None => level,
        }
    }

    /// How many finds `cell` has, searched apart from the walk's figures (no node cache).
    pub(super) fn count(&self, cell: u32) -> Result<usize> {
        let screen = self.screen_rule(cell)?;
        let found = self.db.hdov_search_screened(
            cell,
            self.eta,
            Some(self.scheme),
            None,
            screen.as_ref(),
        )?;
        Ok(found.found.len())
    }

    /// The prefetch thread's work: `req`'s cell searched, and what the buffer did not
    /// hold at its level read.
    fn prefetch(&self, loader: &mut Loader<'_>, req: &Request) -> Result<Prefetched> {
        let Finds {
            pieces, mut failed, ..
        } = self.finds(loader, req.cell)?;
        let mut loaded = Vec::new();
        for p in &pieces {
            if req.held.get(&p.key) == Some(&p.level) {
                continue;
            }
            match read(loader, p, self) {
                Ok(l) => loaded.push(l),
                Err(e) if self.tolerant => failed.push((p.key, e)),
                Err(e) => return Err(e),
            }
        }
        Ok(Prefetched {
            cell: req.cell,
            pieces,
            loaded,
            failed,
        })
    }
}

/// The viewcell of the HDoV-tree whose box holds `p` ([`viewcell_holding`]).
pub(super) fn cell_at(db: &Database, p: glam::Vec3) -> Result<Option<u32>> {
    Ok(match viewcell_holding(db, p)? {
        Some(c) if db.hdov_head()?.slot(c).is_some() => Some(c),
        _ => None,
    })
}

/// The id a find has in the buffer.
pub(super) fn key_of(found: &Found) -> Result<u64> {
    match found {
        Found::Object { entry, .. } if entry.id & GROUP_ID != 0 => Err(Error::Invalid(format!(
            "object {} has an id with its top bit set, which VISUAL keeps for HDoV nodes",
            entry.id
        ))),
        Found::Object { entry, .. } => Ok(entry.id),
        Found::Node { node, .. } => Ok(GROUP_ID | *node as u64),
    }
}

/// `piece` read at its level, as the buffer holds it, with what LOD selection is to
/// know of it as `search` says (its DoV, how fine it may be drawn).
fn read(loader: &mut Loader<'_>, piece: &Piece, search: &Searcher<'_>) -> Result<Loaded> {
    let mesh = loader.mesh(&piece.found, piece.level)?;
    Ok(loaded(piece, mesh, piece.level, search))
}

/// `piece` as the buffer holds it with `mesh`, its level `level`, and what LOD
/// selection is to know of it as `search` says.
pub(super) fn loaded(piece: &Piece, mesh: Mesh, level: usize, search: &Searcher<'_>) -> Loaded {
    let entry = match &piece.found {
        Found::Object { entry, .. } => *entry,
        Found::Node { mbr, lods, .. } => ObjectEntry {
            id: piece.key,
            bounds: *mbr,
            mesh: *lods,
            triangles: mesh.triangle_count() as u32,
            kind: 0,
        },
    };
    let mut loaded = Loaded::at_level(entry, mesh, level);
    if let Found::Object { dov, .. } = &piece.found {
        // The fallback's objects (DoV 0) have no DoV to hand on.
        if search.dov_tau && *dov > 0.0 {
            loaded.dov = Some(*dov);
        }
        if search.finer_of {
            loaded.finest = 0;
            loaded.finer_of = true;
        }
        if search.selection == Selection::Screen {
            loaded.tau_scale = faint_tau_scale(*dov, search.eta, search.faint_tau);
        }
    }
    loaded
}

/// A frame's start, in either VISUAL mode: its pose taken into `track`, the path's clock
/// waited for under the walk's pace, its camera, and its figures begun. Pages are
/// counted from before the wait: what another thread reads meanwhile is this frame's.
/// The camera, the figures, the pages read so far and when the frame's own work began.
pub(super) fn begin_frame(
    db: &Database,
    cfg: &VisualConfig,
    track: &mut MotionTrack,
    clock: Instant,
    at: FrameAt<'_>,
) -> Result<(Camera, VisualFrame, IoStats, Instant)> {
    let pose = at.pose;
    track.push(at.index, *pose)?;
    let io_before = db.io();
    if let (Some(speed), Some(start)) = (cfg.pace, track.start()) {
        wait_until_due(pose.time, start, speed, clock);
    }
    let camera = at.camera(Some(cfg.far))?;
    let frame = VisualFrame {
        frame: at.index,
        time: pose.time,
        ..Default::default()
    };
    Ok((camera, frame, io_before, Instant::now()))
}

/// A frame's figures once it is culled, from what its retrieval left `pending`: what
/// it draws, its time, and the pages read since its retrieval began, on every thread.
pub(super) fn finish_frame(
    db: &Database,
    pending: Option<(VisualFrame, IoStats, Instant)>,
    culled: &Culled<'_>,
    buffer: &ObjectBuffer,
) -> Result<VisualFrame> {
    let (mut frame, io_before, start) =
        pending.ok_or_else(|| Error::Invalid("a frame finished before it was retrieved".into()))?;
    frame.cull_ms = culled.ms;
    frame.drawn = culled.drawn.len();
    frame.triangles_drawn = culled
        .drawn
        .iter()
        .map(|o| o.mesh.triangle_count() as u64)
        .sum();
    frame.frame_ms = start.elapsed().as_secs_f64() * 1e3;
    let io = db.io().since(&io_before);
    let of = |kinds: &[PageKind]| kinds.iter().map(|k| io.reads_of(*k)).sum::<u64>();
    frame.tree_pages = of(&[PageKind::HdovNode, PageKind::VPage]);
    frame.model_pages = of(&[PageKind::Mesh, PageKind::Lod]);
    frame.other_pages = io.page_reads - frame.tree_pages - frame.model_pages;
    frame.buffer_bytes = buffer.bytes();
    Ok(frame)
}

/// The VISUAL mode: the current cell's finds, the fallback's cell, the prefetch.
struct Visual<'a> {
    db: &'a Database,
    cfg: &'a VisualConfig,
    search: &'a Searcher<'a>,
    loader: Loader<'a>,
    /// The viewcell whose finds the buffer holds; `None` before the first or outside.
    current: Option<u32>,
    /// The keys of its finds (or of the fallback's objects), in the search's order:
    /// what a frame may draw.
    drawable: Vec<u64>,
    /// Of those, objects and nodes.
    found: (usize, usize),
    /// Outside every cell: the fallback's disk cell.
    fallback_cell: Option<Aabb>,
    /// The latest prefetched cell, its finds in the buffer.
    prefetched: Option<(u32, Vec<Piece>)>,
    /// The cell a prefetch is running for.
    in_flight: Option<u32>,
    /// The cell last asked for (not asked again until another is predicted).
    asked: Option<u32>,
    req_tx: Option<mpsc::Sender<Request>>,
    res_rx: mpsc::Receiver<Result<Prefetched>>,
    left_out: Option<LeftOut>,
    track: MotionTrack,
    clock: Instant,
    pending: Option<(VisualFrame, IoStats, Instant)>,
}

impl Mode for Visual<'_> {
    type Frame = VisualFrame;

    /// What VISUAL holds is what its cell finds; the buffer is not capped.
    fn memory_budget(&self) -> usize {
        usize::MAX
    }

    fn retrieve(&mut self, at: FrameAt<'_>, buffer: &mut ObjectBuffer) -> Result<Option<Camera>> {
        let pose = at.pose;
        let (camera, mut frame, io_before, start) =
            begin_frame(self.db, self.cfg, &mut self.track, self.clock, at)?;
        self.collect_prefetch(None, buffer, &mut frame)?;
        let cell = cell_at(self.db, pose.position)?;
        match cell {
            Some(c) if self.current != Some(c) => self.enter(c, buffer, &mut frame)?,
            Some(_) => {}
            None => self.fall_back(&camera, buffer, &mut frame)?,
        }
        frame.cell = cell;
        (frame.objects_found, frame.nodes_found) = self.found;
        if let Some(k) = self.cfg.prefetch_k {
            self.maybe_prefetch(pose.position + self.track.motion().velocity * k, buffer)?;
        }
        self.pending = Some((frame, io_before, start));
        Ok(Some(camera))
    }

    fn drawable(&self) -> Drawable<'_> {
        // Without a prefetched cell beside them the buffer holds exactly the cell's
        // finds: culling walks it as it lies rather than looking each one up.
        match self.prefetched {
            None => Drawable::All,
            Some(_) => Drawable::Only(&self.drawable),
        }
    }

    fn finish(&mut self, culled: &Culled<'_>, buffer: &ObjectBuffer) -> Result<VisualFrame> {
        finish_frame(self.db, self.pending.take(), culled, buffer)
    }

    fn figures(&mut self, f: &VisualFrame, buffer: &ObjectBuffer) -> FrameFigures {
        FrameFigures {
            pages: f.tree_pages + f.model_pages + f.other_pages,
            objects_buffered: buffer.len(),
            objects_drawn: f.drawn,
            triangles: f.triangles_drawn,
            prefetch_queue: self.in_flight.is_some() as usize,
            cache_hit_rate: self.search.pool.map(|p| p.stats().hit_rate()),
            cell: match f.cell {
                Some(c) => format!(
                    "viewcell {c}, η = {}: {} objects, {} nodes",
                    self.cfg.eta, f.objects_found, f.nodes_found
                ),
                None => "outside every viewcell: REVIEW's box query".into(),
            },
            walk_ms: f.frame_ms,
            damaged: self
                .left_out
                .as_mut()
                .map(LeftOut::take_untold)
                .unwrap_or_default(),
            ..Default::default()
        }
    }
}

impl Visual<'_> {
    /// The viewer moved into viewcell `cell`: its finds from a prefetch or a search,
    /// brought into the buffer by delta.
    fn enter(
        &mut self,
        cell: u32,
        buffer: &mut ObjectBuffer,
        frame: &mut VisualFrame,
    ) -> Result<()> {
        if self.in_flight == Some(cell) {
            self.collect_prefetch(Some(MAX_PREFETCH_WAIT), buffer, frame)?;
        }
        let pieces = match self.prefetched.take() {
            Some((c, pieces)) if c == cell => {
                frame.prefetch_used = true;
                pieces
            }
            other => {
                self.prefetched = other;
                let t = Instant::now();
                let Finds { pieces, failed, ms } = self.search.finds(&mut self.loader, cell)?;
                frame.searched = true;
                frame.search_ms = ms;
                frame.load_ms += t.elapsed().as_secs_f64() * 1e3 - ms;
                self.leave_out(failed, frame);
                pieces
            }
        };
        self.hold(pieces, buffer, frame)?;
        self.current = Some(cell);
        self.fallback_cell = None;
        Ok(())
    }

    /// Outside every viewcell: REVIEW's BOX query of the disk cell around the frustum,
    /// asked again when the frustum leaves it.
    fn fall_back(
        &mut self,
        camera: &Camera,
        buffer: &mut ObjectBuffer,
        frame: &mut VisualFrame,
    ) -> Result<()> {
        let fcell = camera.frustum().aabb();
        if self.current.is_none()
            && self
                .fallback_cell
                .is_some_and(|c| contains_ground(&c, &fcell))
        {
            return Ok(());
        }
        let cell = scaled_cell(
            &self.db.bounds(),
            &fcell,
            fcell.center(),
            self.cfg.fallback_sf,
        );
        let t = Instant::now();
        let objects = self.db.range(&cell)?.objects;
        frame.search_ms = t.elapsed().as_secs_f64() * 1e3;
        frame.fallback_query = true;
        let pieces = objects
            .into_iter()
            .map(|entry| Piece {
                key: entry.id,
                level: 0,
                found: Found::Object {
                    entry,
                    dov: 0.0,
                    detail: 1.0,
                },
            })
            .collect();
        self.hold(pieces, buffer, frame)?;
        self.current = None;
        self.fallback_cell = Some(cell);
        Ok(())
    }

    /// Makes `pieces` what the frames draw: reads those the buffer does not hold at
    /// their level, drops what neither they nor the prefetched cell want.
    fn hold(
        &mut self,
        pieces: Vec<Piece>,
        buffer: &mut ObjectBuffer,
        frame: &mut VisualFrame,
    ) -> Result<()> {
        let t = Instant::now();
        let mut kept = Vec::with_capacity(pieces.len());
        for p in pieces {
            if self.left_out.as_ref().is_some_and(|l| l.contains(p.key)) {
                continue;
            }
            if buffer.get(p.key).is_some_and(|o| o.level == p.level) {
                frame.reused += 1;
            } else {
                match read(&mut self.loader, &p, self.search) {
                    Ok(l) => {
                        buffer.replace(l);
                        frame.loaded += 1;
                    }
                    Err(e) if self.left_out.is_some() => {
                        self.leave_out(vec![(p.key, e)], frame);
                        continue;
                    }
                    Err(e) => return Err(e),
                }
            }
            kept.push(p);
        }
        let mut wanted: HashSet<u64> = kept.iter().map(|p| p.key).collect();
        if let Some((_, pre)) = &self.prefetched {
            wanted.extend(pre.iter().map(|p| p.key));
        }
        let gone: Vec<u64> = buffer
            .iter()
            .map(|o| o.entry.id)
            .filter(|id| !wanted.contains(id))
            .collect();
        frame.dropped += gone.len();
        for id in gone {
            buffer.remove(id);
        }
        self.drawable = kept.iter().map(|p| p.key).collect();
        let objects = kept
            .iter()
            .filter(|p| matches!(p.found, Found::Object { .. }))
            .count();
        self.found = (objects, kept.len() - objects);
        frame.load_ms += t.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }

    /// Finds that could not be read, left out from now on.
    fn leave_out(&mut self, failed: Vec<(u64, Error)>, frame: &mut VisualFrame) {
        if let Some(l) = self.left_out.as_mut() {
            for (key, e) in failed {
                if !l.contains(key) {
                    l.leave_out(key, &e);
                    frame.left_out += 1;
                }
            }
        }
    }

    /// Takes a finished prefetch's finds into the buffer; with `wait`, blocks for the
    /// running one that long at most.
    fn collect_prefetch(
        &mut self,
        wait: Option<Duration>,
        buffer: &mut ObjectBuffer,
        frame: &mut VisualFrame,
    ) -> Result<()> {
        if self.in_flight.is_none() {
            return Ok(());
        }
        let Some(got) = receive(&self.res_rx, wait)? else {
            return Ok(());
        };
        self.in_flight = None;
        let got = got?;
        let t = Instant::now();
        frame.prefetch_adopted = true;
        self.leave_out(got.failed, frame);
        for l in got.loaded {
            // Loaded at the level the cell wants, unless the buffer now holds it so.
            if buffer.get(l.entry.id).is_none_or(|o| o.level != l.level) {
                buffer.replace(l);
            }
        }
        self.prefetched = Some((got.cell, got.pieces));
        frame.load_ms += t.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }

    /// Asks the prefetch thread for the viewcell at `ahead` (where the eye will be),
    /// when it is another than the current one and not yet asked for.
    fn maybe_prefetch(&mut self, ahead: glam::Vec3, buffer: &ObjectBuffer) -> Result<()> {
        let Some(tx) = &self.req_tx else {
            return Ok(());
        };
        if self.in_flight.is_some() || !ahead.is_finite() {
            return Ok(());
        }
        let Some(cell) = cell_at(self.db, ahead)? else {
            return Ok(());
        };
        if Some(cell) == self.current || Some(cell) == self.asked {
            return Ok(());
        }
        let held = buffer.iter().map(|o| (o.entry.id, o.level)).collect();
        if tx.send(Request { cell, held }).is_ok() {
            self.in_flight = Some(cell);
            self.asked = Some(cell);
        }
        Ok(())
    }
}
