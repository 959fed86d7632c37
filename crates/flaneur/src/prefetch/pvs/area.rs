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

/// What the client has measured of the walk so far, for a rule that looks further
/// ahead the longer its answers take and the faster the viewer goes
/// ([`Lanp`](super::Lanp)). Both are measured by the client, never given: the round
/// trip from the transactions it has had answered, the motion from the positions it
/// has looked from.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Observed {
    /// Steps from asking to holding, the longest of the recent answers (or the age of
    /// the oldest unanswered transaction, if longer); 0 before any answer.
    pub round_trip: u32,
    /// The viewer's last step, metres (east, south); zero before it has moved.
    pub heading: (f64, f64),
    /// The viewer's speed, metres per step: the longest of its recent steps.
    pub speed: f64,
}

/// A prefetching rule: SNP ([`Snp`](super::Snp)), PBNP ([`Pbnp`](super::Pbnp)) or ours,
/// LANP ([`Lanp`](super::Lanp)).
pub trait PrefetchArea {
    /// The area that must be cached while the viewer stands at `p`; an error for a
    /// position that is not finite or lies outside the grid.
    fn area(&self, grid: &ViewcellGrid, p: Position) -> Result<Area>;

    /// The area at `p` given what the client has `seen` and which cells have a
    /// viewcell (`walkable`); the cells come in the order they are wanted, in case the
    /// cache cannot take them all. SNP and PBNP look at neither: their area is
    /// [`area`](Self::area)'s.
    fn area_seen(
        &self,
        grid: &ViewcellGrid,
        p: Position,
        seen: &Observed,
        walkable: &dyn Fn(Cell) -> Result<bool>,
    ) -> Result<Area> {
        let _ = (seen, walkable);
        self.area(grid, p)
    }

    /// Whether the cache may replace neighbours of the current cell that the area does
    /// not want, when it has no other room for the cells the area does (§7.4 keeps every
    /// neighbour; a rule whose area reaches past them may need their room). SNP and
    /// PBNP: no.
    fn replaces_neighbours(&self) -> bool {
        false
    }

    /// Whether the client's cache grows to hold the rule's whole area when it is
    /// larger than the cache (never shrinking again): a rule whose area is what the
    /// viewer may reach before an answer comes (`Lanp`). SNP and PBNP: no, their
    /// area always fits the thesis's 9 entries.
    fn grows_cache(&self) -> bool {
        false
    }

    /// A short name for reports ("SNP", "PBNP").
    fn name(&self) -> &'static str;
}
