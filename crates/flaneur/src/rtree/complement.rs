//! CSearch — Shou 2002, §4.2.2, Fig. 4.5: the complement query C − (C₁ ∪ … ∪ Cᵢ).
//!
//! Leaf entries qualify when they overlap C and none of the history cells, so the
//! result is exactly `range(C) − ∪ range(Cᵢ)` whatever the descent rule below.
//!
//! Internal entries, two rules (`Coverlap`):
//! - `Thesis`: enter when the MBR overlaps C and complement-overlaps every history
//!   cell (COverlap = "not completely contained in": some corner outside the cell).
//! - `Clipped` (our default, a departure): enter when the part of the MBR inside C is
//!   not covered by the union of the history cells. Every object of the subtree lies
//!   in the MBR, so its part inside C lies in that clipped box; if the union covers the
//!   clipped box, an object that overlaps C overlaps some history cell and cannot
//!   qualify. The result is the same; the pages are fewer, because a node larger than
//!   a cell (every upper node, when cells are small) is never inside one history cell
//!   but its part inside C often is inside their union. This is the thesis's
//!   TentativeComplementSearch (Fig. 4.4) made cheap: for boxes, "is B covered by a
//!   union of boxes" is a few box subtractions, no BSP tree.

use super::search::Selection;
use crate::geom::{covered, Aabb};

/// How CSearch decides to enter a subtree.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum Coverlap {
    /// Fig. 4.5 as written: not contained in any single history cell.
    Thesis,
    /// The MBR clipped to C, not covered by the union of the history cells.
    #[default]
    Clipped,
}

impl std::str::FromStr for Coverlap {
    type Err = String;

    fn from_str(s: &str) -> Result<Coverlap, String> {
        match s {
            "thesis" => Ok(Coverlap::Thesis),
            "clipped" => Ok(Coverlap::Clipped),
            _ => Err(format!("unknown COverlap rule '{s}' (thesis, clipped)")),
        }
    }
}

pub struct Complement<'a> {
    pub cell: Aabb,
    pub history: &'a [Aabb],
    pub rule: Coverlap,
}

impl Selection for Complement<'_> {
    #[inline]
    fn descend(&self, mbr: &Aabb) -> bool {
        let Some(inside) = self.cell.intersection(mbr) else {
            return false;
        };
        match self.rule {
            Coverlap::Thesis => self.history.iter().all(|h| !h.contains(mbr)),
            Coverlap::Clipped => !covered(inside, self.history),
        }
    }

    #[inline]
    fn select(&self, bounds: &Aabb) -> bool {
        // Newest first: on a walk the latest cells are the likeliest to hold an object.
        self.cell.overlaps(bounds) && self.history.iter().rev().all(|h| !h.overlaps(bounds))
    }
}
