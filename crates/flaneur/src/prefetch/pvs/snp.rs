//! SNP, the simple neighbour prefetch (Koltun et al., as Zheng 2007 §7.2.1 and Fig. 7.1
//! describe it): the current viewcell and all eight neighbours must be cached, so that
//! crossing a side brings in three new cells and crossing a corner five.

use super::area::{Area, PrefetchArea};
use super::grid::{Position, ViewcellGrid, NEIGHBOURS};
use crate::error::Result;

/// The simple neighbour prefetch.
///
/// ```
/// use flaneur::prefetch::pvs::{Cell, Position, PrefetchArea, Snp, ViewcellGrid};
/// let grid = ViewcellGrid::new(Position::new(0.0, 0.0), 20.0, 5, 5)?;
/// let area = Snp.area(&grid, Position::new(50.0, 50.0))?;
/// assert_eq!(area.current, Cell::new(2, 2));
/// assert_eq!(area.cells.len(), 9);
/// // At the grid's corner only four cells exist.
/// assert_eq!(Snp.area(&grid, Position::new(1.0, 1.0))?.cells.len(), 4);
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Snp;

impl PrefetchArea for Snp {
    fn area(&self, grid: &ViewcellGrid, p: Position) -> Result<Area> {
        Ok(Area::around(grid, grid.cell_of(p)?, &NEIGHBOURS))
    }

    fn name(&self) -> &'static str {
        "SNP"
    }
}
