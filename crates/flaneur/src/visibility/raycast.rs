//! The ray-cast scene: every object's triangles in one compressed wide BVH (obvhs's
//! CWBVH, Ylitie et al. 2017), and the first hit of a ray as an object index. This is the
//! identity buffer's source (Shou 2002, §5.5.2): where the thesis renders object ids into a
//! z-buffer, we cast one ray per pixel.
//!
//! One BVH over all triangles, with a triangle → object map, rather than a two-level BVH
//! (one over the objects' boxes, one per object): measured from street height in a
//! 400-object generated city (235k triangles), the same rays took 1.3–1.8× as long
//! through the two-level tree, because a street ray passes many buildings' boxes on the
//! way to its hit, and a flat tree culls by clusters of triangles, not whole buildings.
//! The triangles are stored in the BVH's leaf order, so a leaf's triangles are one run of
//! memory with no index indirection.
//!
//! obvhs speaks glam 0.34 and flaneur glam 0.29: points cross between them as `[f32; 3]`.

use std::time::Duration;

use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;

use crate::error::{Error, Result};
use crate::scene::Mesh;

/// The traversal stack of obvhs's CWBVH holds 32 entries and silently clamps beyond
/// them, so a deeper tree would give wrong hits rather than an error: refuse it at build.
const MAX_BVH_DEPTH: u32 = 31;

/// No candidate triangle, for [`RayScene::cast_near`].
pub(crate) const NO_TRIANGLE: u32 = u32::MAX;

/// The first surface a ray meets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Index of the object in the order the scene was built from.
    pub object: u32,
    /// The ray parameter of the hit: the distance in units of the direction's length.
    pub distance: f32,
}

/// Objects' triangle meshes in one BVH, for casting rays against: the source of the
/// identity buffer ([`CubicProjection::identity_buffer`](super::CubicProjection::identity_buffer)).
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// use flaneur::visibility::RayScene;
/// // One triangle in the plane z = 5, facing the origin.
/// let mesh = citygen::Mesh {
///     positions: vec![[-1.0, -1.0, 5.0], [1.0, -1.0, 5.0], [0.0, 1.0, 5.0]],
///     normals: vec![[0.0, 0.0, -1.0]; 3],
///     indices: vec![0, 1, 2],
/// };
/// let scene = RayScene::new([(42, &mesh)])?;
/// let hit = scene.first_hit([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])?.expect("the triangle");
/// assert_eq!((scene.object_id(hit.object), hit.distance), (Some(42), 5.0));
/// assert!(scene.first_hit([0.0, 0.0, 0.0], [0.0, 0.0, -1.0])?.is_none()); // sky
/// # Ok(()) }
/// ```
pub struct RayScene {
    /// `None` when no object has a triangle of non-zero area: every ray is sky.
    bvh: Option<CwBvh>,
    /// Triangles in the BVH's primitive order.
    triangles: Vec<RtTriangle>,
    /// The object index of each entry of `triangles`.
    triangle_object: Vec<u32>,
    ids: Vec<u64>,
    build_time: Duration,
}

