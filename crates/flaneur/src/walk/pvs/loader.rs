//! The loader thread of a PVS walk that never waits (ours): it owns the PVS client and
//! does every read the client needs, the PVS rows of the cells it asks for and the
//! meshes of the objects they send, while the viewer's thread only posts where it stands
//! and takes what has arrived. A position is looked from when the loader is free, at the
//! viewer's frame number, so the client measures its round trip in frames, loading
//! included, and LANP reaches as far as the viewer goes in that time.
//!
//! The objects come a batch at a time, those of the current cell's PVS first, then in
//! the order a never-wait REVIEW walk loads in (`load_order`: ahead before behind,
//! nearest first); a newer position reorders what is still to load. On a database with
//! LODs each object comes first at its coarsest stored level (a few pages, its batch's
//! side by side in the file), and its full mesh once nothing coarse is left to load, as
//! a never-wait REVIEW walk draws coarse first; one whose coarse level cannot be read
//! for damage comes at full detail, named (`damage`). A transaction is delivered to the
//! client when the last of its objects has arrived (or has been left out as damaged, or
//! dropped by the cache).

use std::collections::{HashSet, VecDeque};
use std::sync::{mpsc, Mutex};

use glam::Vec3;

use super::index_entries::IndexEntries;
use crate::database::Database;
use crate::error::{Error, Result};
use crate::prefetch::pvs::{Cell, Position, PrefetchArea, PvsClient, StoredPvs, THESIS_CAPACITY};
use crate::rtree::ObjectEntry;
use crate::walk::buffer::Loaded;
use crate::walk::sink::LeftOut;
use crate::walk::threads::damage::{coarsest_or_full, Damaged};
use crate::walk::threads::load_order::load_order;
use crate::walk::threads::mesh_batch::read_meshes;
use crate::walk::threads::refining::MESHES_ASKED_TOGETHER;

/// Coarsest levels asked for at once: a few pages each and side by side in the file,
/// so a cell's worth comes in the round trips of one batch.
const COARSE_ASKED_TOGETHER: usize = 1024;

/// Full meshes of objects held coarse asked for at once: few, so that the loader looks
/// from the viewer's latest position again soon.
const FINE_ASKED_TOGETHER: usize = 32;

/// Where the viewer stands at one frame, as it posts it to the loader.
#[derive(Clone, Copy, Debug)]
pub(super) struct Stand {
    pub frame: u64,
    pub at: Position,
    pub eye: Vec3,
    pub aim: Vec3,
}

/// The viewer's latest position, as the loader takes it.
pub(super) type Mailbox = crate::walk::threads::mailbox::Mailbox<Stand>;

/// What the loader tells the viewer, in the order it happened.
pub(super) enum Update {
    /// A transaction was asked: the rows of the cells it brought, the cells and objects
    /// the cache let go, and its ΔS and swaps.
    Asked {
        rows: Vec<(Cell, Vec<u64>)>,
        evicted: Vec<Cell>,
        dropped: Vec<u64>,
        sent: usize,
        swaps: usize,
    },
    /// Objects arrived, with their meshes.
    Loaded(Vec<Loaded>),
    /// The client's round trip as measured after a delivery, frames.
    RoundTrip(u32),
    /// A read failed on the network; what it was for is asked for again.
    Retrying(String),
    /// The loader cannot go on.
    Stopped(Error),
}

/// Runs the loader until the walk ends, telling `tx` what it does. `left_out` is kept
/// when the viewer walks on past damaged objects; `damaged` names the coarse levels
/// that could not be read.
pub(super) fn run(
    db: &Database,
    source: &StoredPvs<'_>,
    rule: &(dyn PrefetchArea + Sync),
    mailbox: &Mailbox,
    (left_out, damaged): (Option<&Mutex<LeftOut>>, &Mutex<Damaged>),
    tx: mpsc::Sender<Update>,
) {
    let mut loader = match Loader::new(db, source, rule, (left_out, damaged), &tx) {
        Ok(l) => l,
        Err(e) => {
            let _ = tx.send(Update::Stopped(e));
            return;
        }
    };
    while !mailbox.ended() {
        if let Err(e) = loader.turn(mailbox) {
            let _ = tx.send(Update::Stopped(e));
            return;
        }
    }
}

