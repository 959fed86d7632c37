//! What a visibility precomputation under some [`VisibilityOptions`] implies over one
//! city, known from the city's bounds before any of it runs: the viewcells, the sample
//! points of the conservative test in each, and the memory their lists and the DoV's
//! buffers hold. A build checks it before its slow steps (LODs first of all), so that an
//! option that asks for trillions of cells or of sample points is refused in a moment
//! with what it would need, not hours later by an allocation that aborts.
//!
//! The byte counts are lower bounds: each counts only the fixed part of a record the
//! precomputation keeps per cell, per corner of a band or per sample point, never the
//! PVSs themselves (their length is what the precomputation finds). A refusal on them is
//! certain; passing them promises nothing.

use std::mem::size_of;

use glam::Vec3;

use super::cells::{Viewcell, ViewcellGrid};
use super::conservative::MAX_SAMPLES_PER_CELL;
use super::dov_sums::PointDov;
use super::precompute::BAND_ROWS;
use super::shown::shown;
use super::table::CellPvs;
use super::VisibilityOptions;
use crate::error::{Error, Result};
use crate::geom::Aabb;

/// The most viewcells a grid may have (2²⁴, 16.8 million): each walkable one holds a
/// PVS in memory until the table is written, and at the measured 0.06–0.6 s a cell a
/// grid this large is already months of one machine's work.
pub const MAX_VIEWCELLS: u64 = 1 << 24;

/// What a precomputation implies over one city ([`VisibilityOptions::cost`]).
///
/// ```
/// use flaneur::geom::Aabb;
/// use flaneur::visibility::VisibilityOptions;
/// let city = Aabb::new([0.0; 3], [400.0, 60.0, 200.0])?;
/// let cost = VisibilityOptions::default().cost(&city, 100, None)?;
/// assert_eq!((cost.columns, cost.rows), (10, 5)); // 40 m cells
/// assert_eq!(cost.samples_per_cell, 14 * 14); // patches of at most 3 m
/// assert!(cost.bytes() > 0);
/// let tiny = VisibilityOptions { cell_size: 1e-6, ..Default::default() };
/// assert!(tiny.cost(&city, 100, None).unwrap_err().to_string().contains("--cell-size"));
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VisibilityCost {
    /// Columns of the viewcell grid (along x).
    pub columns: u64,
    /// Rows of the viewcell grid (along z).
    pub rows: u64,
    /// Walkable cells: as counted over the objects' boxes, or every cell of the grid
    /// (at most that many) where they were not counted.
    pub walkable: u64,
    /// Sample points of the conservative test in each cell.
    pub samples_per_cell: u64,
    /// Bytes the walkable cells' lists hold at least (each cell's place, then its PVS's
    /// record before its entries).
    pub cell_bytes: u64,
    /// Bytes the DoV holds at least: a band of rows' corners and the band before it,
    /// each corner's object sums while it is cast, and the cube's pixel weights.
    pub dov_bytes: u64,
    /// Bytes of the sample points of the cells computed at once, one per thread.
    pub sample_bytes: u64,
}

impl VisibilityCost {
    /// Cells of the grid, walkable or not.
    pub fn cells(&self) -> u64 {
        self.columns * self.rows
    }

    /// Bytes the precomputation holds at least, besides the meshes it casts rays at.
    pub fn bytes(&self) -> u64 {
        self.cell_bytes
            .saturating_add(self.dov_bytes)
            .saturating_add(self.sample_bytes)
    }
}

impl VisibilityOptions {
    /// What these options imply over a city whose objects (`objects` of them) lie in
    /// `city`, with `walkable` of its cells walkable where that is known (every cell is
    /// taken as walkable otherwise). An error, naming the option, its value and the
    /// limit, when a setting is invalid, when the grid would have more than
    /// [`MAX_VIEWCELLS`] cells or a cell more than [`MAX_SAMPLES_PER_CELL`] sample points.
    pub fn cost(&self, city: &Aabb, objects: u64, walkable: Option<u64>) -> Result<VisibilityCost> {
        self.validate()?;
        city.validate()?;
        let extent = city.extent();
        // As `ViewcellGrid::new` counts them, in f32, so that the two agree.
        let count = |len: f32| (len / self.cell_size).ceil().max(1.0) as u64;
        let (columns, rows) = (count(extent.x), count(extent.z));
        let cells = columns.saturating_mul(rows);
        if cells > MAX_VIEWCELLS {
            let least = ((extent.x.max(self.cell_size) as f64
                * extent.z.max(self.cell_size) as f64)
                / MAX_VIEWCELLS as f64)
                .sqrt();
            return Err(Error::Invalid(format!(
                "viewcell size {} m (--cell-size) makes {} × {} viewcells over this city \
                 ({} × {} m): more than the {MAX_VIEWCELLS} a build takes; give a cell size of \
                 at least about {} m",
                shown(self.cell_size),
                large(extent.x as f64 / self.cell_size as f64, 0),
                large(extent.z as f64 / self.cell_size as f64, 0),
                large(extent.x as f64, 0),
                large(extent.z as f64, 0),
                rounded_up(least)
            )));
        }
        // In f32, as `SampleOptions::samples` lays the patches out.
        let across = (self.cell_size / self.samples.spacing).ceil().max(1.0) as f64;
        let samples_per_cell = across * across;
        if !(samples_per_cell <= MAX_SAMPLES_PER_CELL as f64) {
            let per_side = (MAX_SAMPLES_PER_CELL as f64).sqrt();
            return Err(Error::Invalid(format!(
                "sample spacing {} m (--sample-spacing) makes {samples_per_cell:.3e} sample points \
                 in each {} m viewcell: more than the {MAX_SAMPLES_PER_CELL} a cell takes; give a \
                 spacing of at least {} m (or smaller cells)",
                shown(self.samples.spacing),
                shown(self.cell_size),
                rounded_up(self.cell_size as f64 / per_side)
            )));
        }
        let samples_per_cell = samples_per_cell as u64;
        let walkable = walkable.unwrap_or(cells).min(cells);
        let threads = rayon::current_num_threads() as u64;
        let n = self.resolution as u64;
        // A band of rows computes at most its rows' walkable cells, each with at least
        // two corners of its own (a corner is shared by at most four cells, of two
        // eye heights each); its corners' DoVs are kept for the next band.
        let band_cells = walkable.min(BAND_ROWS as u64 * columns);
        let corner = (size_of::<[f32; 3]>() + 2 * size_of::<PointDov>()) as u64;
        let dov_bytes = 2 * 2 * band_cells * corner
            + threads * objects * size_of::<f64>() as u64
            + n * n * size_of::<f32>() as u64;
        Ok(VisibilityCost {
            columns,
            rows,
            walkable,
            samples_per_cell,
            cell_bytes: walkable * (size_of::<Viewcell>() + size_of::<(u32, CellPvs)>()) as u64,
            dov_bytes,
            sample_bytes: threads * samples_per_cell * size_of::<Vec3>() as u64,
        })
    }
}

