//! The `dov-accuracy` experiment (ours, for Shou 2002 §5.5.2): the DoVs a build stores,
//! drawn by the CPU rasteriser's item buffers, against the ray-cast reference, cell by
//! cell, on a database's own meshes.
//!
//! The raster draws as the build drew it: far objects through the coarse levels the
//! database stores for them (`RasterScene::with_levels`), so that what is measured is
//! the error the stored DoVs carry; the ray-cast always takes the full meshes.
//!
//! Both sources are built over the same objects in the same order, so an object has the
//! same index in both; each sampled cell's DoVs (eq. 5.2: the maximum over its eight
//! corners) come from [`cell_dovs`] with each. A cell's difference is the sum over its
//! objects of the absolute difference of their DoVs, in shares of the view sphere: the
//! issue's criterion is at most 0.01 a cell at N = 256. The cells are spread evenly over
//! the walkable ones, as `pvs-tightness` spreads them, and each source takes them in one
//! batch, so both cast the same corners and their times compare.

use std::time::Instant;

use crate::pvs_tightness::{spread, stored_visibility, StoredVisibility};
use crate::report::Report;
use flaneur::database::Database;
use flaneur::error::Result;
use flaneur::geom::Aabb;
use flaneur::scene::Mesh;
use flaneur::visibility::{cell_dovs, DovStats, RasterScene, RayScene};

/// How the experiment samples.
#[derive(Clone, Debug, PartialEq)]
pub struct DovAccuracyConfig {
    /// Cells measured, spread evenly over the walkable ones (all of them when fewer).
    pub cells: usize,
    /// Pixels per side of a cube face (N).
    pub resolution: u32,
}

impl Default for DovAccuracyConfig {
    fn default() -> Self {
        DovAccuracyConfig {
            cells: 40,
            resolution: 256,
        }
    }
}

/// One cell measured.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CellRow {
    pub cell: u32,
    /// Objects with a DoV above 0 by the raster, and by the rays.
    pub raster_objects: usize,
    pub ray_objects: usize,
    /// The sum over objects of |raster DoV − ray DoV|, in shares of the sphere.
    pub difference: f64,
    /// The largest single object's |raster DoV − ray DoV|.
    pub largest: f64,
}

/// What the experiment measured.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct DovAccuracyReport {
    pub objects: usize,
    pub walkable_cells: usize,
    /// Objects the raster may draw through a coarser level the database stores.
    pub with_levels: usize,
    pub resolution: u32,
    /// Distinct corners each source drew or cast.
    pub corners: usize,
    /// Seconds to build each source's scene.
    pub raster_build_seconds: f64,
    pub ray_build_seconds: f64,
    /// Wall-clock seconds a corner, all cores.
    pub raster_seconds_per_corner: f64,
    pub ray_seconds_per_corner: f64,
    pub mean_difference: f64,
    pub max_difference: f64,
    pub rows: Vec<CellRow>,
}

/// Measures `db` (built with --visibility) as `cfg` says.
pub fn run(db: &Database, cfg: &DovAccuracyConfig) -> Result<DovAccuracyReport> {
    let StoredVisibility {
        projection,
        head,
        walkable,
        objects,
    } = stored_visibility(db, cfg.cells, cfg.resolution)?;
    let chosen = spread(&walkable, cfg.cells);
    let bounds: Vec<Aabb> = chosen
        .iter()
        .map(|&cell| {
            let (r, c) = head.grid.place(cell);
            head.grid.cell_bounds(r, c)
        })
        .collect();
    let pairs = || objects.iter().map(|(id, m)| (*id, m));
    let levels = coarse_levels(db, &objects)?;

    let t = Instant::now();
    let raster = RasterScene::with_levels(
        objects
            .iter()
            .zip(&levels)
            .map(|((id, m), l)| (*id, m, l.as_slice())),
    )?;
    let raster_build_seconds = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let rays = RayScene::new(pairs())?;
    let ray_build_seconds = t.elapsed().as_secs_f64();

    let drawn = cell_dovs(&raster, &projection, &bounds)?;
    let cast = cell_dovs(&rays, &projection, &bounds)?;
    let rows: Vec<CellRow> = chosen
        .iter()
        .zip(drawn.cells.iter().zip(&cast.cells))
        .map(|(&cell, (a, b))| {
            let (difference, largest) = compare(a, b);
            CellRow {
                cell,
                raster_objects: a.len(),
                ray_objects: b.len(),
                difference,
                largest,
            }
        })
        .collect();
    let n = rows.len().max(1) as f64;
    let per_corner = |s: &DovStats| s.elapsed.as_secs_f64() / s.corners.max(1) as f64;
    Ok(DovAccuracyReport {
        objects: objects.len(),
        walkable_cells: walkable.len(),
        with_levels: levels.iter().filter(|l| !l.is_empty()).count(),
        resolution: cfg.resolution,
        corners: drawn.stats.corners,
        raster_build_seconds,
        ray_build_seconds,
        raster_seconds_per_corner: per_corner(&drawn.stats),
        ray_seconds_per_corner: per_corner(&cast.stats),
        mean_difference: rows.iter().map(|r| r.difference).sum::<f64>() / n,
        max_difference: rows.iter().map(|r| r.difference).fold(0.0, f64::max),
        rows,
    })
}

