//! Where the prefetcher gets PVS rows from: the server's boolean table T of §7.3, one
//! row S_i per viewcell. A small trait, so that the prefetcher runs unchanged over a
//! database's precomputed visibility ([`StoredPvs`](super::StoredPvs)) and over the
//! tables an experiment or a test makes up.

use super::grid::{Cell, ViewcellGrid};
use crate::error::Result;

/// An object's id, as the database numbers objects.
pub type ObjectId = u64;

/// A table of potentially visible sets over a viewcell grid.
///
/// ```
/// use flaneur::prefetch::pvs::{Cell, ObjectId, Position, PvsSource, ViewcellGrid};
/// use flaneur::{Error, Result};
///
/// /// Two cells side by side: a street that sees objects 1, 2 and 4, and a building.
/// struct Corner {
///     grid: ViewcellGrid,
/// }
///
/// impl PvsSource for Corner {
///     fn grid(&self) -> &ViewcellGrid {
///         &self.grid
///     }
///     fn scene_objects(&self) -> u64 {
///         10
///     }
///     fn is_viewcell(&self, cell: Cell) -> Result<bool> {
///         Ok(cell == Cell::new(0, 0))
///     }
///     fn pvs(&self, cell: Cell) -> Result<Vec<ObjectId>> {
///         match self.is_viewcell(cell)? {
///             true => Ok(vec![1, 2, 4]),
///             false => Err(Error::Pvs(format!("cell {cell} has no viewcell"))),
///         }
///     }
/// }
///
/// let corner = Corner { grid: ViewcellGrid::new(Position::new(0.0, 0.0), 20.0, 1, 2)? };
/// let here = corner.grid().cell_of(Position::new(5.0, 5.0))?;
/// assert_eq!(corner.pvs(here)?, [1, 2, 4]);
/// assert!(!corner.is_viewcell(Cell::new(0, 1))?);
/// assert!(corner.pvs(Cell::new(0, 1)).is_err());
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

    /// The rows of `cells` are about to be read, one [`pvs`](Self::pvs) each: a source
    /// that reads over a network may fetch them together. A hint; by default nothing.
    fn announce(&self, cells: &[Cell]) -> Result<()> {
        let _ = cells;
        Ok(())
    }
}