impl RayScene {
    /// Builds the BVH over `(id, mesh)` pairs, in world coordinates. Objects are then
    /// named by their index in this sequence; [`object_id`](Self::object_id) maps back.
    ///
    /// Errors: a mesh with no triangle, indices that are not whole triangles or point past
    /// the positions, a position that is not finite (each names the object's id), more
    /// than `u32::MAX - 1` objects or triangles, or a BVH too deep to traverse.
    /// Zero-area triangles are dropped: no ray can hit them.
    pub fn new<'a, I>(objects: I) -> Result<RayScene>
    where
        I: IntoIterator<Item = (u64, &'a Mesh)>,
    {
        let started = std::time::Instant::now();
        let mut ids = Vec::new();
        let mut triangles = Vec::new();
        let mut triangle_object = Vec::new();
        for (id, mesh) in objects {
            check_mesh(id, mesh)?;
            let object = u32::try_from(ids.len())
                .ok()
                .filter(|&o| o != u32::MAX)
                .ok_or_else(|| {
                    Error::Invalid("a ray scene holds at most 2^32 - 2 objects".into())
                })?;
            ids.push(id);
            for t in mesh.indices.chunks_exact(3) {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
                if zero_area(a, b, c) {
                    continue;
                }
                triangles.push(Triangle {
                    v0: a.into(),
                    v1: b.into(),
                    v2: c.into(),
                });
                triangle_object.push(object);
            }
        }
        if triangles.len() >= u32::MAX as usize {
            return Err(Error::Invalid(format!(
                "a ray scene holds at most 2^32 - 2 triangles, not {}",
                triangles.len()
            )));
        }
        if triangles.is_empty() {
            return Ok(RayScene {
                bvh: None,
                triangles: Vec::new(),
                triangle_object: Vec::new(),
                ids,
                build_time: started.elapsed(),
            });
        }
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &triangles,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        let depth = max_depth(&bvh);
        if depth > MAX_BVH_DEPTH {
            return Err(Error::Invalid(format!(
                "the scene's BVH is {depth} levels deep; traversal handles at most \
                 {MAX_BVH_DEPTH} (is the geometry degenerate?)"
            )));
        }
        let (ordered, ordered_object) = bvh
            .primitive_indices
            .iter()
            .map(|&p| {
                let t = &triangles[p as usize];
                (
                    RtTriangle::new(t.v0, t.v1, t.v2),
                    triangle_object[p as usize],
                )
            })
            .unzip();
        Ok(RayScene {
            bvh: Some(bvh),
            triangles: ordered,
            triangle_object: ordered_object,
            ids,
            build_time: started.elapsed(),
        })
    }

    /// The number of objects, including those whose triangles all had zero area.
    pub fn object_count(&self) -> usize {
        self.ids.len()
    }

    /// The number of triangles in the BVH (zero-area ones dropped).
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The id of object `object` (an index), or `None` past the end.
    pub fn object_id(&self, object: u32) -> Option<u64> {
        self.ids.get(object as usize).copied()
    }

    /// How long [`new`](Self::new) took, checks and BVH build included.
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// The first object a ray from `origin` along `direction` meets (at any distance ≥ 0,
    /// front or back of a triangle), or `None` for sky. `direction` need not be unit.
    pub fn first_hit(&self, origin: [f32; 3], direction: [f32; 3]) -> Result<Option<Hit>> {
        check_point("ray origin", origin)?;
        if !direction.iter().all(|c| c.is_finite()) || direction == [0.0; 3] {
            return Err(Error::BadViewpoint(format!(
                "ray direction {direction:?} must be finite and non-zero"
            )));
        }
        Ok(self.cast(origin, direction))
    }

    /// [`first_hit`](Self::first_hit) for checked input.
    #[inline]
    pub(crate) fn cast(&self, origin: [f32; 3], direction: [f32; 3]) -> Option<Hit> {
        self.cast_near(origin, direction, [NO_TRIANGLE; 2])
            .map(|(triangle, distance)| Hit {
                object: self.triangle_object[triangle as usize],
                distance,
            })
    }

    /// The first hit as `(triangle, distance)`, for checked input, trying the
    /// `candidates` (triangles, or [`NO_TRIANGLE`]) first: neighbouring pixels mostly see
    /// the same triangle, and once it is hit the traversal only has to look nearer than
    /// it, which prunes every node behind it. The answer is the nearest hit whatever the
    /// candidates (at an exact tie, a candidate).
    #[inline]
    pub(crate) fn cast_near(
        &self,
        origin: [f32; 3],
        direction: [f32; 3],
        candidates: [u32; 2],
    ) -> Option<(u32, f32)> {
        let bvh = self.bvh.as_ref()?;
        let mut ray = Ray::new(origin.into(), direction.into(), 0.0, f32::INFINITY);
        let mut best = None;
        let repeat = candidates[1] == candidates[0];
        for c in &candidates[..2 - repeat as usize] {
            if let Some(tri) = self.triangles.get(*c as usize) {
                let t = tri.intersect(&ray);
                if t < ray.tmax {
                    ray.tmax = t;
                    best = Some((*c, t));
                }
            }
        }
        let mut hit = RayHit::none();
        let triangles = &self.triangles;
        // `p` indexes the BVH's primitive list, which `triangles` mirrors.
        if bvh.ray_traverse(ray, &mut hit, |ray, p| triangles[p].intersect(ray)) {
            Some((hit.primitive_id, hit.t))
        } else {
            best
        }
    }

    /// The object index of triangle `triangle` (an index from [`cast_near`](Self::cast_near)).
    #[inline]
    pub(crate) fn object_of(&self, triangle: u32) -> u32 {
        self.triangle_object[triangle as usize]
    }
}

impl std::fmt::Debug for RayScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RayScene")
            .field("objects", &self.ids.len())
            .field("triangles", &self.triangles.len())
            .field("bvh_nodes", &self.bvh.as_ref().map_or(0, |b| b.nodes.len()))
            .finish()
    }
}

/// Whether the triangle's edge vectors are parallel (or one is zero), as f32 computes it:
/// the ray test divides by this cross product, so such a triangle is never hit.
pub(super) fn zero_area(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> bool {
    let e = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let f = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    e[1] * f[2] - e[2] * f[1] == 0.0
        && e[2] * f[0] - e[0] * f[2] == 0.0
        && e[0] * f[1] - e[1] * f[0] == 0.0
}

/// A viewpoint or ray origin must be a finite point.
pub(crate) fn check_point(what: &str, p: [f32; 3]) -> Result<()> {
    if p.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(Error::BadViewpoint(format!(
            "{what} {p:?} has a coordinate that is not finite"
        )))
    }
}

