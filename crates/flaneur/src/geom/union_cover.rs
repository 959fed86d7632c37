//! Whether a box lies inside a union of boxes: CSearch's descent rule (`rtree`'s
//! `Coverlap::Clipped`) and the caches' look-ahead ask it of every node and object they
//! consider, so it is exact for closed boxes and cheap in the common cases.

use super::Aabb;

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
