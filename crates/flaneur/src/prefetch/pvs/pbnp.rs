//! PBNP, the position-based neighbour prefetch (Zheng 2007 §7.2.2, Fig. 7.2, Table 7.1):
//! a neighbour's PVS is fetched only once the viewer leans towards it, read from which
//! of the nine regions of its cell it stands in.
//!
//! The thesis gives no size for the regions: here the side and corner regions are
//! bands a fraction `border` of the cell's side wide (default
//! [`DEFAULT_BORDER`](super::DEFAULT_BORDER), a quarter).

use super::area::{Area, PrefetchArea};
use super::grid::{check_border, Position, Region, ViewcellGrid, DEFAULT_BORDER};
use crate::error::Result;

/// h(R) of Table 7.1, as (row, column) offsets from the current cell C, C itself
/// left implicit: C_N is (−1, 0), C_NE is (−1, 1).
pub fn h(region: Region) -> &'static [(i32, i32)] {
    const N: (i32, i32) = (-1, 0);
    const S: (i32, i32) = (1, 0);
    const E: (i32, i32) = (0, 1);
    const W: (i32, i32) = (0, -1);
    match region {
        Region::M => &[],
        Region::N => &[N],
        Region::S => &[S],
        Region::W => &[W],
        Region::E => &[E],
        Region::NW => &[N, W, (-1, -1)],
        Region::NE => &[N, E, (-1, 1)],
        Region::SE => &[S, E, (1, 1)],
        Region::SW => &[S, W, (1, -1)],
    }
}

/// The position-based neighbour prefetch.
///
/// ```
/// use flaneur::prefetch::pvs::{Cell, Pbnp, Position, PrefetchArea, ViewcellGrid};
/// let grid = ViewcellGrid::new(Position::new(0.0, 0.0), 20.0, 5, 5)?;
/// let pbnp = Pbnp::new(0.25)?;
/// // In the middle of cell (2, 2): only the cell itself.
/// assert_eq!(pbnp.area(&grid, Position::new(50.0, 50.0))?.cells, [Cell::new(2, 2)]);
/// // 2 m from its north-east corner: C, C_N, C_E and C_NE.
/// let ne = pbnp.area(&grid, Position::new(58.0, 42.0))?;
/// assert_eq!(ne.cells, [Cell::new(2, 2), Cell::new(1, 2), Cell::new(2, 3), Cell::new(1, 3)]);
/// assert!(Pbnp::new(0.7).is_err());
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pbnp {
    border: f64,
}

impl Pbnp {
    /// PBNP with side and corner regions `border` of the cell's side wide, in (0, 0.5].
    pub fn new(border: f64) -> Result<Pbnp> {
        check_border(border)?;
        Ok(Pbnp { border })
    }

    /// The width of the side and corner regions, as a share of the cell's side.
    pub fn border(&self) -> f64 {
        self.border
    }
}

impl Default for Pbnp {
    fn default() -> Pbnp {
        Pbnp {
            border: DEFAULT_BORDER,
        }
    }
}

impl PrefetchArea for Pbnp {
    fn area(&self, grid: &ViewcellGrid, p: Position) -> Result<Area> {
        let (cell, region) = grid.locate(p, self.border)?;
        Ok(Area::around(grid, cell, h(region)))
    }

    fn name(&self) -> &'static str {
        "PBNP"
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::*;

    /// h(R) as sets of offsets, C included.
    fn hs(r: Region) -> BTreeSet<(i32, i32)> {
        h(r).iter().copied().chain([(0, 0)]).collect()
    }

    #[test]
    fn h_is_table_7_1() {
        let table = [
            (Region::M, vec![]),
            (Region::N, vec![(-1, 0)]),
            (Region::S, vec![(1, 0)]),
            (Region::W, vec![(0, -1)]),
            (Region::E, vec![(0, 1)]),
            (Region::NW, vec![(-1, 0), (0, -1), (-1, -1)]),
            (Region::NE, vec![(-1, 0), (0, 1), (-1, 1)]),
            (Region::SE, vec![(1, 0), (0, 1), (1, 1)]),
            (Region::SW, vec![(1, 0), (0, -1), (1, -1)]),
        ];
        for (r, want) in table {
            assert_eq!(h(r), &want[..], "{r:?}");
            // Every neighbour leans the region's way.
            let (dr, dc) = r.direction();
            for &(a, b) in h(r) {
                assert!((a == 0 || a == dr) && (b == 0 || b == dc), "{r:?}");
            }
        }
    }

    /// §7.2.2, point 1: the prefetching areas of two adjacent regions, within a cell or
    /// across a border, together hold at most 4 cells, so a 9-entry cache never
    /// oscillates. Adjacent regions across a border are those met by stepping over it.
    #[test]
    fn adjacent_regions_need_at_most_four_cells() {
        let mut worst = 0;
        for a in Region::ALL {
            for b in Region::ALL {
                let (ar, ac) = a.direction();
                let (br, bc) = b.direction();
                // Within one cell: neighbouring bands differ by one step on one axis.
                let within = (ar - br).abs() + (ac - bc).abs() == 1;
                // Across the east border: a leans east, b (in C_E) leans west, same row band.
                let across = ac == 1 && bc == -1 && ar == br;
                if within || across {
                    let offset = if across { (0, 1) } else { (0, 0) };
                    let ha = hs(a);
                    let hb: BTreeSet<_> = hs(b)
                        .into_iter()
                        .map(|(r, c)| (r + offset.0, c + offset.1))
                        .collect();
                    worst = worst.max(ha.union(&hb).count());
                }
            }
        }
        assert_eq!(worst, 4);
    }

    #[test]
    fn default_is_the_named_border() {
        assert_eq!(Pbnp::default().border(), DEFAULT_BORDER);
        assert_eq!(Pbnp::new(0.5).unwrap().border(), 0.5);
        for b in [0.0, 0.500001, f64::NAN, -1.0] {
            assert!(Pbnp::new(b).is_err(), "{b}");
        }
    }
}
