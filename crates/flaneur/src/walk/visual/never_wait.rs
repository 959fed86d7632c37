//! The VISUAL mode that never waits on a read (ours): the viewer's side. Each frame it
//! finds the eye's viewcell (the HDoV-tree's head and the viewcells' table are read
//! before the walk), posts where it stands and where it goes to the loader thread
//! (`loader.rs`), takes what has arrived (a place's finds, meshes, what to let go)
//! and draws its place's finds of what it holds, at whatever level they arrived.
//!
//! What has not arrived is a visual miss, counted at every frame in a viewcell: the
//! cell's finds the buffer does not hold at any level; all of them while the cell's
//! search has not come back, the frame then drawing the last place's finds. A frame's
//! finds held coarser than their DoV deserves are counted too. Outside every viewcell
//! the frames draw the fallback's disk cell as it arrives, and count no misses, as the
//! waiting walk counts none there. A read the loader was still asking for when the walk
//! ended is counted once the loader stops, failed or not.

use std::collections::HashMap;
use std::sync::{mpsc, Mutex};
use std::time::Instant;

use super::loader::{self, Place, Stand, Update};
use super::search::{begin_frame, cell_at, finish_frame, Searcher};
use crate::database::Database;
use crate::error::Result;
use crate::geom::{Aabb, Camera};
use crate::prefetch::motion::MotionTrack;
use crate::store::IoStats;
use crate::walk::buffer::{ObjectBuffer, GROUP_ID};
use crate::walk::cells::{contains_ground, scaled_cell};
use crate::walk::session::{self, Culled, Drawable, FrameAt, Mode};
use crate::walk::sink::{FrameFigures, LeftOut, Viewer};
use crate::walk::threads::mailbox::Mailbox;
use crate::walk::threads::receive::receive;
use crate::walk::visual::{VisualConfig, VisualFrame};
use crate::walk::walk_lods::WalkLods;

/// What a never-wait VISUAL walk reports beside its frames.
#[derive(Debug, Default)]
pub(crate) struct NeverWaitRun {
    /// Reads the network failed (each asked for again).
    pub failures: crate::walk::threads::load_failures::LoadFailures,
}

/// A never-wait VISUAL walk under `cfg`, searching with `search`, the poses coming from
/// `viewer`. Every frame's figures go to `each` once the walk has ended: the misses of
/// frames whose cell's finds had not come are counted only once they are known, so this
/// walk keeps its frames until then.
pub(crate) fn walk_live<'db>(
    db: &'db Database,
    cfg: &VisualConfig,
    search: &Searcher<'_>,
    lods: &mut WalkLods<'db>,
    viewer: &mut dyn Viewer,
    each: &mut dyn FnMut(VisualFrame) -> Result<()>,
) -> Result<NeverWaitRun> {
    // Read before the walk, so that finding the eye's viewcell reads nothing on the
    // viewer's thread.
    db.hdov_head()?;
    db.visibility()?;
    let mailbox = Mailbox::default();
    let left_out = viewer
        .skips_damaged()
        .then(|| Mutex::new(LeftOut::default()));
    let (tx, rx) = mpsc::channel();
    let (walked, rx) = std::thread::scope(|scope| {
        let (mb, lo) = (&mailbox, left_out.as_ref());
        scope.spawn(move || loader::run(search, mb, lo, tx));
        let mut mode = NeverWait {
            db,
            cfg,
            mailbox: &mailbox,
            rx,
            left_out: left_out.as_ref(),
            finds: HashMap::new(),
            cells: HashMap::new(),
            here: None,
            shown: None,
            outside: None,
            drawable: Vec::new(),
            track: MotionTrack::default(),
            clock: Instant::now(),
            pending: None,
            unknown: Vec::new(),
            run: NeverWaitRun::default(),
        };
        let walked = session::run(&mut mode, viewer, lods);
        mailbox.end();
        (
            walked.map(|frames| (frames, mode.unknown, mode.cells, mode.run)),
            mode.rx,
        )
    });
    let (mut frames, unknown, cells, mut run) = walked?;
    // The loader has stopped (the scope waited for it): a read it was still asking for
    // as the walk ended has failed or come, and a failure is counted.
    for update in rx.try_iter() {
        match update {
            Update::Retrying(why) => run.failures.note(why),
            // Only the network's failures are counted here.
            Update::Stopped(e) => drop(run.failures.note_stop(e)),
            _ => {}
        }
    }
    // Frames whose cell's finds had not come missed all of them: counted now, a cell the
    // loader never searched searched here, outside the walk's figures.
    for (frame, cell) in unknown {
        let count = match cells.get(&cell) {
            Some(&n) => n,
            None => search.count(cell)?,
        };
        if let Some(f) = frames.get_mut(frame) {
            f.visual_misses = count;
        }
    }
    frames.into_iter().try_for_each(each)?;
    Ok(run)
}