/// The loader's state between turns.
struct Loader<'a, 't> {
    db: &'a Database,
    client: PvsClient<'a, StoredPvs<'a>, dyn PrefetchArea + Sync + 'a>,
    entries: IndexEntries,
    left_out: Option<&'a Mutex<LeftOut>>,
    damaged: &'a Mutex<Damaged>,
    tx: &'t mpsc::Sender<Update>,
    /// Objects to load, in order.
    queue: VecDeque<u64>,
    /// Whether objects come coarse first (the database has LODs).
    coarse: bool,
    /// Objects held coarse whose full meshes are still to load, in order.
    fine: VecDeque<u64>,
    /// Transactions asked and not delivered, with the objects they still wait for.
    waiting: Vec<(u64, HashSet<u64>)>,
    /// Objects handed to the viewer that the cache still holds.
    handed: HashSet<u64>,
    last: Option<Position>,
}

impl<'a, 't> Loader<'a, 't> {
    fn new(
        db: &'a Database,
        source: &'a StoredPvs<'a>,
        rule: &'a (dyn PrefetchArea + Sync),
        (left_out, damaged): (Option<&'a Mutex<LeftOut>>, &'a Mutex<Damaged>),
        tx: &'t mpsc::Sender<Update>,
    ) -> Result<Self> {
        // Every object's index entry, to read the meshes of what the client holds:
        // read here, so that the viewer's first frame does not wait on the index.
        Ok(Loader {
            db,
            client: PvsClient::new(source, rule, THESIS_CAPACITY)?,
            entries: IndexEntries::read(db)?,
            left_out,
            damaged,
            tx,
            queue: VecDeque::new(),
            coarse: db.has_lods(),
            fine: VecDeque::new(),
            waiting: Vec::new(),
            handed: HashSet::new(),
            last: None,
        })
    }

    /// One turn: look from the viewer's latest position if it moved, then load one
    /// batch; waits for a position when there is nothing to load.
    fn turn(&mut self, mailbox: &Mailbox) -> Result<()> {
        let idle = self.queue.is_empty() && self.fine.is_empty();
        if let Some(stand) = mailbox.take(idle) {
            if self.last != Some(stand.at) {
                self.look(stand)?;
            }
        }
        self.load_batch()?;
        self.deliver(mailbox.now())
    }

    fn look(&mut self, stand: Stand) -> Result<()> {
        let out = match self.client.look_at(stand.at, stand.frame) {
            Ok(out) => out,
            Err(e @ Error::Remote { .. }) => {
                // The row could not be read: the next position posted asks again.
                let _ = self.tx.send(Update::Retrying(e.to_string()));
                return Ok(());
            }
            Err(e) => return Err(e),
        };
        self.last = Some(stand.at);
        if let Some(t) = out.transaction {
            let cache = self.client.cache();
            let mut dropped = Vec::new();
            if t.dropped > 0 {
                dropped = self
                    .handed
                    .iter()
                    .copied()
                    .filter(|&id| !cache.holds(id))
                    .collect();
                self.handed.retain(|&id| cache.holds(id));
                self.queue.retain(|&id| cache.holds(id));
                self.fine.retain(|&id| cache.holds(id));
                for (_, wanted) in &mut self.waiting {
                    wanted.retain(|&id| cache.holds(id));
                }
            }
            let rows = t
                .requested
                .iter()
                .filter_map(|&c| cache.pvs(c).map(|r| (c, r.to_vec())))
                .collect();
            let _ = self.tx.send(Update::Asked {
                rows,
                evicted: t.evicted.clone(),
                dropped,
                sent: t.sent.len(),
                swaps: t.evicted.len(),
            });
            self.queue.extend(&t.sent);
            self.waiting.push((t.id, t.sent.into_iter().collect()));
        }
        self.reorder(out.cell, stand.eye, stand.aim)
    }

    /// What is still to load, the current cell's PVS first, then ahead before behind,
    /// nearest first.
    fn reorder(&mut self, cell: Cell, eye: Vec3, aim: Vec3) -> Result<()> {
        let now: HashSet<u64> = self
            .client
            .cache()
            .pvs(cell)
            .map(|r| r.iter().copied().collect())
            .unwrap_or_default();
        let mut keyed = Vec::with_capacity(self.queue.len());
        for &id in &self.queue {
            keyed.push((
                !now.contains(&id),
                load_order(self.entry(id)?, eye, aim),
                id,
            ));
        }
        keyed.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
        self.queue = keyed.into_iter().map(|(_, _, id)| id).collect();
        Ok(())
    }

