//! The PVS mode (Zheng 2007 ch. 7): the retrieval of a PVS walk, one frame at a time for
//! the walk session. Each frame the eye's viewcell is found and the client steps there,
//! prefetching neighbours' PVS rows with SNP or PBNP from the database's stored table;
//! a viewer that draws gets the objects the client holds loaded into the buffer (after
//! the frame's page count, so those reads are the renderer's), and draws the PVS of the
//! current cell (the last one, outside cells). The settings and figures are
//! `walk::pvs_walk`'s; the walk that never waits is `pvs_never_wait`'s.

use std::collections::HashMap;
use std::time::Instant;

use crate::database::Database;
use crate::error::{Error, Result};
use crate::geom::Camera;
use crate::prefetch::pvs::{Cell, Position, PrefetchArea, PvsClient, StoredPvs, THESIS_CAPACITY};
use crate::rtree::ObjectEntry;
use crate::walk::buffer::{Loaded, ObjectBuffer};
use crate::walk::pvs_walk::{PvsFrame, PvsWalkConfig};
use crate::walk::session::{self, Culled, Drawable, FrameAt, Mode};
use crate::walk::sink::{FrameFigures, LeftOut, Viewer};
use crate::walk::walk_lods::WalkLods;

/// Every object's index entry by id: what a PVS walk reads the meshes of the objects a
/// row names through.
#[derive(Debug, Default)]
pub(super) struct IndexEntries(HashMap<u64, ObjectEntry>);

impl IndexEntries {
    /// The whole index of `db`, read once.
    pub(super) fn read(db: &Database) -> Result<IndexEntries> {
        let all = db.range(&db.bounds())?.objects;
        Ok(IndexEntries(all.into_iter().map(|o| (o.id, o)).collect()))
    }

    /// Object `id`'s entry; an error for an id a PVS names and the index does not hold.
    pub(super) fn get(&self, id: u64) -> Result<&ObjectEntry> {
        self.0.get(&id).ok_or_else(|| {
            Error::Invalid(format!(
                "object {id} of a PVS is not in the database's index"
            ))
        })
    }
}

/// What a PVS walk's client measured beside its frames.
#[derive(Debug, Default)]
pub(crate) struct PvsRun {
    /// The longest round trip the client measured, frames.
    pub round_trip: u32,
    /// Reads the network failed (never waiting).
    pub failures: super::load_failures::LoadFailures,
    /// What the loader could not read for damage, each object once, named (never
    /// waiting).
    pub damaged: Vec<String>,
}

/// A PVS walk over `db`'s precomputed visibility as `cfg` says, the poses coming from
/// `viewer`: the walk session with the PVS mode (or, never waiting, its form with a
/// loader thread). Each frame's figures and its time on the viewer's thread, ms, go to
/// `each` as the frame ends.
pub(crate) fn walk_live<'db>(
    db: &'db Database,
    cfg: PvsWalkConfig,
    lods: &mut WalkLods<'db>,
    tick: impl FnMut(usize),
    viewer: &mut dyn Viewer,
    each: impl FnMut((PvsFrame, f64)) -> Result<()>,
) -> Result<PvsRun> {
    let source = StoredPvs::new(db)?;
    let rule = cfg.prefetch.rule()?;
    if cfg.never_wait {
        return super::pvs_never_wait::walk_live(
            db, &source, &*rule, cfg.pace, lods, tick, viewer, each,
        );
    }
    let rule: &dyn PrefetchArea = &*rule;
    let client = PvsClient::new(&source, rule, THESIS_CAPACITY)?;
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
    session::run_each(&mut mode, viewer, lods, tick, each)?;
    Ok(PvsRun::default())
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

/// A PVS frame retrieved at `started`, finished now: its figures and its time, ms.
pub(super) fn finish_timed(pending: Option<(PvsFrame, Instant)>) -> Result<(PvsFrame, f64)> {
    let (frame, started) =
        pending.ok_or_else(|| Error::Invalid("a frame finished before it was retrieved".into()))?;
    Ok((frame, started.elapsed().as_secs_f64() * 1e3))
}

/// What a PVS frame cost, for a display beside the picture; `damaged`, the objects
/// left out since the last frame.
pub(super) fn figures(
    (frame, ms): &(PvsFrame, f64),
    buffer: &ObjectBuffer,
    damaged: Vec<String>,
) -> FrameFigures {
    FrameFigures {
        pages: frame.pages,
        walk_ms: *ms,
        objects_buffered: buffer.len(),
        objects_drawn: frame.drawn,
        visual_misses: frame.visual_misses,
        cell: frame.cell.map_or_else(
            || "outside every viewcell".into(),
            |c| format!("viewcell {c}"),
        ),
        damaged,
        ..Default::default()
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
