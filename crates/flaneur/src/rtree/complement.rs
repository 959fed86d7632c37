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
use crate::geom::Aabb;

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

/// Pieces the subtraction may keep before it gives up and answers "not covered"
/// (which only costs a page read, never a result).
const MAX_PIECES: usize = 256;

/// Whether the closed box `b` lies inside the union of `cells`.
///
/// Subtracts each cell from the pieces left so far. A piece is kept only where some
/// of it lies strictly outside the cell, so the answer is exact for closed boxes: a
/// box that merely touches the union's boundary from inside is covered.
pub fn covered(b: Aabb, cells: &[Aabb]) -> bool {
    // The common cases on a walk, without allocating: one cell holds it all, or no
    // cell touches it.
    if cells.iter().rev().any(|h| h.contains(&b)) {
        return true;
    }
    if !cells.iter().any(|h| h.overlaps(&b)) {
        return false;
    }
    let mut pieces = vec![b];
    for h in cells.iter().filter(|h| h.overlaps(&b)) {
        let mut next = Vec::with_capacity(pieces.len());
        for p in pieces {
            subtract(p, h, &mut next);
        }
        if next.is_empty() {
            return true;
        }
        if next.len() > MAX_PIECES {
            return false;
        }
        pieces = next;
    }
    pieces.is_empty()
}

/// Pushes the parts of `p` outside `h` (at most six boxes, as closed boxes).
fn subtract(p: Aabb, h: &Aabb, out: &mut Vec<Aabb>) {
    if !p.overlaps(h) {
        out.push(p);
        return;
    }
    let mut rest = p;
    for axis in 0..3 {
        if rest.min[axis] < h.min[axis] {
            let mut piece = rest;
            piece.max[axis] = h.min[axis];
            out.push(piece);
            rest.min[axis] = h.min[axis];
        }
        if rest.max[axis] > h.max[axis] {
            let mut piece = rest;
            piece.min[axis] = h.max[axis];
            out.push(piece);
            rest.max[axis] = h.max[axis];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(s: &str) -> Aabb {
        s.parse().unwrap()
    }

    #[test]
    fn union_covers_what_no_single_cell_does() {
        let cells = [b("0,0,0,10,10,10"), b("10,0,0,20,10,10")];
        assert!(covered(b("5,1,1,15,9,9"), &cells));
        assert!(!covered(b("5,1,1,21,9,9"), &cells));
        assert!(covered(b("10,0,0,10,10,10"), &cells)); // flat, on the seam
        assert!(!covered(b("5,1,1,15,9,9"), &cells[..1]));
        assert!(covered(b("5,1,1,15,9,9"), &[b("0,0,0,20,10,10")]));
        assert!(!covered(b("5,1,1,15,9,9"), &[]));
    }

    #[test]
    fn a_gap_between_cells_is_not_covered() {
        let cells = [b("0,0,0,10,10,10"), b("10.5,0,0,20,10,10")];
        assert!(!covered(b("5,1,1,15,9,9"), &cells));
    }
}
