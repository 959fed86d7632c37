//! One client of §7.4: before each frame it checks the viewer's position and, when the
//! prefetching area there holds cells it has not cached, runs one prefetching
//! transaction: the rows of those cells are requested, only ΔS is sent
//! (delta-transmission), and the cache is updated. The rule that picks the area (SNP,
//! PBNP or LANP) is the only thing that differs between the algorithms.
//!
//! Latency (ours; the thesis counts transactions, it does not time them): a
//! transaction may be answered later than it is asked ([`PvsClient::look`], then
//! [`PvsClient::deliver`]). The cache's table changes when the client asks — the
//! entries it asks for are reserved and the ones they replace go — so the cells held,
//! the rows asked for, ΔS and the swaps do not depend on when answers come; only the
//! objects *on hand*, those whose answer has come, do. A frame draws what is on hand,
//! and an object of the current cell's PVS that is not is a visual miss. With every
//! answer at once ([`PvsClient::step`]) the objects on hand are the cache's.

use std::collections::{HashSet, VecDeque};

use super::area::{Observed, PrefetchArea};
use super::cache::ClientCache;
use super::delta::delta;
use super::grid::{Cell, Position};
use super::source::{ObjectId, PvsSource};
use crate::error::{Error, Result};

/// One prefetching transaction.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Transaction {
    /// The client's number for it, from 0 in the order asked: what
    /// [`PvsClient::deliver`] takes.
    pub id: u64,
    /// The cells whose PVS rows were requested: those of the area not cached.
    pub requested: Vec<Cell>,
    /// ΔS, the objects sent, ascending.
    pub sent: Vec<ObjectId>,
    /// Entries replaced to make room: one cache swap each.
    pub evicted: Vec<Cell>,
    /// Objects deleted from the client with the evicted entries.
    pub dropped: usize,
}

/// What one position of the walk cost.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StepOutcome {
    /// The cell the position lies in.
    pub cell: Cell,
    /// The viewer came into `cell` from another cell at this position (never at the
    /// first position of a walk, which starts from an empty cache).
    pub entered: bool,
    /// This position's prefetching transaction; `None` when every cell of its area was
    /// already cached or asked for.
    pub transaction: Option<Transaction>,
    /// Objects of `cell`'s PVS not on hand when the viewer stood here, before this
    /// position's transaction: the frame drawn here lacks them. Not counted at the
    /// first position, which starts from an empty cache.
    pub visual_misses: usize,
}

/// A transaction asked and not yet answered.
struct InFlight {
    id: u64,
    asked: u64,
    sent: Vec<ObjectId>,
}

/// The recent answers and steps the client measures the round trip and the speed
/// over.
const RECENT: usize = 8;

/// The most entries a growing cache (`PrefetchArea::grows_cache`) grows to: an area
/// wider than this is cut, the nearest of its cells kept (4,096 viewcells is a reach of
/// about 36 cells every way).
const MAX_GROWN: usize = 4096;

