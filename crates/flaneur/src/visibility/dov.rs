//! Degree of visibility (Shou 2002, §5.2.1 and §5.5.2): an object's point DoV is the
//! share of the sphere of directions around a viewpoint in which it is the first thing
//! seen (eq. 5.1), summed over the identity buffer's pixels; its DoV for a viewcell is
//! the maximum over the cell's eight corners (eq. 5.2).
//!
//! A grid of cells shares corners (a cell of a row shares four with each neighbour), so
//! [`cell_dovs`] takes a batch of cells, casts each distinct corner once, in parallel, and
//! then takes each cell's maxima: on a large grid that is about two corners per cell
//! instead of eight. Corners are the same only when their coordinates are bit for bit
//! the same (−0 and +0 aside): cells cut from one grid by the same arithmetic are.
//! Batches taken one after another share corners too (the row of corners between two
//! bands of rows): [`CornerMemo`] keeps the last batch's corners for the next.
//!
//! A corner's point DoV comes from a [`DovSource`]: the rasterised item buffers
//! (`raster`, the precomputation's default) or the ray-cast (the reference, [`RayScene`]).
//! On an 80-object generated city's 17 cells at N = 256 the two differ by at most
//! 2·10⁻⁴ of the sphere a cell (the sum over objects of the absolute differences), and
//! the raster took 0.52 s against the rays' 2.8 s (`tests/dov_raster.rs`).

use std::collections::HashMap;
use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::cube::{CubicProjection, SKY};
use super::dov_sums::{DovSums, PointDov};
use super::raycast::{check_point, RayScene};
use crate::error::{Error, Result};
use crate::geom::Aabb;

/// A source of point DoVs: a scene that can say, for a viewpoint, which object each
/// pixel of the cubic projection shows, summed by object. The ray-cast [`RayScene`] is
/// the reference; the rasterised [`RasterScene`](super::RasterScene) is what the
/// precomputation uses by default; a GPU renderer of item buffers (the thesis's own
/// means) would be a third, outside the engine.
///
/// Objects are named by index, `0..object_count()`, in the order the scene was built.
pub trait DovSource: Sync {
    /// The objects a result may name.
    fn object_count(&self) -> usize;

    /// What `point` sees: every object at least one pixel shows, by index, and the sky.
    /// Errors: a point that is not finite; whatever the source itself can fail with.
    fn point_dov(&self, projection: &CubicProjection, point: [f32; 3]) -> Result<PointDov>;

    /// [`point_dov`](Self::point_dov) of each of `points`, in order. By default the
    /// points are spread over rayon's threads, each point on one; a source that renders
    /// batches (a GPU) would override this.
    fn point_dovs(
        &self,
        projection: &CubicProjection,
        points: &[[f32; 3]],
    ) -> Result<Vec<PointDov>> {
        points
            .par_iter()
            .map(|&p| self.point_dov(projection, p))
            .collect()
    }
}

impl DovSource for RayScene {
    fn object_count(&self) -> usize {
        RayScene::object_count(self)
    }

    fn point_dov(&self, projection: &CubicProjection, point: [f32; 3]) -> Result<PointDov> {
        point_dov(self, projection, point)
    }
}

impl DovSource for super::RasterScene {
    fn object_count(&self) -> usize {
        super::RasterScene::object_count(self)
    }

    fn point_dov(&self, projection: &CubicProjection, point: [f32; 3]) -> Result<PointDov> {
        check_point("viewpoint", point)?;
        Ok(self.point_dov_checked(projection, point))
    }
}

/// Which [`DovSource`] a precomputation builds from the objects' meshes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DovMethod {
    /// [`RasterScene`](super::RasterScene): item buffers drawn by the CPU rasteriser,
    /// front to back with hierarchical depth.
    #[default]
    Raster,
    /// [`RayScene`]: one ray per pixel into a BVH of every triangle; the reference.
    RayCast,
}