/// The viewer's side of the walk.
struct NeverWait<'a> {
    db: &'a Database,
    cfg: &'a VisualConfig,
    mailbox: &'a Mailbox<Stand>,
    rx: mpsc::Receiver<Update>,
    left_out: Option<&'a Mutex<LeftOut>>,
    /// The finds of the places the loader has searched, each key at the level it
    /// deserves: the viewer's place and the next one.
    finds: HashMap<Place, Vec<(u64, usize)>>,
    /// Every viewcell's count of finds, as they came.
    cells: HashMap<u32, usize>,
    /// The viewer's place.
    here: Option<Place>,
    /// The place whose finds the frames draw: the viewer's once they have come, else
    /// the last one's.
    shown: Option<Place>,
    /// Outside every viewcell: the fallback's disk cell, numbered.
    outside: Option<(u64, Aabb)>,
    /// The shown place's keys.
    drawable: Vec<u64>,
    track: MotionTrack,
    clock: Instant,
    pending: Option<(VisualFrame, IoStats, Instant)>,
    /// Frames in a viewcell whose finds had not come, and the cell.
    unknown: Vec<(usize, u32)>,
    run: NeverWaitRun,
}

impl Mode for NeverWait<'_> {
    type Frame = VisualFrame;

    /// What VISUAL holds is what its cell finds; the buffer is not capped.
    fn memory_budget(&self) -> usize {
        usize::MAX
    }

    fn retrieve(&mut self, at: FrameAt<'_>, buffer: &mut ObjectBuffer) -> Result<Option<Camera>> {
        let (i, pose) = (at.index, at.pose);
        let (camera, mut frame, io_before, started) =
            begin_frame(self.db, self.cfg, &mut self.track, self.clock, at)?;
        let cell = cell_at(self.db, pose.position)?;
        let (here, outside) = match cell {
            Some(c) => (Place::Cell(c), None),
            None => {
                let (n, disk) = self.fall_back(&camera);
                frame.fallback_query = self.here != Some(Place::Outside(n));
                (Place::Outside(n), Some(disk))
            }
        };
        let ahead = self
            .cfg
            .prefetch_k
            .map(|k| pose.position + self.track.motion().velocity * k)
            .filter(|p| p.is_finite())
            .map(|p| cell_at(self.db, p))
            .transpose()?
            .flatten()
            .filter(|&c| cell != Some(c));
        self.here = Some(here);
        self.mailbox.post(
            i as u64,
            Stand {
                eye: camera.position,
                aim: camera.forward(),
                here,
                outside,
                ahead,
            },
        );
        self.take_updates(buffer, &mut frame)?;
        if self.finds.contains_key(&here) {
            self.shown = Some(here);
        }
        self.drawable = self
            .shown
            .and_then(|p| self.finds.get(&p))
            .map_or_else(Vec::new, |f| f.iter().map(|(k, _)| *k).collect());
        frame.cell = cell;
        if let Some(c) = cell {
            match self.finds.get(&here) {
                Some(finds) => {
                    let held = |k: &u64| buffer.get(*k).map(|o| o.level);
                    frame.visual_misses = finds.iter().filter(|(k, _)| held(k).is_none()).count();
                    frame.coarse = finds
                        .iter()
                        .filter(|(k, level)| held(k).is_some_and(|l| l > *level))
                        .count();
                    frame.objects_found = finds.iter().filter(|(k, _)| k & GROUP_ID == 0).count();
                    frame.nodes_found = finds.len() - frame.objects_found;
                }
                None => self.unknown.push((i, c)),
            }
        }
        self.pending = Some((frame, io_before, started));
        Ok(Some(camera))
    }

    fn drawable(&self) -> Drawable<'_> {
        Drawable::Only(&self.drawable)
    }

    fn finish(&mut self, culled: &Culled<'_>, buffer: &ObjectBuffer) -> Result<VisualFrame> {
        // Every page read since the frame began, the loader's included.
        finish_frame(self.db, self.pending.take(), culled, buffer)
    }

    fn figures(&mut self, f: &VisualFrame, buffer: &ObjectBuffer) -> FrameFigures {
        let damaged = self
            .left_out
            .and_then(|l| l.lock().ok().map(|mut l| l.take_untold()));
        FrameFigures {
            pages: f.tree_pages + f.model_pages + f.other_pages,
            objects_buffered: buffer.len(),
            objects_drawn: f.drawn,
            triangles: f.triangles_drawn,
            visual_misses: f.visual_misses,
            cell: match (f.cell, self.shown == self.here) {
                (Some(c), true) => format!(
                    "viewcell {c}, η = {}: {} objects, {} nodes, {} coarse, never waiting",
                    self.cfg.eta, f.objects_found, f.nodes_found, f.coarse
                ),
                (Some(c), false) => format!("viewcell {c}: its search has not come back"),
                (None, _) => "outside every viewcell: REVIEW's box query".into(),
            },
            walk_ms: f.frame_ms,
            damaged: damaged.unwrap_or_default(),
            ..Default::default()
        }
    }
}

