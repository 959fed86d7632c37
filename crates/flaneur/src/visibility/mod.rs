//! Precomputed from-region visibility — Shou 2002 §5.5 (and §5.2.1, eqs. 5.1–5.2):
//! viewcells over the walkable city, occluders, each cell's conservative potentially
//! visible set, and the degree of visibility (DoV) of its objects by cubic projection.
//!
//! - [`cells`](ViewcellGrid): the grid of viewcells, the walkable ones.
//! - `occluder`: a box inside each building's solid, its convex part (paper-notes).
//! - `conservative`: the conservative PVS of §5.5.1 (a `Scene`), by occluder shrinking
//!   and the occlusion horizons of sample points (`horizon`), sampled as
//!   [`SampleOptions`] say.
//! - `precompute`: all of it for a city, as `flaneur build --visibility` runs it with
//!   [`VisibilityOptions`]; `table` its bytes ([`TableHead`], each cell's [`CellPvs`]),
//!   `stored` their reading through the store ([`Database::visibility`],
//!   [`Database::pvs`]).
//! - `shard`: the precomputation split across processes ([`Shard`], [`ShardCells`],
//!   [`precompute_shard`]), merged by the build into the same table.
//! - `cost`: what the options imply over a city before any of it runs
//!   ([`VisibilityCost`]: cells, sample points, memory), checked by every build.
//! - `raster`: [`RasterScene`], the DoV by rasterised item buffers (the thesis's own
//!   means, on the CPU): each cube face drawn front to back with a depth buffer and
//!   hierarchical depth, far objects through coarse levels a build hands it
//!   ([`RasterScene::with_levels`], [`LOD_PIXELS`]). What the precomputation uses by
//!   default.
//! - `raycast`: [`RayScene`], the scene's triangles in one BVH; the first hit of a ray as
//!   an object ([`Hit`]). The reference the raster is tested against.
//! - `cube`: [`CubicProjection`], the cube's faces, pixels and their ΔDoV; the identity
//!   buffer.
//! - `dov`: point DoV ([`point_dov`], the sum of an object's pixels) and cell DoV
//!   ([`cell_dovs`], the maximum over a viewcell's eight corners), for a batch of cells
//!   sharing corners ([`cell_dovs_after`] for a run of batches), from any [`DovSource`]
//!   (the raster, the rays; a GPU's item buffers would be a third, outside the engine),
//!   chosen by [`DovMethod`].
//!
//! [`Database::visibility`]: crate::Database::visibility
//! [`Database::pvs`]: crate::Database::pvs
//!
//! The DoV computation's choices (the thesis renders object ids into a z-buffer on the
//! six faces of a cube; so does `raster`, and the reference casts one ray per pixel into
//! a BVH of the scene's triangles; `raster`'s top comment says where the two differ):
//!
//! - **Sampling.** One ray per pixel centre, no supersampling: a pixel belongs wholly to
//!   the first object its centre ray meets. N = 256 pixels per face side by default.
//! - **ΔDoV.** The pixel's exact solid angle over 4π, of which eq. 5.11 is the midpoint
//!   value; eq. 5.11 slightly overcounts the sphere, the exact form sums to 1 ([`CubicProjection`]).
//! - **Sky.** A pixel whose ray meets nothing belongs to no object; its share is reported
//!   as `sky`. The scene is what the caller gives: citygen builds no ground, so rays below
//!   the horizon that pass between buildings are sky, not ground.
//! - **Hits.** The first hit at any distance ≥ 0 (a surface through the viewpoint is hit),
//!   front or back of a triangle (no back-face culling, like a z-buffer without it): a
//!   viewpoint inside a closed object sees that object's inside in every direction. Two
//!   surfaces at exactly the same distance (coincident faces) may show either. The
//!   ray–triangle test is Möller–Trumbore in f32, not watertight: a ray exactly along an
//!   edge shared by two triangles may pass between them, so a pixel may rarely show what
//!   lies behind. Zero-area triangles are dropped.
//! - **Cells.** A viewcell is a box (the eye's height range over a patch of street); its
//!   sample points are its 8 corners and an object's DoV for it is the maximum of its
//!   point DoVs there (eq. 5.2). A box with zero size on an axis is refused: its corners
//!   would not be 8. Corners shared by cells of a batch are cast once, matched by their
//!   exact coordinates.
//! - **Zero DoV.** An object no pixel shows has DoV 0 and is left out of the results;
//!   the precomputation gives the "visible zero-DoV" objects (kept by the conservative
//!   test, unseen from every corner) DoV_s, [`CubicProjection::zero_dov_floor`], the
//!   smallest pixel's ΔDoV.
//! - **Precision.** Pixel weights are f32, each object's sum f64, results f32: the DoVs
//!   seen from one viewpoint and its sky sum to 1 within about 10⁻⁶.
//!
//! Speed of the ray-cast (`cargo bench --bench dov`: a 400-object generated city of 235k
//! triangles, street-height viewpoints, N = 256, two cores of an AMD EPYC): about 13
//! million rays per second, 30 ms per viewpoint; a batch of 36 street cells (4.4 distinct
//! corners per cell) took 0.15 s per cell. The thesis took 1.02 s per cell on its
//! hardware (§5.8.1). The raster, measured on the 3,000-object city (`citygen --objects
//! 3000 --seed 1`, 2.0 M triangles; `flaneur build c3k.scene -o s --no-lod --visibility
//! --shard 0/10`, 72 cells, two busy cores): its scene builds in 0.12 s; before its
//! boxes reaching behind the viewpoint were footprinted by their part in front, it drew
//! some 6,300 objects and 4.2 M triangles a corner (0.14–0.18 s a corner on one thread)
//! and the shard's DoV took 19.5 s against the ray-cast's 20.6 s; after, 2.1 s (29 ms a
//! cell), the whole shard 8.2 s against the old binary's 44.5 s. With each object's
//! vertices welded and projected once a face, and triangles between pixel centres
//! rejected on them, the same item buffers cost a third: the bench's raster 0.030 s a
//! cell against 0.086 s (one corner 7.0 ms against 19.2 ms), the shard's DoV 2.6 s
//! against 6.2 s with the two interleaved on busy cores.

mod cells;
mod conservative;
mod cost;
mod cube;
mod dov;
mod dov_sums;
mod horizon;
mod intersect;
mod occluder;
mod precompute;
mod raster;
mod raycast;
mod shard;
mod shown;
mod stored;
pub(crate) mod table;

#[cfg(test)]
mod tests;

pub use cells::{object_boxes, Viewcell, ViewcellGrid};
pub use conservative::{SampleOptions, Scene as ConservativeScene, MAX_SAMPLES_PER_CELL};
pub(crate) use cost::walkable_cells;
pub use cost::{VisibilityCost, MAX_VIEWCELLS};
pub use cube::{CubicProjection, SKY};
pub use dov::{
    cell_dovs, cell_dovs_after, point_dov, CellDovs, CornerMemo, DovMethod, DovSource, DovStats,
};
pub use dov_sums::PointDov;
pub(crate) use precompute::precompute;
pub use precompute::VisibilityOptions;
pub use raster::{CoarseLevels, DrawCounts, RasterScene, LOD_PIXELS};
pub use raycast::{Hit, RayScene};
pub(crate) use shard::merge_shards;
pub use shard::{fingerprint, precompute_shard, Shard, ShardCells, ShardLod};
pub(crate) use shown::shown;
pub(crate) use stored::VisibilityTable;
pub(crate) use table::encode_table;
pub use table::{
    CellEntry, CellPvs, TableHead, VisibilitySettings, VisibilityStats, VISIBILITY_SEGMENT,
};