/// A client walking over a PVS source with a prefetching rule.
///
/// ```
/// use flaneur::prefetch::pvs::{Cell, ObjectId, Pbnp, Position, PvsClient, PvsSource, ViewcellGrid};
/// # use flaneur::Result;
/// // A street of three cells west to east, each seeing three objects, the next cell's
/// // view shifted one object on.
/// struct Street(ViewcellGrid);
/// impl PvsSource for Street {
///     fn grid(&self) -> &ViewcellGrid { &self.0 }
///     fn scene_objects(&self) -> u64 { 10 }
///     fn is_viewcell(&self, cell: Cell) -> Result<bool> { Ok(self.0.contains(cell)) }
///     fn pvs(&self, cell: Cell) -> Result<Vec<ObjectId>> {
///         let first = u64::from(cell.col) + 1;
///         Ok((first..first + 3).collect())
///     }
/// }
/// let table = Street(ViewcellGrid::new(Position::new(0.0, 0.0), 20.0, 1, 3)?);
/// let pbnp = Pbnp::new(0.25)?;
/// let mut client = PvsClient::new(&table, &pbnp, 9)?;
/// let start = client.step(Position::new(30.0, 10.0))?; // the middle of cell (0, 1)
/// assert_eq!(start.transaction.unwrap().sent, [2, 3, 4]);
/// // Leaning east: cell (0, 2) comes, and only object 5 is new.
/// let lean = client.step(Position::new(37.0, 10.0))?;
/// assert_eq!(lean.transaction.unwrap().sent, [5]);
/// // Crossing into it costs nothing more: it was prefetched.
/// let cross = client.step(Position::new(41.0, 10.0))?;
/// assert!(cross.entered && cross.transaction.is_none() && cross.visual_misses == 0);
/// // With answers that take time: object 1 is asked for when leaning west, but not on
/// // hand until its answer comes.
/// let back = client.look(Position::new(23.0, 10.0))?;
/// let asked = back.transaction.unwrap();
/// assert_eq!(asked.sent, [1]);
/// assert!(!client.on_hand(1) && client.unanswered() == 1);
/// client.deliver(asked.id)?;
/// assert!(client.on_hand(1) && client.observed().round_trip == 0);
/// assert!(client.deliver(asked.id).is_err());
/// # Ok::<(), flaneur::Error>(())
/// ```
pub struct PvsClient<'a, S: PvsSource + ?Sized, A: PrefetchArea + ?Sized> {
    source: &'a S,
    rule: &'a A,
    cache: ClientCache,
    last: Option<Cell>,
    /// The client's clock at its latest look, in steps; `None` before the first.
    now: Option<u64>,
    next_id: u64,
    in_flight: Vec<InFlight>,
    /// The objects whose answer has come and which the cache still holds.
    on_hand: HashSet<ObjectId>,
    /// The latest round trips measured, steps.
    trips: VecDeque<u64>,
    /// The latest positions looked from, each with the last time the viewer stood
    /// there.
    seen_at: VecDeque<(Position, u64)>,
}

impl<'a, S: PvsSource + ?Sized, A: PrefetchArea + ?Sized> PvsClient<'a, S, A> {
    /// A client with an empty cache of `capacity` entries (at least 9).
    pub fn new(source: &'a S, rule: &'a A, capacity: usize) -> Result<Self> {
        Ok(PvsClient {
            source,
            rule,
            cache: ClientCache::new(capacity)?,
            last: None,
            now: None,
            next_id: 0,
            in_flight: Vec::new(),
            on_hand: HashSet::new(),
            trips: VecDeque::new(),
            seen_at: VecDeque::new(),
        })
    }

    /// The client's cache of PVS rows and objects.
    pub fn cache(&self) -> &ClientCache {
        &self.cache
    }

    /// Whether object `id` is on hand: held, and its answer come.
    pub fn on_hand(&self, id: ObjectId) -> bool {
        self.on_hand.contains(&id)
    }

    /// Transactions asked and not yet answered.
    pub fn unanswered(&self) -> usize {
        self.in_flight.len()
    }

    /// The viewer is at `p` and every answer comes at once: [`look`](Self::look), then
    /// [`deliver`](Self::deliver) this position's transaction. An error for a position
    /// that is not finite, lies outside the grid or in a cell without a viewcell.
    pub fn step(&mut self, p: Position) -> Result<StepOutcome> {
        let out = self.look(p)?;
        if let Some(t) = &out.transaction {
            self.deliver(t.id)?;
        }
        Ok(out)
    }

    /// What the client has measured: the round trip and the viewer's motion.
    pub fn observed(&self) -> Observed {
        let oldest = self
            .in_flight
            .iter()
            .map(|t| self.clock() - t.asked)
            .max()
            .unwrap_or(0);
        let round_trip = self.trips.iter().copied().max().unwrap_or(0).max(oldest);
        let steps = self.seen_at.iter().zip(self.seen_at.iter().skip(1));
        let speed = steps
            .map(|((a, ta), (b, tb))| a.distance(*b) / (tb - ta).max(1) as f64)
            .fold(0.0, f64::max);
        let heading = match (self.seen_at.len(), self.seen_at.back()) {
            (n, Some((b, _))) if n >= 2 => {
                let a = self.seen_at[n - 2].0;
                (b.x - a.x, b.z - a.z)
            }
            _ => (0.0, 0.0),
        };
        Observed {
            round_trip: u32::try_from(round_trip).unwrap_or(u32::MAX),
            heading,
            speed,
        }
    }