impl NeverWait<'_> {
    /// Outside every viewcell: the fallback's disk cell around the frustum, a new one
    /// (numbered) when the frustum leaves it or the viewer comes from a viewcell.
    fn fall_back(&mut self, camera: &Camera) -> (u64, Aabb) {
        let fcell = camera.frustum().aabb();
        match self.outside {
            Some((n, disk))
                if self.here == Some(Place::Outside(n)) && contains_ground(&disk, &fcell) =>
            {
                (n, disk)
            }
            last => {
                let disk = scaled_cell(
                    &self.db.bounds(),
                    &fcell,
                    fcell.center(),
                    self.cfg.fallback_sf,
                );
                let n = last.map_or(0, |(n, _)| n + 1);
                self.outside = Some((n, disk));
                (n, disk)
            }
        }
    }

    /// Takes everything the loader has sent since the last frame, in order.
    fn take_updates(&mut self, buffer: &mut ObjectBuffer, frame: &mut VisualFrame) -> Result<()> {
        while let Some(update) = receive(&self.rx, None)? {
            match update {
                Update::Found { place, finds } => {
                    if let Place::Cell(c) = place {
                        self.cells.insert(c, finds.len());
                    }
                    self.finds.insert(place, finds);
                }
                Update::Loaded(objects) => {
                    frame.loaded += objects.len();
                    for o in objects {
                        buffer.replace(o);
                    }
                }
                Update::LetGo { places, keys } => {
                    // The places the loader forgot are searched again if come back to.
                    for p in places {
                        self.finds.remove(&p);
                    }
                    frame.dropped += keys.len();
                    for k in keys {
                        buffer.remove(k);
                    }
                }
                Update::Retrying(why) => self.run.failures.note(why),
                Update::Stopped(e) => return Err(e),
            }
        }
        Ok(())
    }
}
