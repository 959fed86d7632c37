//! The statistics the thesis generates its PVS table to (Zheng 2007 §7.5): the PVS as
//! a share of the scene, and the share of a viewcell's PVS its neighbour also sees.
//! Measured over any [`PvsSource`], so a table computed from real geometry can be set
//! beside the synthetic one. Only the `pvs-prefetch` experiment reports them, so they
//! live here rather than in the engine's prefetcher.

use flaneur::error::Result;
use flaneur::prefetch::pvs::{Cell, ObjectId, PvsSource};

/// A PVS table's figures.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TableStats {
    pub scene_objects: u64,
    pub viewcells: usize,
    pub mean_pvs: f64,
    pub min_pvs: usize,
    pub max_pvs: usize,
    /// Mean PVS size over the scene's objects (the thesis: about 5 %).
    pub mean_share: f64,
    /// Pairs of viewcells sharing a side.
    pub side_pairs: usize,
    /// Mean over side neighbours i, j (both ways) of |S_i ∩ S_j| / |S_i| (the thesis:
    /// about 60 %).
    pub side_overlap: f64,
    /// The same as |S_i ∩ S_j| / |S_i ∪ S_j|.
    pub side_jaccard: f64,
    /// The overlap of diagonal neighbours, and of cells two apart along a row or column.
    pub diagonal_overlap: f64,
    pub two_apart_overlap: f64,
}

/// Reads every row of `source` and measures it. Cells with an empty PVS count in the
/// sizes but not in the overlaps (a share of nothing is no share).
pub fn measure<S: PvsSource + ?Sized>(source: &S) -> Result<TableStats> {
    let grid = source.grid();
    let (rows, cols) = (grid.rows(), grid.cols());
    let mut pvs: Vec<Option<Vec<ObjectId>>> = Vec::with_capacity(rows as usize * cols as usize);
    for r in 0..rows {
        for c in 0..cols {
            let cell = Cell::new(r, c);
            pvs.push(if source.is_viewcell(cell)? {
                Some(source.pvs(cell)?)
            } else {
                None
            });
        }
    }
    let at = |cell: Cell| pvs[cell.row as usize * cols as usize + cell.col as usize].as_deref();

    let sizes: Vec<usize> = pvs.iter().flatten().map(Vec::len).collect();
    let mut s = TableStats {
        scene_objects: source.scene_objects(),
        viewcells: sizes.len(),
        min_pvs: sizes.iter().copied().min().unwrap_or(0),
        max_pvs: sizes.iter().copied().max().unwrap_or(0),
        ..TableStats::default()
    };
    if !sizes.is_empty() {
        s.mean_pvs = sizes.iter().sum::<usize>() as f64 / sizes.len() as f64;
        s.mean_share = s.mean_pvs / s.scene_objects.max(1) as f64;
    }

    // Each offset once per unordered pair; both directions of the share are counted.
    let mean_overlap = |offsets: &[(i32, i32)], pairs: Option<&mut usize>| {
        let (mut share, mut jaccard, mut n, mut unordered) = (0.0, 0.0, 0usize, 0usize);
        for r in 0..rows {
            for c in 0..cols {
                let a_cell = Cell::new(r, c);
                let Some(a) = at(a_cell) else { continue };
                for &(dr, dc) in offsets {
                    let Some(b) = grid.offset(a_cell, dr, dc).and_then(at) else {
                        continue;
                    };
                    unordered += 1;
                    let common = intersection(a, b);
                    for x in [a, b] {
                        if !x.is_empty() {
                            share += common as f64 / x.len() as f64;
                            n += 1;
                        }
                    }
                    let union = a.len() + b.len() - common;
                    if union > 0 {
                        jaccard += common as f64 / union as f64;
                    }
                }
            }
        }
        if let Some(p) = pairs {
            *p = unordered;
        }
        (share / n.max(1) as f64, jaccard / unordered.max(1) as f64)
    };
    let mut side_pairs = 0;
    (s.side_overlap, s.side_jaccard) = mean_overlap(&[(0, 1), (1, 0)], Some(&mut side_pairs));
    s.side_pairs = side_pairs;
    s.diagonal_overlap = mean_overlap(&[(1, 1), (1, -1)], None).0;
    s.two_apart_overlap = mean_overlap(&[(0, 2), (2, 0)], None).0;
    Ok(s)
}

/// |a ∩ b| of two ascending lists.
fn intersection(a: &[ObjectId], b: &[ObjectId]) -> usize {
    let (mut i, mut j, mut n) = (0, 0, 0);
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                n += 1;
                i += 1;
                j += 1;
            }
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pvs_prefetch::{PvsTable, SyntheticCity, SyntheticConfig};
    use flaneur::prefetch::pvs::{Position, ViewcellGrid};

    #[test]
    fn a_small_table_by_hand() {
        let grid = ViewcellGrid::new(Position::new(0.0, 0.0), 10.0, 1, 3).unwrap();
        let mut t = PvsTable::new(grid, 10).unwrap();
        t.insert(Cell::new(0, 0), vec![1, 2, 3, 4]).unwrap();
        t.insert(Cell::new(0, 1), vec![3, 4, 5, 6]).unwrap();
        let s = measure(&t).unwrap();
        assert_eq!(
            (s.viewcells, s.side_pairs, s.min_pvs, s.max_pvs),
            (2, 1, 4, 4)
        );
        assert!((s.mean_share - 0.4).abs() < 1e-12);
        assert!((s.side_overlap - 0.5).abs() < 1e-12);
        assert!((s.side_jaccard - 2.0 / 6.0).abs() < 1e-12);
        assert_eq!(s.diagonal_overlap, 0.0);
        assert_eq!(intersection(&[1, 5, 9], &[2, 5, 9, 11]), 2);
    }

    #[test]
    fn the_thesis_city_has_its_figures() {
        let city = SyntheticCity::generate(&SyntheticConfig::default()).unwrap();
        let g = city.grid();
        assert_eq!((g.rows(), g.cols()), (243, 243));
        assert_eq!(city.side(), 4860.0);
        assert_eq!(city.scene_objects(), 900);
        let s = measure(&city).unwrap();
        // Street cells: 93 full rows plus 93 columns of the other 150 rows.
        assert_eq!(s.viewcells, 93 * 243 + 150 * 93);
        assert!((s.mean_share - 0.05).abs() < 0.002, "{s:?}");
        assert!((s.side_overlap - 0.6).abs() < 0.02, "{s:?}");
        assert!(s.diagonal_overlap < s.side_overlap && s.two_apart_overlap < s.diagonal_overlap);
        assert!(s.min_pvs > 10 && s.max_pvs < 90, "{s:?}");
    }
}
