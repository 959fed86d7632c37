//! One client of §7.4: before each frame it checks the viewer's position and, when the
//! prefetching area there holds cells it has not cached, runs one prefetching
//! transaction: the rows of those cells are requested, only ΔS is sent
//! (delta-transmission), and the cache is updated. The rule that picks the area (SNP
//! or PBNP) is the only thing that differs between the algorithms.

use super::area::PrefetchArea;
use super::cache::ClientCache;
use super::delta::delta;
use super::grid::{Cell, Position};
use super::source::{ObjectId, PvsSource};
use crate::error::{Error, Result};

/// One prefetching transaction.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Transaction {
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
    /// already cached.
    pub transaction: Option<Transaction>,
    /// On entering a cell: objects of its PVS the client did not hold, which the
    /// viewer would see missing until this position's transaction arrives.
    pub visual_misses: usize,
}

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
/// # Ok::<(), flaneur::Error>(())
/// ```
pub struct PvsClient<'a, S: PvsSource + ?Sized, A: PrefetchArea + ?Sized> {
    source: &'a S,
    rule: &'a A,
    cache: ClientCache,
    last: Option<Cell>,
}

impl<'a, S: PvsSource + ?Sized, A: PrefetchArea + ?Sized> PvsClient<'a, S, A> {
    /// A client with an empty cache of `capacity` entries (at least 9).
    pub fn new(source: &'a S, rule: &'a A, capacity: usize) -> Result<Self> {
        Ok(PvsClient {
            source,
            rule,
            cache: ClientCache::new(capacity)?,
            last: None,
        })
    }

    /// The client's cache of PVS rows and objects.
    pub fn cache(&self) -> &ClientCache {
        &self.cache
    }

    /// The viewer is at `p`: prefetch what its area needs. An error for a position
    /// that is not finite, lies outside the grid or in a cell without a viewcell.
    pub fn step(&mut self, p: Position) -> Result<StepOutcome> {
        let area = self.rule.area(self.source.grid(), p)?;
        let current = area.current;
        if !self.source.is_viewcell(current)? {
            return Err(Error::Pvs(format!(
                "position {p} lies in cell {current}, which has no viewcell (the viewer cannot stand there)"
            )));
        }
        let mut wanted = Vec::with_capacity(area.cells.len());
        for cell in area.cells {
            if cell == current || self.source.is_viewcell(cell)? {
                wanted.push(cell);
            }
        }
        self.cache.touch(&wanted);
        let entered = self.last.is_some_and(|l| l != current);
        self.last = Some(current);
        let missing: Vec<Cell> = wanted
            .into_iter()
            .filter(|&c| !self.cache.contains(c))
            .collect();
        if missing.is_empty() {
            return Ok(StepOutcome {
                cell: current,
                entered,
                transaction: None,
                visual_misses: 0,
            });
        }
        let rows = missing
            .iter()
            .map(|&c| Ok((c, self.source.pvs(c)?)))
            .collect::<Result<Vec<_>>>()?;
        let visual_misses = match rows.iter().find(|(c, _)| *c == current) {
            Some((_, pvs)) if entered => pvs.iter().filter(|&&id| !self.cache.holds(id)).count(),
            _ => 0,
        };
        let requested: Vec<&[ObjectId]> = rows.iter().map(|(_, r)| &r[..]).collect();
        let sent = delta(&requested, |id| self.cache.holds(id));
        let admitted = self.cache.admit(current, rows)?;
        Ok(StepOutcome {
            cell: current,
            entered,
            transaction: Some(Transaction {
                requested: missing,
                sent,
                evicted: admitted.evicted,
                dropped: admitted.dropped,
            }),
            visual_misses,
        })
    }
}
