//! Where the prefetcher gets PVS rows from: the server's boolean table T of §7.3, one
//! row S_i per viewcell. A small trait, so that the prefetcher runs unchanged over the
//! synthetic table of the experiments ([`PvsTable`](super::PvsTable)) and over a
//! database's precomputed visibility.

use super::grid::{Cell, ViewcellGrid};
use crate::error::Result;

/// An object's id, as the database numbers objects.
pub type ObjectId = u64;

/// A table of potentially visible sets over a viewcell grid.
///
/// ```
/// use flaneur::prefetch::pvs::{Cell, Position, PvsSource, PvsTable, ViewcellGrid};
/// let grid = ViewcellGrid::new(Position::new(0.0, 0.0), 20.0, 1, 2)?;
/// let mut table = PvsTable::new(grid, 10)?;
/// table.insert(Cell::new(0, 0), vec![4, 1, 2])?;
/// assert_eq!(table.pvs(Cell::new(0, 0))?, [1, 2, 4]);
/// assert!(!table.is_viewcell(Cell::new(0, 1))?); // inside a building, say
/// assert!(table.pvs(Cell::new(0, 1)).is_err());
/// # Ok::<(), flaneur::Error>(())
/// ```
pub trait PvsSource {
    /// The grid the table was computed on; the prefetcher walks the same one.
    fn grid(&self) -> &ViewcellGrid;

    /// Objects in the whole scene (the PVS share is measured against it).
    fn scene_objects(&self) -> u64;

    /// Whether a viewcell lies at `cell`. Cells where the viewer cannot stand (inside a
    /// building) have none: they are never prefetched and never take a cache entry.
    fn is_viewcell(&self, cell: Cell) -> Result<bool>;

    /// The PVS of the viewcell at `cell`: object ids, ascending, without repeats. An
    /// error when no viewcell lies there or the table cannot be read.
    fn pvs(&self, cell: Cell) -> Result<Vec<ObjectId>>;
}