impl DovMethod {
    /// The source over `(id, mesh)` pairs, objects indexed in their order.
    pub fn scene<'a, I>(self, objects: I) -> Result<Box<dyn DovSource + Send>>
    where
        I: IntoIterator<Item = (u64, &'a crate::scene::Mesh)>,
    {
        Ok(match self {
            DovMethod::Raster => Box::new(super::RasterScene::new(objects)?),
            DovMethod::RayCast => Box::new(RayScene::new(objects)?),
        })
    }

    /// [`scene`](Self::scene) with each object's coarser levels (`levels[k]` those of
    /// the `k`-th object; an empty `levels`, none for any): the raster draws a far
    /// object through them ([`RasterScene::with_levels`](super::RasterScene::with_levels)),
    /// the ray-cast, the reference, ignores them. Refused when `levels` is neither empty
    /// nor one entry per object.
    pub fn scene_with_levels<'a, I>(
        self,
        objects: I,
        levels: &'a [Vec<(crate::scene::Mesh, f32)>],
    ) -> Result<Box<dyn DovSource + Send>>
    where
        I: ExactSizeIterator<Item = (u64, &'a crate::scene::Mesh)>,
    {
        if levels.is_empty() || self == DovMethod::RayCast {
            return self.scene(objects);
        }
        if levels.len() != objects.len() {
            return Err(Error::Invalid(format!(
                "coarse levels for {} objects, given {}",
                levels.len(),
                objects.len()
            )));
        }
        Ok(Box::new(super::RasterScene::with_levels(
            objects.zip(levels).map(|((id, m), l)| (id, m, &l[..])),
        )?))
    }
}

/// The DoV of every object from `point` by cubic projection: 6N² rays, each pixel's
/// ΔDoV credited to the object its ray meets first.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// use flaneur::visibility::{point_dov, CubicProjection, RayScene};
/// // Two unit cubes on the x axis, one behind the other as seen from the origin.
/// let cube = |x: f32| {
///     let mut m = citygen::Mesh::default();
///     for i in 0..8 {
///         let c = |bit: u32| if i & bit == 0 { -0.5 } else { 0.5 };
///         m.positions.push([x + c(1), c(2), c(4)]);
///     }
///     m.normals = vec![[0.0, 1.0, 0.0]; 8];
///     m.indices = vec![0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4,
///                      2, 6, 7, 2, 7, 3, 0, 4, 6, 0, 6, 2, 1, 3, 7, 1, 7, 5];
///     m
/// };
/// let (near, far) = (cube(3.0), cube(6.0));
/// let scene = RayScene::new([(10, &near), (20, &far)])?;
/// let seen = point_dov(&scene, &CubicProjection::new(128)?, [0.0, 0.0, 0.0])?;
/// // Only the near cube shows: its face, a unit square 2.5 away, covers 1.22 % of the
/// // sphere (at N = 128, give or take the pixels along its edges).
/// assert_eq!(seen.objects.len(), 1);
/// let (object, dov) = seen.objects[0];
/// assert_eq!(scene.object_id(object), Some(10));
/// assert!((dov - 0.01224).abs() < 0.0006, "{dov}");
/// # Ok(()) }
/// ```
pub fn point_dov(
    scene: &RayScene,
    projection: &CubicProjection,
    point: [f32; 3],
) -> Result<PointDov> {
    check_point("viewpoint", point)?;
    Ok(point_dov_checked(scene, projection, point))
}

fn point_dov_checked(scene: &RayScene, projection: &CubicProjection, point: [f32; 3]) -> PointDov {
    let n = projection.resolution() as usize;
    let weights = projection.weights();
    // Each band of rows sums its pixels into runs of one object, so that all bands of all
    // faces run in parallel without an identity buffer; sums in f64, because at N = 256 a
    // DoV adds up to 393,216 terms near 10⁻⁶.
    let bands: Vec<(Vec<(u32, f64)>, f64)> = (0..projection.bands())
        .into_par_iter()
        .map(|k| {
            let (face, rows) = projection.band_rows(k);
            let first = rows.start * n;
            let mut runs: Vec<(u32, f64)> = Vec::new();
            let mut sky = 0.0f64;
            projection.cast_rows(scene, point, face, rows, |pixel, id| {
                let w = weights[first + pixel] as f64;
                match runs.last_mut() {
                    _ if id == SKY => sky += w,
                    Some((last, sum)) if *last == id => *sum += w,
                    _ => runs.push((id, w)),
                }
            });
            (runs, sky)
        })
        .collect();
    let mut sums = DovSums::new(scene.object_count());
    for (runs, band_sky) in bands {
        sums.credit(SKY, band_sky);
        for (id, w) in runs {
            sums.credit(id, w);
        }
    }
    sums.finish()
}

/// The DoVs of a batch of viewcells.
#[derive(Clone, Debug, PartialEq)]
pub struct CellDovs {
    /// Per cell, in the order given: `(object index, DoV)` for every object that some
    /// corner sees, by index. A cell's DoVs may sum to more than 1 (each is a maximum
    /// over corners).
    pub cells: Vec<Vec<(u32, f32)>>,
    /// What it cost.
    pub stats: DovStats,
}

/// The cost of a [`cell_dovs`] run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DovStats {
    /// Cells in the batch.
    pub cells: usize,
    /// Distinct corners cast (at most 8 per cell; fewer where a batch before cast some).
    pub corners: usize,
    /// Pixels sampled (rays cast, for the ray-cast): `corners` × 6N².
    pub rays: u64,
    /// Wall-clock time of the whole batch.
    pub elapsed: Duration,
}

