//! The VISUAL mode (Shou 2002 §5.8.5): the retrieval of a VISUAL walk, one frame at a
//! time for the walk session. Each frame the eye's viewcell is found; on a change of
//! cell the HDoV-tree is searched (or a prefetch's finds taken) and the finds brought
//! into the buffer by delta; outside every cell, REVIEW's BOX query of a disk cell
//! instead. The next-cell prefetch (ours) runs on a thread of its own. The settings,
//! figures and departures are `walk::visual`'s.

use super::search::begin_frame;
use super::search::cell_at;
use super::search::finish_frame;
use super::search::read;
use super::search::Finds;
use super::search::Piece;
use super::search::Prefetched;
use super::search::Request;
use super::search::Searcher;
use std::collections::HashSet;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use crate::database::Database;
use crate::error::{Error, Result};
use crate::geom::{Aabb, Camera};
use crate::hdov::{Found, Loader};
use crate::prefetch::motion::MotionTrack;
use crate::store::IoStats;
use crate::walk::buffer::ObjectBuffer;
use crate::walk::cells::{contains_ground, scaled_cell};
use crate::walk::session::{self, Culled, Drawable, FrameAt, Mode};
use crate::walk::sink::{FrameFigures, LeftOut, Viewer};
use crate::walk::threads::receive::receive;
use crate::walk::visual::{VisualConfig, VisualFrame};
use crate::walk::walk_lods::WalkLods;

/// How long the viewer waits for a prefetch of the cell it enters before it searches
/// for itself, as REVIEW's does.
const MAX_PREFETCH_WAIT: Duration = Duration::from_millis(10);

/// A VISUAL walk that waits on its reads: the walk session with the VISUAL mode, and
/// the next cell's prefetch on a thread of its own when the walk prefetches.
pub(super) fn walk_waiting<'db>(
    db: &'db Database,
    cfg: &VisualConfig,
    search: &Searcher<'_>,
    lods: &mut WalkLods<'db>,
    viewer: &mut dyn Viewer,
    counted: &mut dyn FnMut(VisualFrame) -> Result<()>,
) -> Result<()> {
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
            left_out: search.tolerant.then(LeftOut::default),
            track: MotionTrack::default(),
            clock: Instant::now(),
            pending: None,
        };
        let walk = session::run_each(&mut mode, viewer, lods, counted);
        mode.req_tx = None;
        walk
    })
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
