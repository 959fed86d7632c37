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

use super::cells::{object_boxes, Viewcell, ViewcellGrid};
use super::conservative::{SampleOptions, Scene};
use super::dov::corner_keys;
use super::table::{CellPvs, VisibilitySettings, VisibilityStats};
use super::{cell_dovs_after, CornerMemo, CubicProjection, DovMethod, DovSource};
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::scene::Mesh;

/// Rows of cells computed together.
pub(super) const BAND_ROWS: u32 = 8;

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
    /// How the DoV is computed: rasterised by default, ray-cast as the reference. The
    /// shard file does not record it: shards by either merge.
    pub dov: DovMethod,
}

impl Default for VisibilityOptions {
    fn default() -> Self {
        VisibilityOptions {
            cell_size: super::cells::DEFAULT_CELL_SIZE,
            eye: super::cells::DEFAULT_EYE_RANGE,
            resolution: 256,
            samples: SampleOptions::default(),
            dov: DovMethod::default(),
        }
    }
}

impl VisibilityOptions {
    /// Checks every setting, before any work: the cell size and eye range, the cube
    /// faces' resolution, the sampling. The error names the bad one.
    pub fn validate(&self) -> Result<()> {
        ViewcellGrid::check(self.cell_size, self.eye)?;
        CubicProjection::check(self.resolution)
            .map_err(|e| Error::Invalid(format!("{e} (--dov-resolution)")))?;
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

/// Computes the visibility of `objects` (id and mesh), the DoV drawing far objects
/// through their coarser `levels` (one entry per object, or empty for none: see
/// [`DovMethod::scene_with_levels`]). `progress` is told the cells done and the cells in
/// all, after each band of rows.
pub fn precompute(
    objects: &[(u64, Mesh)],
    levels: &[Vec<(Mesh, f32)>],
    opts: &VisibilityOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Precomputed> {
    let started = Instant::now();
    let prep = prepare(objects, levels, opts)?;
    let bands = bands(&prep.walkable);
    let made = compute(&prep, objects, opts, &bands, progress)?;
    Ok(Precomputed {
        stats: VisibilityStats {
            seconds: started.elapsed().as_secs_f64(),
            dov_seconds: made.dov_seconds,
            rays: made.rays,
            entries: made.cells.iter().map(|(_, p)| p.ids.len() as u64).sum(),
            objects: objects.len() as u64,
        },
        settings: settings(opts, prep.dov_s),
        grid: prep.grid,
        cells: made.cells,
        occluders: prep.occluders,
    })
}

/// What every cell's computation shares, made once per build (or per shard): the
/// objects' boxes and occluders, the ray scene, the cube, and the walkable cells.
pub(super) struct Prepared {
    scene: Scene,
    dov: Box<dyn DovSource + Send>,
    projection: CubicProjection,
    pub grid: ViewcellGrid,
    pub walkable: Vec<Viewcell>,
    dov_s: f32,
    /// Objects with an occluder box.
    pub occluders: usize,
}

/// The settings a table records for a precomputation under `opts`, whose visible
/// zero-DoV objects get `dov_s`.
pub(super) fn settings(opts: &VisibilityOptions, dov_s: f32) -> VisibilitySettings {
    VisibilitySettings {
        resolution: opts.resolution,
        dov_s,
        samples: opts.samples,
        bins: super::horizon::BINS as u32,
    }
}

/// The viewcell grid over `objects` and its walkable cells: all a merge of shards needs.
/// Options that would make more cells (or sample points) than a build takes are refused
/// first, as a build refuses them before it starts (`VisibilityOptions::cost`).
pub(super) fn grid_and_walkable(
    objects: &[(u64, Mesh)],
    opts: &VisibilityOptions,
) -> Result<(ViewcellGrid, Vec<Viewcell>)> {
    let (boxes, city) = object_boxes(objects.iter().map(|(id, m)| (*id, m)))?;
    opts.cost(&city, boxes.len() as u64, None)?;
    let grid = ViewcellGrid::new(&city, opts.cell_size, opts.eye)?;
    let walkable = grid.walkable(&boxes);
    Ok((grid, walkable))
}

/// Everything the cells' computation shares; `levels` as [`precompute`] takes them.
pub(super) fn prepare(
    objects: &[(u64, Mesh)],
    levels: &[Vec<(Mesh, f32)>],
    opts: &VisibilityOptions,
) -> Result<Prepared> {
    opts.validate()?;
    // The grid first: what the options make of the city is refused before the slow steps.
    let (grid, walkable) = grid_and_walkable(objects, opts)?;
    let scene = Scene::from_meshes(objects)?;
    let dov = opts
        .dov
        .scene_with_levels(objects.iter().map(|(id, m)| (*id, m)), levels)?;
    let projection = CubicProjection::new(opts.resolution)?;
    Ok(Prepared {
        occluders: scene.occluding_objects(),
        scene,
        dov,
        dov_s: projection.zero_dov_floor(),
        projection,
        grid,
        walkable,
    })
}

/// The walkable cells in the bands of rows they are computed in.
pub(super) fn bands(walkable: &[Viewcell]) -> Vec<&[Viewcell]> {
    walkable
        .chunk_by(|a, b| a.row / BAND_ROWS == b.row / BAND_ROWS)
        .collect()
}

/// The rays a whole build casts for `walkable`: each band casts the corners it does not
/// share with the band before it (`CornerMemo`). What a merge of shards stores, whose
/// shards cast the corners at their edges twice.
pub(super) fn whole_build_rays(walkable: &[Viewcell], projection: &CubicProjection) -> u64 {
    let mut before = std::collections::HashSet::new();
    let mut corners = 0;
    for band in bands(walkable) {
        let here = corner_keys(&band.iter().map(|c| c.bounds).collect::<Vec<_>>());
        corners += here.difference(&before).count() as u64;
        before = here;
    }
    corners * projection.rays_per_point()
}

/// The cells computed, and what computing them cast.
pub(super) struct Computed {
    pub cells: Vec<(u32, CellPvs)>,
    pub rays: u64,
    pub dov_seconds: f64,
}

/// Each cell of `bands` with its PVS, in the bands' order; `progress` is told the cells
/// done of the bands' cells after each band.
pub(super) fn compute(
    prep: &Prepared,
    objects: &[(u64, Mesh)],
    opts: &VisibilityOptions,
    bands: &[&[Viewcell]],
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Computed> {
    let total = bands.iter().map(|b| b.len()).sum();
    let mut made = Computed {
        cells: Vec::with_capacity(total),
        rays: 0,
        dov_seconds: 0.0,
    };
    let mut memo = CornerMemo::default();
    progress(0, total);
    for band in bands {
        let bounds: Vec<Aabb> = band.iter().map(|c| c.bounds).collect();
        let dovs = cell_dovs_after(prep.dov.as_ref(), &prep.projection, &bounds, &mut memo)?;
        made.rays += dovs.stats.rays;
        made.dov_seconds += dovs.stats.elapsed.as_secs_f64();
        let cells: Vec<(u32, CellPvs)> = band
            .par_iter()
            .zip(dovs.cells.par_iter())
            .map(|(cell, seen)| cell_pvs(&prep.scene, opts, cell, seen, objects, prep.dov_s))
            .collect::<Result<_>>()?;
        made.cells.extend(cells);
        progress(made.cells.len(), total);
    }
    Ok(made)
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