impl DovStats {
    /// Pixels (rays) per second of wall-clock time.
    pub fn rays_per_second(&self) -> f64 {
        self.rays as f64 / self.elapsed.as_secs_f64().max(f64::MIN_POSITIVE)
    }

    /// Wall-clock seconds per cell of the batch.
    pub fn seconds_per_cell(&self) -> f64 {
        self.elapsed.as_secs_f64() / self.cells.max(1) as f64
    }

    /// Distinct corners per cell: 8 for lone cells, towards 2 on a large grid.
    pub fn corners_per_cell(&self) -> f64 {
        self.corners as f64 / self.cells.max(1) as f64
    }
}

/// The point DoVs of the last batch's corners, so that the next batch casts only the
/// corners it does not share with it. Holds one batch's worth of [`PointDov`]s.
#[derive(Debug, Default)]
pub struct CornerMemo {
    last: HashMap<[u32; 3], PointDov>,
}

/// The distinct corners of `cells`, as the memo keys them.
pub(super) fn corner_keys(cells: &[Aabb]) -> std::collections::HashSet<[u32; 3]> {
    cells
        .iter()
        .flat_map(|c| corners(c).map(corner_key))
        .collect()
}

/// A corner's key: its coordinates' bits, with −0 made +0 (adding +0 does that).
fn corner_key(p: [f32; 3]) -> [u32; 3] {
    p.map(|c| (c + 0.0).to_bits())
}

/// The eight corners of a box: bit 0 of the index picks max x, bit 1 max y, bit 2 max z.
pub fn corners(cell: &Aabb) -> [[f32; 3]; 8] {
    super::cells::corners(cell).map(|c| c.to_array())
}

/// The DoV of every object for each of `cells` (eq. 5.2: the maximum of its point DoVs
/// over the cell's eight corners), casting each corner shared by several cells once.
///
/// Errors: a cell with a coordinate that is not finite, or whose max is not greater
/// than its min on every axis (a flat, empty or inverted box); the error names the cell
/// by its index in `cells`.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// use flaneur::geom::Aabb;
/// use flaneur::visibility::{cell_dovs, CubicProjection, RayScene};
/// let wall = citygen::Mesh {
///     positions: vec![[-5.0, 0.0, 10.0], [5.0, 0.0, 10.0], [5.0, 6.0, 10.0], [-5.0, 6.0, 10.0]],
///     normals: vec![[0.0, 0.0, -1.0]; 4],
///     indices: vec![0, 1, 2, 0, 2, 3],
/// };
/// let scene = RayScene::new([(0, &wall)])?;
/// // Two cells side by side: 12 distinct corners, not 16.
/// let cells = [
///     Aabb::new([0.0, 1.2, 0.0], [2.0, 2.0, 2.0])?,
///     Aabb::new([2.0, 1.2, 0.0], [4.0, 2.0, 2.0])?,
/// ];
/// let result = cell_dovs(&scene, &CubicProjection::new(32)?, &cells)?;
/// assert_eq!(result.stats.corners, 12);
/// assert!(result.cells.iter().all(|c| c.len() == 1 && c[0].0 == 0 && c[0].1 > 0.0));
/// # Ok(()) }
/// ```
pub fn cell_dovs<S: DovSource + ?Sized>(
    scene: &S,
    projection: &CubicProjection,
    cells: &[Aabb],
) -> Result<CellDovs> {
    cell_dovs_after(scene, projection, cells, &mut CornerMemo::default())
}

