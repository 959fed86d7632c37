//! The rasterised scene: every object's triangles, its box, and the hierarchy over the
//! boxes; and the cube's six item buffers drawn from one viewpoint, front to back.

use std::time::{Duration, Instant};

use rustc_hash::FxHashMap;

use super::buffer::ItemBuffer;
use super::face::{Face, NEAR};
use super::tree::{Kind, ObjectTree};
use super::triangle::{self, Vertex};
use crate::error::{Error, Result};
use crate::scene::Mesh;
use crate::visibility::cube::{CubicProjection, SKY};
use crate::visibility::dov_sums::{DovSums, PointDov};
use crate::visibility::raycast::{check_mesh, check_point, zero_area};

/// Objects' triangle meshes, drawn by a CPU rasteriser into the cubic projection's item
/// buffers: the same DoVs as the ray-cast [`RayScene`](super::super::RayScene), a
/// pixel's object found by depth-buffered drawing rather than by a ray per pixel.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// use flaneur::visibility::{CubicProjection, DovSource, RasterScene};
/// // A unit square 2.5 m in front of the viewpoint, along +x.
/// let wall = citygen::Mesh {
///     positions: vec![[2.5, -0.5, -0.5], [2.5, 0.5, -0.5], [2.5, 0.5, 0.5], [2.5, -0.5, 0.5]],
///     normals: vec![[-1.0, 0.0, 0.0]; 4],
///     indices: vec![0, 1, 2, 0, 2, 3],
/// };
/// let scene = RasterScene::new([(7, &wall)])?;
/// let seen = scene.point_dov(&CubicProjection::new(128)?, [0.0, 0.0, 0.0])?;
/// assert_eq!(seen.objects.len(), 1);
/// assert!((seen.objects[0].1 - 0.01224).abs() < 0.0006);
/// # Ok(()) }
/// ```
pub struct RasterScene {
    ids: Vec<u64>,
    /// Each mesh's distinct vertex positions, those of mesh `m` at
    /// `vertex_first[m]..vertex_first[m + 1]`: a vertex is projected once on a face for
    /// all the triangles sharing it (a generated building has about 0.6 a triangle).
    vertices: Vec<[f32; 3]>,
    vertex_first: Vec<u32>,
    /// Triangles as indices into their mesh's run of `vertices`, those of mesh `m` at
    /// `first[m]..first[m + 1]`, in the mesh's order (the first drawn wins a tie).
    triangles: Vec<[u32; 3]>,
    first: Vec<u32>,
    /// Object `o`'s meshes are `level_first[o]..level_first[o + 1]`: its full mesh, then
    /// its coarser levels, finest first.
    level_first: Vec<u32>,
    /// Each mesh's geometric error in metres (0 for a full mesh).
    errors: Vec<f32>,
    /// Each object's box, around all its meshes.
    boxes: Vec<([f32; 3], [f32; 3])>,
    tree: ObjectTree,
    build_time: Duration,
}

/// How far a coarse level's surface may move on a face when it is drawn for an object's
/// full mesh, in pixels: a level is drawn from a viewpoint only if its error, seen from
/// the nearest point of the object's box, is under this share of the narrowest pixel.
pub const LOD_PIXELS: f32 = 0.25;

/// What drawing one viewpoint's six faces cost ([`RasterScene::draw_counts`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DrawCounts {
    /// Objects whose triangles were set up on a face (summed over the faces).
    pub objects: u64,
    /// Triangles set up (projected and tested against the pixel centres).
    pub triangles: u64,
    /// Of those, the triangles that won at least one pixel's depth test.
    pub covering: u64,
    /// Objects drawn through a coarse level rather than their full mesh.
    pub coarse_objects: u64,
}

/// A triangle the viewpoint lies on: its object, unit normal and the viewpoint's signed
/// distance to its plane along it.
struct Through {
    object: u32,
    normal: [f64; 3],
    h: f64,
}

/// An object's coarser meshes, finest first, each with its geometric error in metres:
/// how far its surface lies from the full mesh's.
pub type CoarseLevels = [(Mesh, f32)];