    fn entry(&self, id: u64) -> Result<&ObjectEntry> {
        self.entries.get(id)
    }

    /// Loads the next batch, of the queue or else of the full meshes to come, and hands
    /// it to the viewer.
    fn load_batch(&mut self) -> Result<()> {
        let (from_queue, list, most) = match self.queue.is_empty() {
            false if self.coarse => (true, &mut self.queue, COARSE_ASKED_TOGETHER),
            false => (true, &mut self.queue, MESHES_ASKED_TOGETHER),
            true => (false, &mut self.fine, FINE_ASKED_TOGETHER),
        };
        let n = list.len().min(most);
        if n == 0 {
            return Ok(());
        }
        let ids: Vec<u64> = list.drain(..n).collect();
        let batch: Vec<ObjectEntry> = ids
            .into_iter()
            .map(|id| self.entry(id).copied())
            .collect::<Result<_>>()?;
        if !(from_queue && self.coarse) {
            let (loaded, done) = self.load_full(batch, !from_queue)?;
            return self.hand_over(loaded, &done);
        }
        let (mut loaded, full) = match coarsest_or_full(self.db, &batch, self.damaged) {
            Ok(got) => got,
            Err(e @ Error::Remote { .. }) => {
                self.queue.extend(batch.iter().map(|e| e.id));
                let _ = self.tx.send(Update::Retrying(e.to_string()));
                return Ok(());
            }
            // The file changed under the walk: never mix its pages with the old ones'.
            Err(e) => return Err(e),
        };
        self.fine
            .extend(loaded.iter().filter(|o| o.level > 0).map(|o| o.entry.id));
        let mut done: Vec<u64> = loaded.iter().map(|o| o.entry.id).collect();
        // Those whose coarse level is damaged, at full detail: read one by one, which
        // names (or, for a viewer that walks on, leaves out) a damaged mesh too.
        if !full.is_empty() {
            let (more, more_done) = self.load_full(full, false)?;
            loaded.extend(more);
            done.extend(more_done);
        }
        self.hand_over(loaded, &done)
    }

    /// Hands `loaded` to the viewer, and counts the objects `done` with as arrived for
    /// the transactions waiting on them.
    fn hand_over(&mut self, loaded: Vec<Loaded>, done: &[u64]) -> Result<()> {
        self.handed.extend(loaded.iter().map(|o| o.entry.id));
        if !loaded.is_empty() {
            let _ = self.tx.send(Update::Loaded(loaded));
        }
        for (_, wanted) in &mut self.waiting {
            for id in done {
                wanted.remove(id);
            }
        }
        Ok(())
    }

    /// The full meshes of `batch` (`fine`: of objects held coarse), its pages asked for
    /// at once (over HTTP coalesced and in parallel), and the objects done with: loaded
    /// or left out as damaged when the viewer walks on without them. One the network
    /// failed to bring goes back to be asked for again.
    fn load_full(
        &mut self,
        batch: Vec<ObjectEntry>,
        fine: bool,
    ) -> Result<(Vec<Loaded>, Vec<u64>)> {
        let mut again = Vec::new();
        let mut failed = None;
        let loaded = read_meshes(self.db, &batch, self.left_out, |e, err| match err {
            Error::Remote { .. } => {
                again.push(e.id);
                failed = Some(err.to_string());
                Ok(())
            }
            other => Err(other),
        })?;
        match fine {
            true => self.fine.extend(&again),
            false => self.queue.extend(&again),
        }
        if let Some(why) = failed {
            let _ = self.tx.send(Update::Retrying(why));
        }
        // Loaded, or left out as damaged: all but those asked for again.
        let done = batch
            .iter()
            .map(|e| e.id)
            .filter(|id| !again.contains(id))
            .collect();
        Ok((loaded, done))
    }

    /// Delivers, at frame `now`, every transaction whose objects have all arrived.
    fn deliver(&mut self, now: u64) -> Result<()> {
        let mut any = false;
        for (id, _) in self.waiting.iter().filter(|(_, w)| w.is_empty()) {
            self.client.deliver_at(*id, now)?;
            any = true;
        }
        if any {
            self.waiting.retain(|(_, w)| !w.is_empty());
            let trip = self.client.observed().round_trip;
            let _ = self.tx.send(Update::RoundTrip(trip));
        }
        Ok(())
    }
}