/// [`cell_dovs`] for one of a run of batches: corners the last batch (in `memo`) cast
/// are taken from it, not cast again, and `memo` then holds this batch's corners.
/// [`DovStats::corners`] counts only the corners cast.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// use flaneur::geom::Aabb;
/// use flaneur::visibility::{cell_dovs, cell_dovs_after, CornerMemo, CubicProjection, RayScene};
/// let wall = citygen::Mesh {
///     positions: vec![[-5.0, 0.0, 10.0], [5.0, 0.0, 10.0], [5.0, 6.0, 10.0], [-5.0, 6.0, 10.0]],
///     normals: vec![[0.0, 0.0, -1.0]; 4],
///     indices: vec![0, 1, 2, 0, 2, 3],
/// };
/// let scene = RayScene::new([(0, &wall)])?;
/// let cube = CubicProjection::new(32)?;
/// let first = [Aabb::new([0.0, 1.2, 0.0], [2.0, 2.0, 2.0])?];
/// let second = [Aabb::new([0.0, 1.2, 2.0], [2.0, 2.0, 4.0])?];
/// let mut memo = CornerMemo::default();
/// assert_eq!(cell_dovs_after(&scene, &cube, &first, &mut memo)?.stats.corners, 8);
/// // The second cell shares four corners with the first.
/// let next = cell_dovs_after(&scene, &cube, &second, &mut memo)?;
/// assert_eq!(next.stats.corners, 4);
/// assert_eq!(next.cells, cell_dovs(&scene, &cube, &second)?.cells);
/// # Ok(()) }
/// ```
pub fn cell_dovs_after<S: DovSource + ?Sized>(
    scene: &S,
    projection: &CubicProjection,
    cells: &[Aabb],
    memo: &mut CornerMemo,
) -> Result<CellDovs> {
    let started = Instant::now();
    for (i, cell) in cells.iter().enumerate() {
        check_cell(i, cell)?;
    }
    let mut index: HashMap<[u32; 3], u32> = HashMap::new();
    let mut points: Vec<[f32; 3]> = Vec::new();
    let cell_corners: Vec<[u32; 8]> = cells
        .iter()
        .map(|cell| {
            corners(cell).map(|p| {
                *index.entry(corner_key(p)).or_insert_with(|| {
                    points.push(p);
                    (points.len() - 1) as u32
                })
            })
        })
        .collect();
    let mut last = std::mem::take(&mut memo.last);
    let known: Vec<Option<PointDov>> = points
        .iter()
        .map(|&p| last.remove(&corner_key(p)))
        .collect();
    let missing: Vec<[f32; 3]> = points
        .iter()
        .zip(&known)
        .filter(|(_, k)| k.is_none())
        .map(|(&p, _)| p)
        .collect();
    let cast = missing.len();
    let mut drawn = scene.point_dovs(projection, &missing)?.into_iter();
    let seen: Vec<PointDov> = known
        .into_iter()
        .map(|k| k.or_else(|| drawn.next()))
        .collect::<Option<_>>()
        .ok_or_else(|| Error::Invalid("a DoV source returned too few viewpoints".into()))?;
    let dovs = cell_corners
        .iter()
        .map(|corner| {
            let mut all: Vec<(u32, f32)> = corner
                .iter()
                .flat_map(|&c| seen[c as usize].objects.iter().copied())
                .collect();
            all.sort_unstable_by_key(|&(o, _)| o);
            all.dedup_by(|later, kept| {
                let same = later.0 == kept.0;
                if same {
                    kept.1 = kept.1.max(later.1);
                }
                same
            });
            all
        })
        .collect();
    memo.last = points.iter().map(|&p| corner_key(p)).zip(seen).collect();
    Ok(CellDovs {
        cells: dovs,
        stats: DovStats {
            cells: cells.len(),
            corners: cast,
            rays: cast as u64 * projection.rays_per_point(),
            elapsed: started.elapsed(),
        },
    })
}

/// A viewcell must be a finite box with volume: its eight corners distinct.
fn check_cell(cell: usize, b: &Aabb) -> Result<()> {
    let bad = |what: String| Err(Error::BadViewcell { cell, what });
    if !b.min.is_finite() || !b.max.is_finite() {
        return bad(format!(
            "box {:?}–{:?} has a coordinate that is not finite",
            b.min.to_array(),
            b.max.to_array()
        ));
    }
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let (lo, hi) = (b.min[k], b.max[k]);
        if hi < lo {
            return bad(format!("box is inverted on {axis}: min {lo} > max {hi}"));
        }
        if hi == lo {
            return bad(format!(
                "box has zero size on {axis} (min = max = {lo}); a viewcell needs volume"
            ));
        }
    }
    Ok(())
}
