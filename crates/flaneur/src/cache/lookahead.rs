//! What a walk predicts its next searches will be: the cells it expects to query, soonest
//! first, and the cells whose objects it already holds — enough to tell, for a cached
//! node, which of those searches would read it. The path policy (`policy/path.rs`)
//! evicts by it, an online stand-in for the future that Belady's optimum (`belady.rs`)
//! reads from the trace.
//!
//! The cells come from the viewer's motion so far (Shou 2002 §4.2.5, F' = F + k·v, as
//! the REVIEW walk predicts them for its prefetch), never from the accesses to come. The
//! test mirrors CSearch's descent rule (§4.2.2, our `Clipped` rule): a search of cell C
//! against the held cells H enters a node when the part of its MBR inside C is not
//! covered by the union of H, and every predicted cell before C counts as held by then.

use crate::geom::{covered, Aabb};

/// The searches a walk expects next, as it knows them now.
///
/// ```
/// use flaneur::cache::Lookahead;
/// use flaneur::geom::Aabb;
/// let b = |s: &str| s.parse::<Aabb>().unwrap();
/// let ahead = Lookahead {
///     cells: vec![b("0,0,0,10,10,10"), b("10,0,0,20,10,10")],
///     held: vec![b("0,0,0,5,10,10")],
/// };
/// assert_eq!(ahead.first_need(&b("6,1,1,8,2,2")), Some(0));
/// assert_eq!(ahead.first_need(&b("1,1,1,4,2,2")), None, "held already");
/// assert_eq!(ahead.first_need(&b("12,1,1,14,2,2")), Some(1));
/// assert_eq!(ahead.first_need(&b("30,1,1,34,2,2")), None, "off the path");
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Lookahead {
    /// The cells of the predicted searches, in the order the walk expects them.
    pub cells: Vec<Aabb>,
    /// Cells whose objects the walk holds (its CSearch history): a search skips a node
    /// whose part inside its cell they cover.
    pub held: Vec<Aabb>,
}

impl Lookahead {
    /// The index in `cells` of the first predicted search that would read a node of
    /// MBR `mbr`: the first cell the MBR meets outside the held cells and the cells
    /// predicted before it. `None` for a node no predicted search reads, and for an
    /// unknown (empty) MBR.
    pub fn first_need(&self, mbr: &Aabb) -> Option<usize> {
        if mbr.is_empty() {
            return None;
        }
        let mut before: Vec<Aabb> = self.held.clone();
        for (i, cell) in self.cells.iter().enumerate() {
            if let Some(inside) = cell.intersection(mbr) {
                if !covered(inside, &before) {
                    return Some(i);
                }
            }
            before.push(*cell);
        }
        None
    }

    /// Whether the walk predicts nothing (then a policy falls back on recency).
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(s: &str) -> Aabb {
        s.parse().unwrap()
    }

    #[test]
    fn a_node_is_needed_by_the_first_cell_it_meets_outside_what_is_held() {
        let ahead = Lookahead {
            cells: vec![
                b("0,0,0,10,10,10"),
                b("5,0,0,20,10,10"),
                b("0,0,0,30,10,10"),
            ],
            held: vec![],
        };
        // Inside the first cell: its search.
        assert_eq!(ahead.first_need(&b("1,1,1,2,2,2")), Some(0));
        // Within the first cell's part of the second: the second search skips it, the
        // third too (both earlier cells cover it).
        assert_eq!(ahead.first_need(&b("6,1,1,9,2,2")), Some(0));
        // Straddling the first cell's edge into the second: first read by the first.
        assert_eq!(ahead.first_need(&b("8,1,1,12,2,2")), Some(0));
        assert_eq!(ahead.first_need(&b("12,1,1,14,2,2")), Some(1));
        assert_eq!(ahead.first_need(&b("22,1,1,24,2,2")), Some(2));
        assert_eq!(ahead.first_need(&b("40,1,1,44,2,2")), None);
        assert_eq!(ahead.first_need(&Aabb::EMPTY), None);
        assert_eq!(Lookahead::default().first_need(&b("1,1,1,2,2,2")), None);
    }

    #[test]
    fn held_cells_hide_what_they_cover() {
        let ahead = Lookahead {
            cells: vec![b("0,0,0,10,10,10")],
            held: vec![b("0,0,0,4,10,10"), b("4,0,0,8,10,10")],
        };
        // Covered by the union of two held cells, not by either alone.
        assert_eq!(ahead.first_need(&b("2,1,1,6,2,2")), None);
        assert_eq!(ahead.first_need(&b("2,1,1,9,2,2")), Some(0));
    }
}
