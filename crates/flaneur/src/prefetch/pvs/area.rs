//! The prefetching area: the cells whose PVS must be on the client when the viewer
//! stands at a position. SNP and PBNP differ only in this choice; the transaction, the
//! delta and the cache that follow are the same for both (`client`).

use super::grid::{Cell, Position, ViewcellGrid};
use crate::error::Result;

/// The cells that must be cached at one position: the current cell, then the
/// neighbours, all inside the grid. Whether a viewcell lies in each is the PVS
/// source's business, not the area's.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Area {
    /// The cell the viewer stands in.
    pub current: Cell,
    /// The current cell first.
    pub cells: Vec<Cell>,
}

impl Area {
    /// The area made of `current` and its neighbours at the `(row, column)` offsets
    /// given, those outside the grid left out.
    pub fn around(grid: &ViewcellGrid, current: Cell, offsets: &[(i32, i32)]) -> Area {
        let mut cells = vec![current];
        cells.extend(
            offsets
                .iter()
                .filter(|&&o| o != (0, 0))
                .filter_map(|&(dr, dc)| grid.offset(current, dr, dc)),
        );
        Area { current, cells }
    }
}

/// A prefetching rule: SNP ([`Snp`](super::Snp)) or PBNP ([`Pbnp`](super::Pbnp)).
pub trait PrefetchArea {
    /// The area that must be cached while the viewer stands at `p`; an error for a
    /// position that is not finite or lies outside the grid.
    fn area(&self, grid: &ViewcellGrid, p: Position) -> Result<Area>;

    /// A short name for reports ("SNP", "PBNP").
    fn name(&self) -> &'static str;
}
