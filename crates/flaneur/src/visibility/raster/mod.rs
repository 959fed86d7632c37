//! The DoV by rasterised item buffers — Shou 2002, §5.5.2 (Fig. 5.10–5.11, eqs. 5.1–5.2
//! and 5.11): the thesis renders every object in its own colour into the six faces of a
//! cube around the viewpoint, with a z-buffer, and counts each colour's pixels weighted by
//! their solid angle. This is that rendering on the CPU.
//!
//! - `face`: a face's frame and pixel grid, sampled as the ray-cast samples it
//!   (pixel centres, `cube.rs`'s face and pixel convention), and a box's footprint.
//! - `triangle`: clipping (the near plane and a guard band) and fixed-point half-space
//!   edge functions with a top-left fill rule, a depth test per pixel.
//! - `buffer`: the item and depth buffers of a face, and the coarse depth of 4×4 tiles.
//! - `tree`: a hierarchy over the objects' boxes, visited front to back.
//! - `scene`: [`RasterScene`], the six faces drawn for a viewpoint, summed into a
//!   [`PointDov`](super::PointDov).
//!
//! What it keeps from the ray-cast reference (`raycast.rs`, `cube.rs`): one sample per
//! pixel centre, each pixel's weight from [`CubicProjection`](super::CubicProjection);
//! the depth is the distance along the face's axis, which is the ray parameter of the
//! cast, so the nearer surface wins as it does for a ray; no back-face culling; a
//! surface through the viewpoint is seen.
//!
//! Where it departs:
//! - **Hierarchical depth** (Greene et al. 1993, one coarse level): objects are drawn
//!   nearest first through a hierarchy of their boxes, and a node or object whose box
//!   lies behind every pixel of the tiles it covers is skipped with its triangles. The
//!   city behind the first rows of buildings then costs a box test per group. A
//!   triangle of a drawn object is rejected before its setup when its nearest vertex is
//!   no nearer than every pixel of the (fresh) tiles its pixel box reaches: its clamped
//!   `w` could take none of them, so the buffers stay the same bit for bit. Tiles of 4×4
//!   rather than 8×8 took the 3,000-object city's `--no-lod` shard 0/10 from 3.9 and 3.7 s
//!   of DoV to 3.0 and 2.6 s, and the triangle test to 2.8 and 2.2 s (busy cores).
//! - **Far objects through coarse levels.** A scene may hold, per object, coarser meshes
//!   with their geometric errors (`RasterScene::with_levels`; a build hands it the LOD
//!   chain it stores). From a viewpoint, an object is drawn through its coarsest level
//!   whose error e is under c·d, d the distance to the nearest point of the object's box
//!   (which holds every level) and c = `LOD_PIXELS`·(2/N)·√2/3 radians, a quarter of
//!   the narrowest pixel (at a face's corner a pixel spans (2/N)·√2/3). Taking e as the
//!   distance between the level's surface and the full mesh's, every point moves by at
//!   most e at distance ≥ d, so its direction turns by at most e/d < c and its image by
//!   less than `LOD_PIXELS` of a pixel. Hence the bound: a pixel changes owner only if
//!   its centre lies within a quarter pixel of the outline of an object drawn coarse, so
//!   a corner's DoVs move by at most the weight of those pixels (twice: one object's loss
//!   is another's gain), a quarter of a pixel along each far object's outline; an object
//!   whose box is within e/c is drawn in full. One exception: where two objects'
//!   surfaces lie within e of each other along a ray (touching buildings), the nearer
//!   may swap, as coincident walls already may. The LOD chain's error is a root mean
//!   square of the collapses' quadric distances, not a maximum, so the bound is argued,
//!   not proven; `flaneur bench dov-accuracy` (stored DoVs against the rays on full
//!   meshes) measures what it costs.
//! - **Edges.** Vertices are snapped to 1/256 of a pixel and the edge functions are exact,
//!   so shared edges leave no cracks (the ray-cast's Möller–Trumbore test may rarely
//!   slip through one); a pixel whose centre lies within about 1/512 of a pixel of a
//!   silhouette edge may go the other way than its ray does.
//! - **Depth** is `1/z` interpolated in f32 across the triangle: two surfaces nearer to
//!   each other than its precision (coincident walls) may show either, as for the cast.
//! - **Near.** Surfaces within 0.1 mm of the viewpoint along a face's axis are clipped,
//!   except a triangle the viewpoint lies on (within 0.1 mm of its plane, its foot
//!   inside it), which owns every direction on its side, as the cast meets it at
//!   distance 0 in all of them.

mod buffer;
mod face;
mod scene;
mod tree;
mod triangle;

pub use scene::{CoarseLevels, DrawCounts, RasterScene, LOD_PIXELS};

#[cfg(test)]
mod tests;