    /// The clock of the latest look (0 before the first).
    fn clock(&self) -> u64 {
        self.now.unwrap_or(0)
    }

    /// One step of the client's clock with the viewer at `p`: the frame's visual
    /// misses are counted, and the cells of the area not cached are asked for; their
    /// objects are on hand once [`deliver`](Self::deliver) is told the answer came.
    /// Errors as [`step`](Self::step)'s.
    pub fn look(&mut self, p: Position) -> Result<StepOutcome> {
        self.look_at(p, self.now.map_or(0, |n| n + 1))
    }

    /// [`look`](Self::look) at time `at` of a clock of the caller's (a walk's frame
    /// number), for a client that does not look at every step: round trips and speed
    /// are then measured in that clock's steps. An error for a time before the last
    /// look's.
    pub fn look_at(&mut self, p: Position, at: u64) -> Result<StepOutcome> {
        if self.now.is_some_and(|n| at < n) {
            return Err(Error::Invalid(format!(
                "a PVS client looked at step {at}, before its last look at step {}",
                self.clock()
            )));
        }
        let grid = self.source.grid();
        let current = grid.cell_of(p)?;
        if !self.source.is_viewcell(current)? {
            return Err(Error::Pvs(format!(
                "position {p} lies in cell {current}, which has no viewcell (the viewer cannot stand there)"
            )));
        }
        match self.seen_at.back_mut() {
            Some((q, t)) if *q == p => *t = at,
            _ => {
                if self.seen_at.len() > RECENT {
                    self.seen_at.pop_front();
                }
                self.seen_at.push_back((p, at));
            }
        }
        let first = self.now.is_none();
        self.now = Some(at);
        let source = self.source;
        let walkable = |c: Cell| source.is_viewcell(c);
        let area = self.rule.area_seen(grid, p, &self.observed(), &walkable)?;
        let mut wanted = Vec::with_capacity(area.cells.len());
        for cell in area.cells {
            if cell == current || self.source.is_viewcell(cell)? {
                wanted.push(cell);
            }
        }
        if wanted.first() != Some(&current) {
            wanted.retain(|&c| c != current);
            wanted.insert(0, current);
        }
        if self.rule.grows_cache() {
            self.cache.grow_to(wanted.len().min(MAX_GROWN));
        }
        self.cache.touch(&wanted);
        let entered = self.last.is_some_and(|l| l != current);
        self.last = Some(current);
        let visual_misses = match (first, self.cache.pvs(current)) {
            (true, _) => 0,
            (false, Some(pvs)) => pvs.iter().filter(|id| !self.on_hand(**id)).count(),
            (false, None) => self
                .source
                .pvs(current)?
                .iter()
                .filter(|id| !self.on_hand(**id))
                .count(),
        };
        let mut missing: Vec<Cell> = wanted
            .iter()
            .copied()
            .filter(|&c| !self.cache.contains(c))
            .collect();
        // A far-looking area may want more than the cache can take: the first wanted
        // come first, and the current cell always fits (at most its neighbours stay).
        let neighbours_go = self.rule.replaces_neighbours();
        missing.truncate(self.cache.room(current, &wanted, neighbours_go));
        if missing.is_empty() {
            return Ok(StepOutcome {
                cell: current,
                entered,
                transaction: None,
                visual_misses,
            });
        }
        // A hint: a row that cannot be fetched fails when it is read below.
        let _ = self.source.announce(&missing);
        let rows = missing
            .iter()
            .map(|&c| Ok((c, self.source.pvs(c)?)))
            .collect::<Result<Vec<_>>>()?;
        let requested: Vec<&[ObjectId]> = rows.iter().map(|(_, r)| &r[..]).collect();
        let sent = delta(&requested, |id| self.cache.holds(id));
        let admitted = self
            .cache
            .admit_keeping(current, rows, &wanted, neighbours_go)?;
        if admitted.dropped > 0 {
            let cache = &self.cache;
            self.on_hand.retain(|&id| cache.holds(id));
        }
        let id = self.next_id;
        self.next_id += 1;
        self.in_flight.push(InFlight {
            id,
            asked: at,
            sent: sent.clone(),
        });
        Ok(StepOutcome {
            cell: current,
            entered,
            transaction: Some(Transaction {
                id,
                requested: missing,
                sent,
                evicted: admitted.evicted,
                dropped: admitted.dropped,
            }),
            visual_misses,
        })
    }

