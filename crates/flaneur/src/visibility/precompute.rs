//! The visibility precomputation a build runs (Shou 2002 §5.5): the viewcells over the
//! walkable city, each cell's conservative PVS (§5.5.1), the DoV of every object in it
//! by cubic projection from the cell's corners (§5.5.2), and the table that stores them.
//!
//! Choices made here:
//! - The DoV comes first: an object a corner's rays met is visible, so the conservative
//!   test is told so and spends no time on it (`Scene::visible_from`). Objects in the conservative set that no ray
//!   met are the thesis's visible zero-DoV objects and get DoV_s, the DoV of the
//!   smallest pixel of the cube (`CubicProjection::zero_dov_floor`).
//! - Cells are computed a band of rows at a time, so that the progress can be reported;
//!   neighbouring cells share their corners' projections, within a band and with the
//!   band before (`CornerMemo`).

use std::time::Instant;

use rayon::prelude::*;

use super::cells::{Viewcell, ViewcellGrid};
use super::conservative::{SampleOptions, Scene};
use super::occluder::occluder_boxes;
use super::table::{CellPvs, VisibilitySettings, VisibilityStats};
use super::{cell_dovs_after, CornerMemo, CubicProjection, RayScene};
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::scene::Mesh;

/// Rows of cells computed together.
const BAND_ROWS: u32 = 8;

/// How `flaneur build --visibility` computes visibility.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VisibilityOptions {
    /// Side of a viewcell in metres.
    pub cell_size: f32,
    /// Eye heights above the ground, in metres.
    pub eye: [f32; 2],
    /// Pixels per side of a cube face (N).
    pub resolution: u32,
    /// How the conservative test samples a cell.
    pub samples: SampleOptions,
}

impl Default for VisibilityOptions {
    fn default() -> Self {
        VisibilityOptions {
            cell_size: super::cells::DEFAULT_CELL_SIZE,
            eye: super::cells::DEFAULT_EYE_RANGE,
            resolution: 256,
            samples: SampleOptions::default(),
        }
    }
}

impl VisibilityOptions {
    /// Checks every setting, before any work: the cell size and eye range, the cube
    /// faces' resolution, the sampling. The error names the bad one.
    pub fn validate(&self) -> Result<()> {
        ViewcellGrid::check(self.cell_size, self.eye)?;
        CubicProjection::check(self.resolution)?;
        self.samples.validate()
    }
}

/// What the precomputation made: the grid, and each walkable cell's PVS by id.
#[derive(Clone, Debug)]
pub struct Precomputed {
    pub grid: ViewcellGrid,
    pub settings: VisibilitySettings,
    pub stats: VisibilityStats,
    pub cells: Vec<(u32, CellPvs)>,
    /// Occluders found among the objects.
    pub occluders: usize,
}

/// Computes the visibility of `objects` (id and mesh). `progress` is told the cells
/// done and the cells in all, after each band of rows.
pub fn precompute(
    objects: &[(u64, Mesh)],
    opts: &VisibilityOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Precomputed> {
    let started = Instant::now();
    if objects.is_empty() {
        return Err(Error::Invalid(
            "visibility of a city with no objects".into(),
        ));
    }
    opts.validate()?;
    let boxes: Vec<Aabb> = objects
        .iter()
        .map(|(id, m)| {
            let (lo, hi) = m.bounds();
            Aabb::new(lo, hi).map_err(|e| Error::Invalid(format!("object {id}: {e}")))
        })
        .collect::<Result<_>>()?;
    let occluders: Vec<Vec<Aabb>> = objects.par_iter().map(|(_, m)| occluder_boxes(m)).collect();
    let scene = Scene::new(&boxes, &occluders)?;
    let rays = RayScene::new(objects.iter().map(|(id, m)| (*id, m)))?;
    let projection = CubicProjection::new(opts.resolution)?;
    let city = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(b));
    let grid = ViewcellGrid::new(&city, opts.cell_size, opts.eye)?;
    let walkable = grid.walkable(&boxes);
    let dov_s = projection.zero_dov_floor();

    let mut cells = Vec::with_capacity(walkable.len());
    let mut cast = 0u64;
    let mut dov_seconds = 0.0;
    let mut memo = CornerMemo::default();
    progress(0, walkable.len());
    for band in walkable.chunk_by(|a, b| a.row / BAND_ROWS == b.row / BAND_ROWS) {
        let bounds: Vec<Aabb> = band.iter().map(|c| c.bounds).collect();
        let dovs = cell_dovs_after(&rays, &projection, &bounds, &mut memo)?;
        cast += dovs.stats.rays;
        dov_seconds += dovs.stats.elapsed.as_secs_f64();
        let made: Vec<(u32, CellPvs)> = band
            .par_iter()
            .zip(dovs.cells.par_iter())
            .map(|(cell, seen)| cell_pvs(&scene, opts, cell, seen, objects, dov_s))
            .collect::<Result<_>>()?;
        cells.extend(made);
        progress(cells.len(), walkable.len());
    }
    let entries = cells.iter().map(|(_, p)| p.ids.len() as u64).sum();
    Ok(Precomputed {
        grid,
        settings: VisibilitySettings {
            resolution: opts.resolution,
            dov_s,
            samples: opts.samples,
            bins: super::horizon::BINS as u32,
        },
        stats: VisibilityStats {
            seconds: started.elapsed().as_secs_f64(),
            dov_seconds,
            rays: cast,
            entries,
            objects: objects.len() as u64,
        },
        cells,
        occluders: occluders.iter().filter(|o| !o.is_empty()).count(),
    })
}

/// One cell's PVS from its conservative set and the DoVs its corners saw (by object
/// index).
fn cell_pvs(
    scene: &Scene,
    opts: &VisibilityOptions,
    cell: &Viewcell,
    seen: &[(u32, f32)],
    objects: &[(u64, Mesh)],
    dov_s: f32,
) -> Result<(u32, CellPvs)> {
    let mut seen_sorted = seen.to_vec();
    seen_sorted.sort_unstable_by_key(|s| s.0);
    let seen_ids: Vec<u32> = seen_sorted.iter().map(|s| s.0).collect();
    let visible = scene.visible_from(&cell.bounds, &opts.samples, &seen_ids)?;
    // What the rays saw is in the conservative set (`visible_from` keeps it), with
    // its measured DoV; the rest are the visible zero-DoV objects.
    let mut merged: Vec<(u64, f32)> = visible
        .iter()
        .map(|&i| {
            let dov = seen_sorted
                .binary_search_by_key(&i, |s| s.0)
                .map_or(dov_s, |k| seen_sorted[k].1);
            (objects[i as usize].0, dov.clamp(dov_s, 1.0))
        })
        .collect();
    merged.sort_unstable_by_key(|m| m.0);
    Ok((
        cell.id,
        CellPvs {
            ids: merged.iter().map(|m| m.0).collect(),
            dov: merged.iter().map(|m| m.1).collect(),
        },
    ))
}