impl RasterScene {
    /// The scene of `(id, mesh)` pairs, in world coordinates; objects are then named by
    /// their index in this sequence, as [`RayScene::new`](super::super::RayScene::new)
    /// names them, and refused for the same faults. Zero-area triangles are dropped, as
    /// the ray-cast drops them.
    pub fn new<'a, I>(objects: I) -> Result<RasterScene>
    where
        I: IntoIterator<Item = (u64, &'a Mesh)>,
    {
        Self::with_levels(objects.into_iter().map(|(id, m)| (id, m, &[][..])))
    }

    /// [`new`](Self::new), each object with its coarser levels (possibly none): a
    /// viewpoint draws an object through the coarsest level whose error, seen from the
    /// nearest point of the object's box, moves its surface by less than [`LOD_PIXELS`]
    /// of a pixel on a face (the error bound in the module's docs). Refused, naming the
    /// object, for a level the full mesh would be refused for, or an error that is not a
    /// finite number of metres ≥ 0.
    pub fn with_levels<'a, I>(objects: I) -> Result<RasterScene>
    where
        I: IntoIterator<Item = (u64, &'a Mesh, &'a CoarseLevels)>,
    {
        let started = Instant::now();
        let (mut ids, mut triangles, mut first, mut boxes) = (vec![], vec![], vec![0], vec![]);
        let (mut vertices, mut vertex_first) = (vec![], vec![0]);
        let (mut level_first, mut errors) = (vec![0], vec![]);
        let mut welded = FxHashMap::default();
        for (id, mesh, levels) in objects {
            check_mesh(id, mesh)?;
            if ids.len() >= u32::MAX as usize - 1 {
                return Err(Error::Invalid(
                    "a raster scene holds at most 2^32 - 2 objects".into(),
                ));
            }
            ids.push(id);
            let (mut lo, mut hi) = mesh.bounds();
            for (k, (level, error)) in levels.iter().enumerate() {
                check_mesh(id, level).map_err(|e| {
                    Error::Invalid(format!("coarse level {} of object {id}: {e}", k + 1))
                })?;
                if !(error.is_finite() && *error >= 0.0) {
                    return Err(Error::Invalid(format!(
                        "coarse level {} of object {id} has error {error}, not a finite \
                         number of metres >= 0",
                        k + 1
                    )));
                }
                // The box holds every level, so that culling by it stays exact for
                // whichever is drawn.
                let (a, b) = level.bounds();
                lo = std::array::from_fn(|c| lo[c].min(a[c]));
                hi = std::array::from_fn(|c| hi[c].max(b[c]));
            }
            let all = std::iter::once((mesh, 0.0)).chain(levels.iter().map(|(m, e)| (m, *e)));
            for (mesh, error) in all {
                // Positions equal bit for bit are one vertex: a generated mesh repeats
                // each corner for every face meeting there, to give it that face's normal.
                let base = vertices.len();
                welded.clear();
                let local: Vec<u32> = mesh
                    .positions
                    .iter()
                    .map(|p| {
                        *welded.entry(p.map(f32::to_bits)).or_insert_with(|| {
                            vertices.push(*p);
                            (vertices.len() - base - 1) as u32
                        })
                    })
                    .collect();
                triangles.extend(mesh.indices.chunks_exact(3).filter_map(|t| {
                    let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
                    (!zero_area(a, b, c)).then(|| [t[0], t[1], t[2]].map(|i| local[i as usize]))
                }));
                first.push(u32::try_from(triangles.len()).map_err(|_| {
                    Error::Invalid("a raster scene holds at most 2^32 - 1 triangles".into())
                })?);
                vertex_first.push(u32::try_from(vertices.len()).map_err(|_| {
                    Error::Invalid("a raster scene holds at most 2^32 - 1 vertices".into())
                })?);
                errors.push(error);
            }
            level_first.push(u32::try_from(errors.len()).map_err(|_| {
                Error::Invalid("a raster scene holds at most 2^32 - 1 meshes".into())
            })?);
            boxes.push((lo, hi));
        }
        Ok(RasterScene {
            tree: ObjectTree::new(&boxes),
            ids,
            vertices,
            vertex_first,
            triangles,
            first,
            level_first,
            errors,
            boxes,
            build_time: started.elapsed(),
        })
    }

    /// The number of objects, including those whose triangles all had zero area.
    pub fn object_count(&self) -> usize {
        self.ids.len()
    }

    /// The number of the full meshes' triangles (zero-area ones dropped).
    pub fn triangle_count(&self) -> usize {
        (0..self.ids.len())
            .map(|o| {
                let m = self.level_first[o] as usize;
                (self.first[m + 1] - self.first[m]) as usize
            })
            .sum()
    }

    /// What drawing the six faces around `point` costs: the objects and triangles set
    /// up, and the triangles that took a pixel.
    pub fn draw_counts(&self, projection: &CubicProjection, point: [f32; 3]) -> Result<DrawCounts> {
        check_point("viewpoint", point)?;
        let mut counts = DrawCounts::default();
        self.draw_counted(projection, point, &mut counts, |_, _| {});
        Ok(counts)
    }

    /// The id of object `object` (an index), or `None` past the end.
    pub fn object_id(&self, object: u32) -> Option<u64> {
        self.ids.get(object as usize).copied()
    }

    /// How long [`new`](Self::new) took.
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// The item buffer of viewpoint `point`, laid out as
    /// [`CubicProjection::identity_buffer`] lays out the ray-cast's: pixel (`i`, `j`)
    /// of face `f` at `(f·N + j)·N + i`, holding an object index or [`SKY`].
    pub fn item_buffer(&self, projection: &CubicProjection, point: [f32; 3]) -> Result<Vec<u32>> {
        check_point("viewpoint", point)?;
        let mut all = Vec::with_capacity(projection.rays_per_point() as usize);
        self.draw(projection, point, |_, buf| all.extend_from_slice(&buf.ids));
        Ok(all)
    }

    /// The point DoV of checked `point`: each face drawn, then its pixels' weights summed
    /// by object.
    pub(crate) fn point_dov_checked(
        &self,
        projection: &CubicProjection,
        point: [f32; 3],
    ) -> PointDov {
        let weights = projection.weights();
        let mut sums = DovSums::new(self.ids.len());
        self.draw(projection, point, |_, buf| {
            // Runs of one object, mostly long, summed before they are credited.
            let (mut run, mut sum) = (SKY, 0.0f64);
            for (&id, &w) in buf.ids.iter().zip(weights) {
                if id != run {
                    sums.credit(run, sum);
                    (run, sum) = (id, 0.0);
                }
                sum += w as f64;
            }
            sums.credit(run, sum);
        });
        sums.finish()
    }

    /// Draws the six faces around `eye` in turn, handing each finished one to `done`.
    fn draw(
        &self,
        projection: &CubicProjection,
        eye: [f32; 3],
        done: impl FnMut(usize, &ItemBuffer),
    ) {
        self.draw_counted(projection, eye, &mut DrawCounts::default(), done);
    }

    /// [`draw`](Self::draw), adding what it cost to `counts`.
    fn draw_counted(
        &self,
        projection: &CubicProjection,
        eye: [f32; 3],
        counts: &mut DrawCounts,
        mut done: impl FnMut(usize, &ItemBuffer),
    ) {
        let n = projection.resolution();
        // A surface moved by e metres at distance d turns by at most e/d radians, and
        // an angle α moves a face's image by at most α·N/(2·√2/3) pixels (the narrowest
        // pixel, at a face's corner, spans (2/N)·√2/3 radians).
        let per_metre = LOD_PIXELS * 2.0 * std::f32::consts::SQRT_2 / (3.0 * n as f32);
        let through = self.through(eye);
        let mut buf = ItemBuffer::new(n);
        let mut projected = Vec::new();
        for f in 0..6 {
            if f > 0 {
                buf.clear();
            }
            let face = Face::new(f, eye, n);
            for t in &through {
                paint_through(&face, &mut buf, t);
            }
            self.draw_face(&face, &mut buf, &mut projected, per_metre, counts);
            done(f, &buf);
        }
    }

    /// Visits the hierarchy nearest first, skipping every node and object whose box is
    /// off the face or behind what is drawn, and draws the triangles of the rest.
    fn draw_face(
        &self,
        face: &Face,
        buf: &mut ItemBuffer,
        projected: &mut Vec<Vertex>,
        per_metre: f32,
        counts: &mut DrawCounts,
    ) {
        let nodes = &self.tree.nodes;
        let mut stack = if nodes.is_empty() { vec![] } else { vec![0u32] };
        while let Some(node) = stack.pop() {
            let node = &nodes[node as usize];
            match face.footprint(node.lo, node.hi) {
                Some(f) if !buf.hides(&f) => {}
                _ => continue,
            }
            match node.kind {
                Kind::Inner(a, b) => {
                    let d = |c: u32| face.distance2(nodes[c as usize].lo, nodes[c as usize].hi);
                    // The nearer child is popped first.
                    if d(a) <= d(b) {
                        stack.extend([b, a]);
                    } else {
                        stack.extend([a, b]);
                    }
                }
                Kind::Leaf { first, count } => {
                    for &o in &self.tree.order[first as usize..(first + count) as usize] {
                        self.draw_object(face, buf, o, projected, per_metre, counts);
                    }
                }
            }
        }
    }

    /// Draws object `o` unless its box is off the face or hidden, through the coarsest
    /// level whose error is under `per_metre` times the distance to its box; `projected`
    /// is scratch for its vertices on the face.
    fn draw_object(
        &self,
        face: &Face,
        buf: &mut ItemBuffer,
        o: u32,
        projected: &mut Vec<Vertex>,
        per_metre: f32,
        counts: &mut DrawCounts,
    ) {
        let (lo, hi) = self.boxes[o as usize];
        let distance2 = match face.footprint(lo, hi) {
            Some(f) if !buf.hides(&f) => f.distance2,
            _ => return,
        };
        let (full, end) = (
            self.level_first[o as usize],
            self.level_first[o as usize + 1],
        );
        let budget = per_metre * per_metre * distance2;
        let m = (full + 1..end)
            .rev()
            .find(|&m| {
                let e = self.errors[m as usize];
                e * e < budget
            })
            .unwrap_or(full) as usize;
        counts.objects += 1;
        counts.coarse_objects += (m != full as usize) as u64;
        let vertices =
            &self.vertices[self.vertex_first[m] as usize..self.vertex_first[m + 1] as usize];
        projected.clear();
        projected.extend(vertices.iter().map(|&p| Vertex::new(face, p)));
        let projected = &projected[..];
        let triangles = &self.triangles[self.first[m] as usize..self.first[m + 1] as usize];
        counts.triangles += triangles.len() as u64;
        for t in triangles {
            counts.covering +=
                triangle::draw(face, buf, t.map(|k| &projected[k as usize]), o) as u64;
        }
    }

    /// The world positions of object `o`'s full mesh's triangles.
    fn object_triangles(&self, o: usize) -> impl Iterator<Item = [[f32; 3]; 3]> + '_ {
        let m = self.level_first[o] as usize;
        let vertices = &self.vertices[self.vertex_first[m] as usize..];
        self.triangles[self.first[m] as usize..self.first[m + 1] as usize]
            .iter()
            .map(move |t| t.map(|k| vertices[k as usize]))
    }

