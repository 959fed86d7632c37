//! The PVS mode that never waits on a read (ours): the viewer's side. Each frame it
//! finds the eye's viewcell from the visibility directory (read before the walk), posts
//! where it stands to the loader thread (`loader.rs`), takes what has arrived (rows,
//! meshes, the cache's evictions) and draws the current cell's PVS of what it holds.
//! What has not arrived is a visual miss, counted at every frame: all of the cell's PVS
//! while its row has not come, the frame then drawing the last cell's. Coarse levels
//! the loader found damaged are counted at the frame that learns of them and named in
//! the walk's figures; what the loader was still reading when the walk ended is taken
//! once it stops, so that failures at the end are counted too.

use std::collections::HashMap;
use std::sync::{mpsc, Mutex};
use std::time::Instant;

use super::loader::{self, Mailbox, Stand, Update};
use super::report::{self, PvsRun};
use crate::database::Database;
use crate::error::Result;
use crate::geom::Camera;
use crate::prefetch::pvs::{Cell, Position, PrefetchArea, PvsSource, StoredPvs};
use crate::walk::buffer::ObjectBuffer;
use crate::walk::pvs::PvsFrame;
use crate::walk::session::{self, Culled, Drawable, FrameAt, Mode};
use crate::walk::sink::{FrameFigures, LeftOut, Viewer};
use crate::walk::threads::damage::{self, DamageCursor, Damaged};
use crate::walk::threads::pace::wait_until_due;
use crate::walk::threads::receive::receive;
use crate::walk::walk_lods::WalkLods;

/// A never-wait PVS walk over `source` (`db`'s visibility) with `rule`, the poses
/// played at `pace` times real time (`None`: back to back), each frame handed to `each`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn walk_live<'db>(
    db: &'db Database,
    source: &StoredPvs<'db>,
    rule: &(dyn PrefetchArea + Sync),
    pace: Option<f32>,
    lods: &mut WalkLods<'db>,
    viewer: &mut dyn Viewer,
    each: impl FnMut((PvsFrame, f64)) -> Result<()>,
) -> Result<PvsRun> {
    let mailbox = Mailbox::default();
    let left_out = viewer
        .skips_damaged()
        .then(|| Mutex::new(LeftOut::default()));
    let met = Mutex::new(Damaged::default());
    let (tx, rx) = mpsc::channel();
    let (walked, rx, mut run) = std::thread::scope(|scope| {
        let (mb, lo, dm) = (&mailbox, left_out.as_ref(), &met);
        scope.spawn(move || loader::run(db, source, rule, mb, (lo, dm), tx));
        let mut mode = NeverWait {
            db,
            source,
            mailbox: &mailbox,
            rx,
            left_out: left_out.as_ref(),
            damaged: &met,
            damage_seen: DamageCursor::default(),
            rows: HashMap::new(),
            shown: None,
            pace,
            start: None,
            clock: Instant::now(),
            pending: None,
            page_reads: db.io().page_reads,
            run: PvsRun::default(),
        };
        let walked = session::run_each(&mut mode, viewer, lods, each);
        mailbox.end();
        (walked, mode.rx, mode.run)
    });
    walked?;
    // The loader has stopped (the scope waited for it): what it was reading as the walk
    // ended has failed or come, and a failure is counted.
    for update in rx.try_iter() {
        match update {
            Update::Retrying(why) => run.failures.note(why),
            Update::Stopped(e) => {
                if let (Some(e), Ok(mut d)) = (run.failures.note_stop(e), met.lock()) {
                    d.note_words(e.to_string());
                }
            }
            _ => {}
        }
    }
    run.damaged = damage::named(met);
    Ok(run)
}

/// The viewer's side of the walk.
struct NeverWait<'a> {
    db: &'a Database,
    source: &'a StoredPvs<'a>,
    mailbox: &'a Mailbox,
    rx: mpsc::Receiver<Update>,
    left_out: Option<&'a Mutex<LeftOut>>,
    /// Coarse levels the loader found damaged, and how far the frames have counted and
    /// the viewer been told of them.
    damaged: &'a Mutex<Damaged>,
    damage_seen: DamageCursor,
    /// The rows the client's cache holds, as the loader has told them.
    rows: HashMap<Cell, Vec<u64>>,
    /// The cell whose PVS the frames draw: the current one once its row has come, else
    /// the last one that had.
    shown: Option<Cell>,
    pace: Option<f32>,
    /// The first pose's time, seconds.
    start: Option<f64>,
    clock: Instant,
    pending: Option<(PvsFrame, Instant)>,
    /// Pages read by the walk's start or its last frame.
    page_reads: u64,
    /// The loader's figures so far.
    run: PvsRun,
}

