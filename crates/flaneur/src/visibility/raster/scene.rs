//! The rasterised scene: every object's triangles, its box, and the hierarchy over the
//! boxes; and the cube's six item buffers drawn from one viewpoint, front to back.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::time::{Duration, Instant};

use super::buffer::ItemBuffer;
use super::face::{Face, NEAR};
use super::tree::{Kind, ObjectTree};
use super::triangle::{self, Vertex};
use crate::error::{Error, Result};
use crate::scene::Mesh;
use crate::visibility::cube::{CubicProjection, SKY};
use crate::visibility::dov::{DovSums, PointDov};
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
    /// Each object's distinct vertex positions, those of object `o` at
    /// `vertex_first[o]..vertex_first[o + 1]`: a vertex is projected once on a face for
    /// all the triangles sharing it (a generated building has about 0.6 a triangle).
    vertices: Vec<[f32; 3]>,
    vertex_first: Vec<u32>,
    /// Triangles as indices into their object's run of `vertices`, those of object `o`
    /// at `first[o]..first[o + 1]`, in the mesh's order (the first drawn wins a tie).
    triangles: Vec<[u32; 3]>,
    first: Vec<u32>,
    boxes: Vec<([f32; 3], [f32; 3])>,
    tree: ObjectTree,
    build_time: Duration,
}

/// A triangle the viewpoint lies on: its object, unit normal and the viewpoint's signed
/// distance to its plane along it.
struct Through {
    object: u32,
    normal: [f64; 3],
    h: f64,
}

impl RasterScene {
    /// The scene of `(id, mesh)` pairs, in world coordinates; objects are then named by
    /// their index in this sequence, as [`RayScene::new`](super::super::RayScene::new)
    /// names them, and refused for the same faults. Zero-area triangles are dropped, as
    /// the ray-cast drops them.
    pub fn new<'a, I>(objects: I) -> Result<RasterScene>
    where
        I: IntoIterator<Item = (u64, &'a Mesh)>,
    {
        let started = Instant::now();
        let (mut ids, mut triangles, mut first, mut boxes) = (vec![], vec![], vec![0], vec![]);
        let (mut vertices, mut vertex_first) = (vec![], vec![0]);
        let mut welded = Weld::default();
        for (id, mesh) in objects {
            check_mesh(id, mesh)?;
            if ids.len() >= u32::MAX as usize - 1 {
                return Err(Error::Invalid(
                    "a raster scene holds at most 2^32 - 2 objects".into(),
                ));
            }
            ids.push(id);
            // Positions equal bit for bit are one vertex: a generated mesh repeats each
            // corner for every face meeting there, to give it that face's normal.
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
            let too_many =
                || Error::Invalid("a raster scene holds at most 2^32 - 1 triangles".into());
            first.push(u32::try_from(triangles.len()).map_err(|_| too_many())?);
            vertex_first.push(u32::try_from(vertices.len()).map_err(|_| too_many())?);
            boxes.push(mesh.bounds());
        }
        Ok(RasterScene {
            tree: ObjectTree::new(&boxes),
            ids,
            vertices,
            vertex_first,
            triangles,
            first,
            boxes,
            build_time: started.elapsed(),
        })
    }

    /// The number of objects, including those whose triangles all had zero area.
    pub fn object_count(&self) -> usize {
        self.ids.len()
    }

    /// The number of triangles drawn (zero-area ones dropped).
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
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
        mut done: impl FnMut(usize, &ItemBuffer),
    ) {
        let n = projection.resolution();
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
            self.draw_face(&face, &mut buf, &mut projected);
            done(f, &buf);
        }
    }

    /// Visits the hierarchy nearest first, skipping every node and object whose box is
    /// off the face or behind what is drawn, and draws the triangles of the rest.
    fn draw_face(&self, face: &Face, buf: &mut ItemBuffer, projected: &mut Vec<Vertex>) {
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
                        self.draw_object(face, buf, o, projected);
                    }
                }
            }
        }
    }

    /// Draws object `o` unless its box is off the face or hidden; `projected` is scratch
    /// for its vertices on the face.
    fn draw_object(&self, face: &Face, buf: &mut ItemBuffer, o: u32, projected: &mut Vec<Vertex>) {
        let (lo, hi) = self.boxes[o as usize];
        match face.footprint(lo, hi) {
            Some(f) if !buf.hides(&f) => {}
            _ => return,
        }
        let k = o as usize;
        let vertices =
            &self.vertices[self.vertex_first[k] as usize..self.vertex_first[k + 1] as usize];
        projected.clear();
        projected.extend(vertices.iter().map(|&p| Vertex::new(face, p)));
        let projected = &projected[..];
        for t in &self.triangles[self.first[k] as usize..self.first[k + 1] as usize] {
            triangle::draw(face, buf, t.map(|k| &projected[k as usize]), o);
        }
    }

    /// The world positions of object `o`'s triangles.
    fn object_triangles(&self, o: usize) -> impl Iterator<Item = [[f32; 3]; 3]> + '_ {
        let vertices = &self.vertices[self.vertex_first[o] as usize..];
        self.triangles[self.first[o] as usize..self.first[o + 1] as usize]
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

/// Welding's map from a position's bits to its vertex: a multiplicative hash (the
/// positions of one mesh, never an adversary's keys), several times faster than SipHash
/// over the 2 million triangles of a 3,000-object city.
type Weld = HashMap<[u32; 3], u32, BuildHasherDefault<WeldHasher>>;

#[derive(Default)]
struct WeldHasher(u64);

impl Hasher for WeldHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        // A `[u32; 3]` hashes its elements' bytes in one call.
        for c in bytes.chunks(4) {
            let mut word = [0; 4];
            word[..c.len()].copy_from_slice(c);
            self.write_u32(u32::from_le_bytes(word));
        }
    }

    fn write_u32(&mut self, x: u32) {
        self.0 = (self.0.rotate_left(5) ^ x as u64).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }

    fn write_usize(&mut self, _: usize) {}
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