    /// The triangles `eye` lies on (within [`NEAR`] of their plane, its foot inside):
    /// the ray-cast meets them at distance 0 (or next to it) in every direction on their
    /// side, which no projection can draw.
    fn through(&self, eye: [f32; 3]) -> Vec<Through> {
        let near = NEAR as f64;
        let mut found = Vec::new();
        for (o, (lo, hi)) in self.boxes.iter().enumerate() {
            if (0..3).any(|k| eye[k] < lo[k] - NEAR || eye[k] > hi[k] + NEAR) {
                continue;
            }
            for t in self.object_triangles(o) {
                let [a, b, c] = t.map(|p| std::array::from_fn(|k| p[k] as f64 - eye[k] as f64));
                let n = cross(sub(b, a), sub(c, a));
                let len = dot(n, n).sqrt();
                if len == 0.0 {
                    continue;
                }
                let normal = n.map(|x| x / len);
                let h = dot(normal, a);
                if h.abs() > near {
                    continue;
                }
                let foot = normal.map(|x| x * h);
                let inside = [(a, b), (b, c), (c, a)]
                    .iter()
                    .all(|&(p, q)| dot(cross(sub(q, p), sub(foot, p)), n) >= 0.0);
                if inside {
                    found.push(Through {
                        object: o as u32,
                        normal,
                        h,
                    });
                }
            }
        }
        found
    }
}

/// Gives the pixels whose ray meets the through-triangle `t` at distance 0 to its
/// object, nearer than anything drawn after.
fn paint_through(face: &Face, buf: &mut ItemBuffer, t: &Through) {
    let n = buf.n;
    for j in 0..n {
        for i in 0..n {
            let d = face.direction(i, j);
            let nd = (0..3).map(|k| t.normal[k] * d[k] as f64).sum::<f64>();
            let k = (j * n + i) as usize;
            if nd != 0.0 && t.h * nd >= 0.0 && buf.depth[k] < f32::INFINITY {
                buf.depth[k] = f32::INFINITY;
                buf.ids[k] = t.object;
            }
        }
    }
    buf.touch_all();
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

impl std::fmt::Debug for RasterScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RasterScene")
            .field("objects", &self.ids.len())
            .field("triangles", &self.triangles.len())
            .field("tree_nodes", &self.tree.nodes.len())
            .finish()
    }
}