/// Each object's coarser stored levels with their errors in metres, finest first, as a
/// build hands them to the raster (none for an object without LOD data).
fn coarse_levels(db: &Database, objects: &[(u64, Mesh)]) -> Result<Vec<Vec<(Mesh, f32)>>> {
    objects
        .iter()
        .map(|(id, _)| db.lod_coarse_levels(*id))
        .collect()
}

/// The sum and the largest of |a − b| over the objects of two cells' DoV lists, each
/// ascending by object index; an object missing from one list counts its whole DoV.
pub fn compare(a: &[(u32, f32)], b: &[(u32, f32)]) -> (f64, f64) {
    let (mut i, mut j) = (0, 0);
    let (mut sum, mut largest) = (0.0f64, 0.0f64);
    let mut add = |d: f64| {
        sum += d;
        largest = largest.max(d);
    };
    loop {
        match (a.get(i), b.get(j)) {
            (Some(x), Some(y)) if x.0 == y.0 => {
                add((f64::from(x.1) - f64::from(y.1)).abs());
                i += 1;
                j += 1;
            }
            (Some(x), Some(y)) if x.0 < y.0 => {
                add(f64::from(x.1));
                i += 1;
            }
            (Some(x), None) => {
                add(f64::from(x.1));
                i += 1;
            }
            (_, Some(y)) => {
                add(f64::from(y.1));
                j += 1;
            }
            (None, None) => break,
        }
    }
    (sum, largest)
}

impl Report for DovAccuracyReport {
    fn name(&self) -> &'static str {
        "dov-accuracy"
    }

    fn to_csv(&self) -> String {
        let mut s = String::from("cell,raster_objects,ray_objects,difference,largest\n");
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{},{:.3e},{:.3e}\n",
                r.cell, r.raster_objects, r.ray_objects, r.difference, r.largest
            ));
        }
        s
    }

    fn markdown(&self) -> String {
        format!(
            "# DoV accuracy: the rasterised item buffers against the ray-cast reference\n\n\
             {} cells of {} walkable, {} objects ({} of them with coarse levels the raster \
             may draw far away, as the build did), N = {}: {} distinct corners each.\n\n\
             | | raster | ray-cast |\n|---|---|---|\n\
             | scene built | {:.2} s | {:.2} s |\n\
             | a corner (all cores) | {:.1} ms | {:.1} ms |\n\n\
             A cell's difference, the sum over its objects of |raster − ray| in shares of the \
             view sphere: mean {:.2e}, largest {:.2e} (the criterion: at most 1.0e-2 a cell).\n",
            self.rows.len(),
            self.walkable_cells,
            self.objects,
            self.with_levels,
            self.resolution,
            self.corners,
            self.raster_build_seconds,
            self.ray_build_seconds,
            1000.0 * self.raster_seconds_per_corner,
            1000.0 * self.ray_seconds_per_corner,
            self.mean_difference,
            self.max_difference,
        )
    }

    fn plot(&self, _dir: &std::path::Path) -> Result<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn differences_count_objects_either_side_misses() {
        let a = [(1, 0.25), (3, 0.5)];
        let b = [(0, 0.125), (3, 0.25), (7, 0.0625)];
        let (sum, largest) = compare(&a, &b);
        assert_eq!(sum, 0.125 + 0.25 + 0.25 + 0.0625);
        assert_eq!(largest, 0.25);
        assert_eq!(compare(&a, &a), (0.0, 0.0));
        assert_eq!(compare(&[], &[]), (0.0, 0.0));
    }
}
