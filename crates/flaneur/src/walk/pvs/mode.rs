//! The PVS mode (Zheng 2007 ch. 7): the retrieval of a PVS walk, one frame at a time for
//! the walk session. Each frame the eye's viewcell is found and the client steps there,
//! prefetching neighbours' PVS rows with SNP or PBNP from the database's stored table;
//! a viewer that draws gets the objects the client holds loaded into the buffer (after
//! the frame's page count, so those reads are the renderer's), and draws the PVS of the
//! current cell (the last one, outside cells). The settings and figures are
//! `walk::pvs`'s; the walk that never waits is `never_wait.rs`.

use super::index_entries::IndexEntries;
use super::report::figures;
use super::report::finish_timed;
use std::time::Instant;

use crate::database::Database;
use crate::error::Result;
use crate::geom::Camera;
use crate::prefetch::pvs::{Cell, Position, PrefetchArea, PvsClient, StoredPvs, THESIS_CAPACITY};
use crate::walk::buffer::{Loaded, ObjectBuffer};
use crate::walk::pvs::PvsFrame;
use crate::walk::session::{self, Culled, Drawable, FrameAt, Mode};
use crate::walk::sink::{FrameFigures, LeftOut, Viewer};
use crate::walk::walk_lods::WalkLods;

/// A PVS walk that waits on its reads, as the thesis's: the walk session with the PVS
/// mode, the client stepping on the viewer's thread.
pub(super) fn walk_waiting<'db>(
    db: &'db Database,
    source: &StoredPvs<'db>,
    rule: &dyn PrefetchArea,
    lods: &mut WalkLods<'db>,
    viewer: &mut dyn Viewer,
    each: impl FnMut((PvsFrame, f64)) -> Result<()>,
) -> Result<()> {
    let client = PvsClient::new(source, rule, THESIS_CAPACITY)?;
    // For a renderer: every object's index entry, to load what the client holds.
    let entries = if viewer.draws() {
        IndexEntries::read(db)?
    } else {
        IndexEntries::default()
    };
    let mut mode = Pvs {
        db,
        client,
        entries,
        left_out: viewer.skips_damaged().then(LeftOut::default),
        shown: None,
        pending: None,
    };
    session::run_each(&mut mode, viewer, lods, each)
}

/// The PVS mode: the client, and what a drawing viewer needs beside it.
struct Pvs<'a> {
    db: &'a Database,
    client: PvsClient<'a, StoredPvs<'a>, dyn PrefetchArea + 'a>,
    entries: IndexEntries,
    /// Objects whose meshes could not be read, when the viewer walks on without them.
    left_out: Option<LeftOut>,
    /// The cell whose PVS the frames draw: the current one, or the last one outside cells.
    shown: Option<Cell>,
    /// The frame retrieved and not yet finished, and when it started.
    pending: Option<(PvsFrame, Instant)>,
}

impl Mode for Pvs<'_> {
    /// The frame's figures and its time on the viewer's thread, ms.
    type Frame = (PvsFrame, f64);

    /// What the client holds is bounded by its cache, not by the buffer.
    fn memory_budget(&self) -> usize {
        usize::MAX
    }

    fn retrieve(&mut self, at: FrameAt<'_>, buffer: &mut ObjectBuffer) -> Result<Option<Camera>> {
        let pose = at.pose;
        let started = Instant::now();
        let before = self.db.io().page_reads;
        let mut frame = PvsFrame::default();
        if let Some(id) = self.db.viewcell_at(pose.position)? {
            let p = Position::new(pose.position.x as f64, pose.position.z as f64);
            let out = self.client.step(p)?;
            self.shown = Some(out.cell);
            frame.cell = Some(id);
            frame.drawn = self.client.cache().pvs(out.cell).map_or(0, |s| s.len());
            frame.visual_misses = out.visual_misses;
            if let Some(t) = &out.transaction {
                frame.transaction = true;
                frame.sent = t.sent.len();
                frame.swaps = t.evicted.len();
            }
        }
        frame.pages = self.db.io().page_reads - before;
        self.pending = Some((frame, started));
        if !at.draws {
            return Ok(None);
        }
        self.load_held(buffer)?;
        Ok(Some(at.camera(None)?))
    }

    fn drawable(&self) -> Drawable<'_> {
        Drawable::Only(
            self.shown
                .and_then(|c| self.client.cache().pvs(c))
                .unwrap_or(&[]),
        )
    }

    fn finish(&mut self, _: &Culled<'_>, _: &ObjectBuffer) -> Result<(PvsFrame, f64)> {
        finish_timed(self.pending.take())
    }

    fn figures(&mut self, frame: &(PvsFrame, f64), buffer: &ObjectBuffer) -> FrameFigures {
        let damaged = self.left_out.as_mut().map(LeftOut::take_untold);
        figures(frame, buffer, damaged.unwrap_or_default())
    }
}

impl Pvs<'_> {
    /// Brings `held` to what the client holds: loads new objects' meshes (leaving out,
    /// when `left_out` is kept, those that cannot be read) and drops what it evicted.
    fn load_held(&mut self, held: &mut ObjectBuffer) -> Result<()> {
        let cache = self.client.cache();
        let gone: Vec<u64> = held
            .iter()
            .map(|o| o.entry.id)
            .filter(|&id| !cache.holds(id))
            .collect();
        for id in gone {
            held.remove(id);
        }
        for id in cache.objects() {
            if held.get(id).is_none() && !self.left_out.as_ref().is_some_and(|l| l.contains(id)) {
                let entry = self.entries.get(id)?;
                let mesh = match (self.db.mesh(entry), self.left_out.as_mut()) {
                    (Ok(m), _) => m,
                    (Err(e), Some(l)) => {
                        l.leave_out(id, &e);
                        continue;
                    }
                    (Err(e), None) => return Err(e),
                };
                held.insert(Loaded::new(*entry, mesh));
            }
        }
        Ok(())
    }
}