pub(super) fn check_mesh(id: u64, mesh: &Mesh) -> Result<()> {
    let bad = |what: String| Err(Error::BadMesh { id, what });
    if mesh.indices.is_empty() {
        return bad("it has no triangles".into());
    }
    if !mesh.indices.len().is_multiple_of(3) {
        return bad(format!(
            "{} indices is not a whole number of triangles",
            mesh.indices.len()
        ));
    }
    let n = mesh.positions.len();
    if let Some((i, &ix)) = mesh
        .indices
        .iter()
        .enumerate()
        .find(|(_, &ix)| ix as usize >= n)
    {
        return bad(format!("index {i} is {ix}, but there are {n} positions"));
    }
    if let Some(i) = mesh
        .positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return bad(format!(
            "position {i} is not finite: {:?}",
            mesh.positions[i]
        ));
    }
    Ok(())
}

/// Levels from the root to the deepest leaf (the root alone is depth 1).
fn max_depth(bvh: &CwBvh) -> u32 {
    let mut deepest = 0;
    let mut stack = vec![(0u32, 1u32)];
    while let Some((node, depth)) = stack.pop() {
        deepest = deepest.max(depth);
        let node = &bvh.nodes[node as usize];
        for child in 0..8 {
            if !node.is_child_empty(child) && !node.is_leaf(child) {
                stack.push((node.child_node_index(child), depth + 1));
            }
        }
    }
    deepest
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(z: f32) -> Mesh {
        Mesh {
            positions: vec![
                [-1.0, -1.0, z],
                [1.0, -1.0, z],
                [1.0, 1.0, z],
                [-1.0, 1.0, z],
            ],
            normals: vec![[0.0, 0.0, -1.0]; 4],
            indices: vec![0, 1, 2, 0, 2, 3],
        }
    }

    #[test]
    fn the_nearer_object_wins_front_or_back() {
        let (near, far) = (quad(2.0), quad(4.0));
        let scene = RayScene::new([(7, &far), (9, &near)]).unwrap();
        let hit = scene.cast([0.1, 0.2, 0.0], [0.0, 0.0, 1.0]).unwrap();
        assert_eq!(scene.object_id(hit.object), Some(9));
        assert!((hit.distance - 2.0).abs() < 1e-6);
        // From behind both: the far one is now first, seen from its back.
        let hit = scene.cast([0.1, 0.2, 9.0], [0.0, 0.0, -2.0]).unwrap();
        assert_eq!(scene.object_id(hit.object), Some(7));
        assert!((hit.distance - 2.5).abs() < 1e-6);
        assert!(scene.cast([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]).is_none());
    }

    #[test]
    fn bad_meshes_are_errors_that_name_the_object() {
        let nan = Mesh {
            positions: vec![[0.0, f32::NAN, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            normals: vec![],
            indices: vec![0, 1, 2],
        };
        let empty = Mesh::default();
        let partial = Mesh {
            indices: vec![0, 1],
            ..quad(1.0)
        };
        let past_end = Mesh {
            indices: vec![0, 1, 9],
            ..quad(1.0)
        };
        for (mesh, words) in [
            (&nan, "not finite"),
            (&empty, "no triangles"),
            (&partial, "whole number"),
            (&past_end, "there are 4 positions"),
        ] {
            let err = RayScene::new([(31, mesh)]).unwrap_err();
            let msg = err.to_string();
            assert!(matches!(err, Error::BadMesh { id: 31, .. }), "{msg}");
            assert!(msg.contains("object 31") && msg.contains(words), "{msg}");
        }
    }

    #[test]
    fn degenerate_triangles_are_dropped_and_an_empty_scene_is_all_sky() {
        let flat = Mesh {
            positions: vec![[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [2.0, 0.0, 1.0]],
            normals: vec![],
            indices: vec![0, 1, 2],
        };
        let scene = RayScene::new([(1, &flat)]).unwrap();
        assert_eq!((scene.object_count(), scene.triangle_count()), (1, 0));
        assert_eq!(
            scene.first_hit([0.5, 0.0, 0.0], [0.0, 0.0, 1.0]).unwrap(),
            None
        );
        let none = RayScene::new(std::iter::empty()).unwrap();
        assert_eq!(none.first_hit([0.0; 3], [1.0, 0.0, 0.0]).unwrap(), None);
    }

    #[test]
    fn bad_rays_are_errors() {
        let q = quad(1.0);
        let scene = RayScene::new([(0, &q)]).unwrap();
        for (o, d) in [
            ([f32::NAN, 0.0, 0.0], [0.0, 0.0, 1.0]),
            ([0.0, f32::INFINITY, 0.0], [0.0, 0.0, 1.0]),
            ([0.0; 3], [0.0; 3]),
            ([0.0; 3], [0.0, f32::NAN, 1.0]),
        ] {
            assert!(matches!(scene.first_hit(o, d), Err(Error::BadViewpoint(_))));
        }
    }
}