    /// Transaction `id`'s answer has come, at the client's latest look: its objects that
    /// the cache still holds are on hand, and its round trip is measured. An error for a
    /// transaction not asked or already answered.
    pub fn deliver(&mut self, id: u64) -> Result<()> {
        self.deliver_at(id, self.clock())
    }

    /// [`deliver`](Self::deliver) at time `at` of the clock [`look_at`](Self::look_at)
    /// is given (a time before the latest look counts as that look's).
    pub fn deliver_at(&mut self, id: u64, at: u64) -> Result<()> {
        let i = self
            .in_flight
            .iter()
            .position(|t| t.id == id)
            .ok_or_else(|| {
                Error::Pvs(format!(
                    "transaction {id} is not awaiting an answer (not asked, or answered already)"
                ))
            })?;
        let t = self.in_flight.swap_remove(i);
        for o in t.sent {
            if self.cache.holds(o) {
                self.on_hand.insert(o);
            }
        }
        if self.trips.len() == RECENT {
            self.trips.pop_front();
        }
        self.trips.push_back(at.max(self.clock()) - t.asked);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::prefetch::pvs::{Snp, ViewcellGrid};

    /// A street of `n` cells west to east, cell `c` seeing objects c..c+3.
    struct Street(ViewcellGrid);

    impl PvsSource for Street {
        fn grid(&self) -> &ViewcellGrid {
            &self.0
        }
        fn scene_objects(&self) -> u64 {
            100
        }
        fn is_viewcell(&self, cell: Cell) -> Result<bool> {
            Ok(self.0.contains(cell))
        }
        fn pvs(&self, cell: Cell) -> Result<Vec<ObjectId>> {
            let first = u64::from(cell.col);
            Ok((first..first + 3).collect())
        }
    }

    fn street() -> Street {
        Street(ViewcellGrid::new(Position::new(0.0, 0.0), 10.0, 1, 20).unwrap())
    }

    #[test]
    fn a_callers_clock_measures_round_trips_and_speed_in_its_steps() {
        let table = street();
        let mut client = PvsClient::new(&table, &Snp, 9).unwrap();
        // Looks at frames 0 and 10, 6 m apart; the second's answer comes at frame 14.
        let first = client.look_at(Position::new(5.0, 5.0), 0).unwrap();
        client.deliver_at(first.transaction.unwrap().id, 0).unwrap();
        let t = client.look_at(Position::new(11.0, 5.0), 10).unwrap();
        let t = t.transaction.expect("cell 2 is new");
        assert_eq!(client.observed().speed, 0.6);
        client.deliver_at(t.id, 14).unwrap();
        assert_eq!(client.observed().round_trip, 4);
        // Standing still, then a step of 3 m in one frame: 3 m a step, not 3 m over
        // the frames stood.
        client.look_at(Position::new(11.0, 5.0), 20).unwrap();
        client.look_at(Position::new(14.0, 5.0), 21).unwrap();
        assert_eq!(client.observed().speed, 3.0);
        // An unanswered transaction's age counts as soon as it exceeds the answers'.
        let far = client.look_at(Position::new(45.0, 5.0), 22).unwrap();
        assert!(far.transaction.is_some());
        client.look_at(Position::new(45.0, 5.0), 30).unwrap();
        assert_eq!(client.observed().round_trip, 8);
    }

    #[test]
    fn a_clock_that_runs_back_is_refused() {
        let table = street();
        let mut client = PvsClient::new(&table, &Snp, 9).unwrap();
        client.look_at(Position::new(5.0, 5.0), 7).unwrap();
        let e = client.look_at(Position::new(5.0, 5.0), 6).unwrap_err();
        assert!(
            e.to_string().contains("before its last look at step 7"),
            "{e}"
        );
        // Plain looks go on from the caller's clock.
        client.look(Position::new(5.0, 5.0)).unwrap();
        client.look_at(Position::new(5.0, 5.0), 8).unwrap();
    }
}