/// A count or a length in a refusal: with `decimals` while it is short, in
/// scientific notation beyond ten million.
fn large(v: f64, decimals: usize) -> String {
    if v.abs() >= 1e7 {
        format!("{v:.3e}")
    } else {
        format!("{v:.decimals$}")
    }
}

/// `v` rounded up to three significant digits: a bound a refusal may suggest.
fn rounded_up(v: f64) -> String {
    if !(v.is_finite() && v > 0.0) {
        return v.to_string();
    }
    let unit = 10f64.powf(v.log10().floor() - 2.0);
    let up = (v / unit).ceil() * unit;
    if up >= 1e7 {
        return format!("{up:.2e}");
    }
    // Printed at the digits kept, not with the float's tail.
    format!("{up:.*}", (2.0 - v.log10().floor()).max(0.0) as usize)
}

/// Walkable cells of the grid `opts` lays over the objects' `boxes`: what
/// [`VisibilityOptions::cost`] takes to be exact, counted as the precomputation will
/// find them. The grid must be within [`MAX_VIEWCELLS`] (a cost computed first says so).
pub(crate) fn walkable_cells(opts: &VisibilityOptions, boxes: &[Aabb]) -> Result<u64> {
    let city = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(b));
    let grid = ViewcellGrid::new(&city, opts.cell_size, opts.eye)?;
    if grid.len() as u64 > MAX_VIEWCELLS {
        return Err(Error::Invalid(format!(
            "{} viewcells: more than the {MAX_VIEWCELLS} a build takes",
            grid.len()
        )));
    }
    Ok(grid.walkable_count(boxes))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::visibility::SampleOptions;

    fn city() -> Aabb {
        Aabb::new([0.0; 3], [1000.0, 80.0, 600.0]).unwrap()
    }

    #[test]
    fn a_grid_or_a_sampling_past_its_limit_is_refused_naming_its_option() {
        let fine = VisibilityOptions {
            cell_size: 1e-9,
            ..Default::default()
        };
        let e = fine.cost(&city(), 10, None).unwrap_err().to_string();
        assert!(e.contains("--cell-size") && e.contains("1e-9"), "{e}");
        let dense = VisibilityOptions {
            samples: SampleOptions {
                spacing: 1e-9,
                ..Default::default()
            },
            ..Default::default()
        };
        let e = dense.cost(&city(), 10, None).unwrap_err().to_string();
        assert!(e.contains("--sample-spacing") && e.contains("1e-9"), "{e}");
        // At the limit itself both are taken.
        let edge = VisibilityOptions {
            cell_size: 40.0,
            samples: SampleOptions {
                spacing: 40.0 / 1024.0,
                ..Default::default()
            },
            ..Default::default()
        };
        let cost = edge.cost(&city(), 10, None).unwrap();
        assert_eq!(cost.samples_per_cell, MAX_SAMPLES_PER_CELL);
        assert_eq!((cost.columns, cost.rows, cost.walkable), (25, 15, 375));
    }

    #[test]
    fn values_are_shown_as_typed_and_bounds_rounded_up() {
        assert_eq!(shown(1e-9), "1e-9");
        assert_eq!(shown(40.0), "40");
        assert_eq!(shown(0.5), "0.5");
        assert_eq!(shown(3e9), "3e9");
        assert_eq!(rounded_up(0.033_61), "0.0337");
        assert_eq!(rounded_up(19.531), "19.6");
        assert_eq!(rounded_up(1234.5), "1240");
        assert_eq!(rounded_up(8.1e26), "8.10e26");
        assert_eq!(large(735.6, 0), "736");
        assert_eq!(large(1.1e31, 0), "1.100e31");
    }

    #[test]
    fn the_bytes_grow_with_the_cells_and_shrink_with_the_walkable_count() {
        let opts = VisibilityOptions::default();
        let coarse = opts.cost(&city(), 10, None).unwrap();
        let fine = VisibilityOptions {
            cell_size: 4.0,
            ..opts
        }
        .cost(&city(), 10, None)
        .unwrap();
        assert!(fine.cell_bytes > 90 * coarse.cell_bytes);
        let few = opts.cost(&city(), 10, Some(3)).unwrap();
        assert_eq!(few.walkable, 3);
        assert!(few.bytes() < coarse.bytes());
    }
}