impl Mode for NeverWait<'_> {
    type Frame = (PvsFrame, f64);

    /// What the viewer holds is bounded by the client's cache, not by the buffer.
    fn memory_budget(&self) -> usize {
        usize::MAX
    }

    fn retrieve(&mut self, at: FrameAt<'_>, buffer: &mut ObjectBuffer) -> Result<Option<Camera>> {
        let pose = at.pose;
        let start = *self.start.get_or_insert(pose.time);
        if let Some(speed) = self.pace {
            wait_until_due(pose.time, start, speed, self.clock);
        }
        let started = Instant::now();
        let mut frame = PvsFrame::default();
        let camera = at.camera(None)?;
        let here = match self.db.viewcell_at(pose.position)? {
            Some(id) => {
                let p = Position::new(f64::from(pose.position.x), f64::from(pose.position.z));
                self.mailbox.post(
                    at.index as u64,
                    Stand {
                        frame: at.index as u64,
                        at: p,
                        eye: camera.position,
                        aim: camera.forward(),
                    },
                );
                frame.cell = Some(id);
                Some(self.source.grid().cell_of(p)?)
            }
            None => None,
        };
        self.take_updates(buffer, &mut frame)?;
        frame.damaged = self.damage_seen.count_new(self.damaged);
        if let Some(cell) = here {
            if self.rows.contains_key(&cell) {
                self.shown = Some(cell);
            }
            // The cell the client stands in, as it finds it (on a cell's side it may be
            // the neighbour of the one the frame is counted in).
            let pvs = self.db.visibility()?.map_or(0, |h| {
                h.cell(h.grid.id(cell.row, cell.col))
                    .map_or(0, |e| e.count as usize)
            });
            let held = self
                .rows
                .get(&cell)
                .map_or(0, |r| r.iter().filter(|&&o| buffer.contains(o)).count());
            frame.visual_misses = pvs.saturating_sub(held);
        }
        frame.drawn = self
            .shown_row()
            .iter()
            .filter(|&&o| buffer.contains(o))
            .count();
        // Every page read since the last frame's count, the loader's included.
        let reads = self.db.io().page_reads;
        frame.pages = reads - std::mem::replace(&mut self.page_reads, reads);
        self.pending = Some((frame, started));
        Ok(at.draws.then_some(camera))
    }

    fn drawable(&self) -> Drawable<'_> {
        Drawable::Only(self.shown_row())
    }

    fn finish(&mut self, _: &Culled<'_>, _: &ObjectBuffer) -> Result<(PvsFrame, f64)> {
        report::finish_timed(self.pending.take())
    }

    fn figures(&mut self, frame: &(PvsFrame, f64), buffer: &ObjectBuffer) -> FrameFigures {
        let mut damaged = self
            .left_out
            .and_then(|l| l.lock().ok().map(|mut l| l.take_untold()))
            .unwrap_or_default();
        damaged.extend(self.damage_seen.take_untold(self.damaged));
        report::figures(frame, buffer, damaged)
    }
}

impl NeverWait<'_> {
    fn shown_row(&self) -> &[u64] {
        self.shown
            .and_then(|c| self.rows.get(&c))
            .map_or(&[], |r| &r[..])
    }

    /// Takes everything the loader has sent since the last frame, in order.
    fn take_updates(&mut self, buffer: &mut ObjectBuffer, frame: &mut PvsFrame) -> Result<()> {
        while let Some(update) = receive(&self.rx, None)? {
            match update {
                Update::Asked {
                    rows,
                    evicted,
                    dropped,
                    sent,
                    swaps,
                } => {
                    for c in evicted {
                        self.rows.remove(&c);
                    }
                    self.rows.extend(rows);
                    for id in dropped {
                        buffer.remove(id);
                    }
                    frame.transaction = true;
                    frame.sent += sent;
                    frame.swaps += swaps;
                }
                Update::Loaded(objects) => {
                    for o in objects {
                        // A full mesh comes after the coarse level the viewer holds.
                        if buffer.contains(o.entry.id) {
                            buffer.refine(o);
                        } else {
                            buffer.insert(o);
                        }
                    }
                }
                Update::RoundTrip(trip) => self.run.round_trip = self.run.round_trip.max(trip),
                Update::Retrying(why) => self.run.failures.note(why),
                Update::Stopped(e) => return Err(e),
            }
        }
        Ok(())
    }
}
