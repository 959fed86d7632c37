//! The view frustum and ViewCulling — Shou 2002, §4.3, Fig. 4.15.
//!
//! A frustum is a convex polytope with six planes (normals pointing in) and eight
//! corners. Its tight axis-aligned box is the **frustum cell** of §4.1, the region the
//! in-memory object buffer is searched with. [`Frustum::overlaps_aabb`] is the thesis's
//! ViewCulling, step for step:
//!
//! 1. if all eight box vertices are outside one frustum plane → disjoint;
//! 2. if a box vertex is inside the frustum → overlap;
//! 3. if a frustum vertex is inside the box → overlap;
//! 4. if a frustum edge crosses a box face, or a box edge crosses a frustum face →
//!    overlap; otherwise disjoint.
//!
//! Steps 2–4 make it exact for two convex polytopes: a non-empty intersection has a
//! vertex, and each vertex of the intersection is a vertex of one shape inside the other
//! or an edge of one crossing a face of the other. The thesis's line 10 tests "faces of H
//! against faces of R"; we test the edge/face pairs that this amounts to, both ways.
//!
//! Departures, named: the thesis's face normals point out of the frustum and "positive
//! side" means outside; ours point in, so step 1 asks for `signed_distance < 0`. Boxes
//! are closed (as [`Aabb`] is), so touching counts as overlapping. Every step allows a
//! tolerance of a few parts per million of the frustum's size (4 mm for a 1 km frustum):
//! a box that misses the frustum by less may be reported as overlapping, so that
//! floating-point rounding errs toward drawing an object rather than dropping it.
//! [`Frustum::cull_fast`] is step 1 alone: conservative (it never rejects a box that
//! overlaps), cheaper, and not what the REVIEW loop uses — that is the exact test.

use glam::Vec3;

use super::plane::Plane;
use super::Aabb;

/// The 12 edges of a frustum or box whose corner `i` has bit 0 = right/max x, bit 1 =
/// top/max y, bit 2 = far/max z: the pairs of corners that differ in one bit.
pub const EDGES: [(usize, usize); 12] = [
    (0, 1),
    (2, 3),
    (4, 5),
    (6, 7),
    (0, 2),
    (1, 3),
    (4, 6),
    (5, 7),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

/// A view frustum: six planes whose inside is the frustum, and its eight corners.
///
/// Build one with [`Camera::frustum`](super::Camera::frustum). Corner `i` is on the
/// right when bit 0 of `i` is set (left otherwise), on the top for bit 1, on the far
/// plane for bit 2. Planes are ordered near, far, left, right, bottom, top.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    planes: [Plane; 6],
    corners: [Vec3; 8],
    /// Tolerance of ViewCulling, metres: a few ppm of the frustum's size.
    eps: f32,
}

impl Frustum {
    /// The frustum with these planes (near, far, left, right, bottom, top, inside
    /// positive) and corners, ViewCulling's tolerance set from `scale`, the frustum's
    /// size in metres.
    pub(super) fn from_parts(planes: [Plane; 6], corners: [Vec3; 8], scale: f32) -> Frustum {
        Frustum {
            planes,
            corners,
            eps: scale * 4e-6,
        }
    }

    /// The six planes, inside positive: near, far, left, right, bottom, top.
    pub fn planes(&self) -> &[Plane; 6] {
        &self.planes
    }

    /// The eight corners; corner `i` is right for bit 0, top for bit 1, far for bit 2.
    pub fn corners(&self) -> &[Vec3; 8] {
        &self.corners
    }

    /// The frustum cell of Shou 2002 §4.1: the smallest axis-aligned box holding the frustum.
    pub fn aabb(&self) -> Aabb {
        Aabb::from_points(self.corners)
    }

    /// True when `p` is inside the frustum or on its boundary.
    pub fn contains_point(&self, p: Vec3) -> bool {
        self.planes.iter().all(|pl| pl.is_inside(p))
    }

    /// Step 1 of ViewCulling alone: false when all eight vertices of `b` are outside one
    /// plane (by more than the tolerance). Conservative: it may answer true for a box near a frustum edge that does
    /// not overlap the frustum, never false for one that does. For an exact answer use
    /// [`Frustum::overlaps_aabb`] (what the REVIEW loop uses). False for an empty box.
    pub fn cull_fast(&self, b: &Aabb) -> bool {
        usable(b) && !self.outside_one_plane(&box_corners(b))
    }

    /// ViewCulling (Shou 2002, Fig. 4.15): does the closed box `b` overlap the frustum?
    /// Exact for any finite box, flat and zero-sized ones included, up to the tolerance
    /// in the module docs; false for an empty or non-finite box.
    ///
    /// ```
    /// use flaneur::geom::{Aabb, Camera};
    /// use glam::Vec3;
    /// # fn main() -> flaneur::Result<()> {
    /// let f = Camera::new(Vec3::new(0.0, 1.7, 0.0), 0.0, 0.0)?.frustum(); // looks along +x
    /// let ahead: Aabb = "100,0,-10,120,30,10".parse()?;
    /// let behind: Aabb = "-50,0,-10,-30,30,10".parse()?;
    /// // Just outside the far left corner: no single plane has all eight vertices
    /// // outside, so the plane test alone keeps it; the exact test does not.
    /// let beside: Aabb = "999,0,-430,1010,30,-418".parse()?;
    /// assert!(f.overlaps_aabb(&ahead));
    /// assert!(!f.overlaps_aabb(&behind) && !f.cull_fast(&behind));
    /// assert!(f.cull_fast(&beside) && !f.overlaps_aabb(&beside));
    /// # Ok(()) }
    /// ```
    pub fn overlaps_aabb(&self, b: &Aabb) -> bool {
        if !usable(b) {
            return false;
        }
        let r = box_corners(b);
        // (1) all vertices of R outside one face of H.
        if self.outside_one_plane(&r) {
            return false;
        }
        // (2) a vertex of R inside H; (3) a vertex of H inside R.
        if r.iter().any(|&v| self.nearly_contains(v))
            || self.corners.iter().any(|&v| b.contains_point(v))
        {
            return true;
        }
        // (4) edge/face crossings, both ways.
        EDGES
            .iter()
            .any(|&(i, j)| self.segment_crosses_box_face(self.corners[i], self.corners[j], b))
            || EDGES
                .iter()
                .any(|&(i, j)| self.segment_crosses_face(r[i], r[j]))
    }

    fn outside_one_plane(&self, pts: &[Vec3; 8]) -> bool {
        self.planes
            .iter()
            .any(|pl| pts.iter().all(|&v| pl.signed_distance(v) < -self.eps))
    }

    /// [`Frustum::contains_point`] with the tolerance of ViewCulling.
    fn nearly_contains(&self, p: Vec3) -> bool {
        self.planes
            .iter()
            .all(|pl| pl.signed_distance(p) >= -self.eps)
    }

    /// Does segment `a`–`c` cross one of the six faces of the box `b`?
    fn segment_crosses_box_face(&self, a: Vec3, c: Vec3, b: &Aabb) -> bool {
        for axis in 0..3 {
            for plane in [b.min[axis], b.max[axis]] {
                let (da, dc) = (a[axis] - plane, c[axis] - plane);
                let Some(p) = crossing(a, c, da, dc) else {
                    continue;
                };
                let on_face = (0..3)
                    .filter(|&k| k != axis)
                    .all(|k| p[k] >= b.min[k] - self.eps && p[k] <= b.max[k] + self.eps);
                if on_face {
                    return true;
                }
            }
        }
        false
    }

    /// Does segment `a`–`c` cross one of the frustum's faces? A point of plane `i` is on
    /// face `i` when it is inside every other plane.
    fn segment_crosses_face(&self, a: Vec3, c: Vec3) -> bool {
        self.planes.iter().enumerate().any(|(i, pl)| {
            let Some(p) = crossing(a, c, pl.signed_distance(a), pl.signed_distance(c)) else {
                return false;
            };
            self.planes
                .iter()
                .enumerate()
                .all(|(j, q)| j == i || q.signed_distance(p) >= -self.eps)
        })
    }
}

/// Where segment `a`–`c` meets a plane, given the endpoints' signed distances to it;
/// `None` when both are strictly on one side, or the segment lies in the plane (its
/// crossings with the neighbouring faces are found instead).
fn crossing(a: Vec3, c: Vec3, da: f32, dc: f32) -> Option<Vec3> {
    if (da > 0.0 && dc > 0.0) || (da < 0.0 && dc < 0.0) || da == dc {
        return None;
    }
    let t = (da / (da - dc)).clamp(0.0, 1.0);
    Some(a + (c - a) * t)
}

fn usable(b: &Aabb) -> bool {
    b.min.is_finite() && b.max.is_finite() && !b.is_empty()
}

/// The eight vertices of a box, numbered like the frustum's corners (bit 0 = max x,
/// bit 1 = max y, bit 2 = max z) so that [`EDGES`] serves both.
pub fn box_corners(b: &Aabb) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 != 0 { b.max.x } else { b.min.x },
            if i & 2 != 0 { b.max.y } else { b.min.y },
            if i & 4 != 0 { b.max.z } else { b.min.z },
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Camera;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn cam() -> Camera {
        Camera::new(Vec3::new(10.0, 1.7, -20.0), 0.4, 0.05).unwrap()
    }

    fn b(min: Vec3, max: Vec3) -> Aabb {
        Aabb { min, max }
    }

    #[test]
    fn corners_lie_on_their_planes_and_in_the_cell() {
        let f = cam().frustum();
        let on = |plane: usize, i: usize| match plane {
            0 => i & 4 == 0,
            1 => i & 4 != 0,
            2 => i & 1 == 0,
            3 => i & 1 != 0,
            4 => i & 2 == 0,
            _ => i & 2 != 0,
        };
        for (k, pl) in f.planes().iter().enumerate() {
            assert!((pl.normal.length() - 1.0).abs() < 1e-5);
            for (i, &c) in f.corners().iter().enumerate() {
                let d = pl.signed_distance(c);
                if on(k, i) {
                    assert!(d.abs() < 1e-3, "corner {i} off plane {k} by {d}");
                } else {
                    assert!(d > 0.0, "corner {i} outside plane {k}: {d}");
                }
            }
        }
        let cell = f.aabb();
        assert!(f.corners().iter().all(|&c| cell.contains_point(c)));
    }

    #[test]
    fn the_four_cases_of_fig_4_13() {
        let c = cam();
        let f = c.frustum();
        let mid = c.position + c.forward() * 300.0;
        // (2) R inside H; (4) H inside R; (1) straddling; (3) disjoint.
        assert!(f.overlaps_aabb(&Aabb::around(mid, Vec3::splat(5.0))));
        assert!(f.overlaps_aabb(&Aabb::around(c.position, Vec3::splat(5000.0))));
        assert!(f.overlaps_aabb(&Aabb::around(c.far_center(), Vec3::splat(20.0))));
        assert!(!f.overlaps_aabb(&Aabb::around(
            c.position - c.forward() * 50.0,
            Vec3::splat(5.0)
        )));
        assert!(!f.overlaps_aabb(&Aabb::around(
            c.far_center() + c.forward() * 50.0,
            Vec3::splat(5.0)
        )));
        // A thin slab cutting straight through the middle has no vertex inside the
        // frustum and the frustum has none inside it: step 4 finds it.
        let slab = b(
            mid - Vec3::new(0.5, 1e4, 1e4),
            mid + Vec3::new(0.5, 1e4, 1e4),
        );
        assert!(f.overlaps_aabb(&slab));
        // A long pole through the frustum, crossing its side faces only.
        let r = c.right();
        let pole = Aabb::from_points([mid - r * 2000.0, mid + r * 2000.0]);
        assert!(f.overlaps_aabb(&pole));
    }

    #[test]
    fn degenerate_boxes() {
        let c = cam();
        let f = c.frustum();
        let mid = c.position + c.forward() * 100.0;
        assert!(f.overlaps_aabb(&b(mid, mid)));
        assert!(!f.overlaps_aabb(&b(c.position, c.position))); // the eye is before the near plane
        assert!(!f.overlaps_aabb(&Aabb::EMPTY));
        assert!(!f.overlaps_aabb(&b(Vec3::splat(f32::NAN), Vec3::splat(1.0))));
        assert!(!f.cull_fast(&Aabb::EMPTY));
        // Flat boxes: a wall across the view, a floor under it.
        let wall = b(Vec3::new(mid.x, -1e3, -1e4), Vec3::new(mid.x, 1e3, 1e4));
        assert!(f.overlaps_aabb(&wall));
        let floor = b(Vec3::new(-1e4, 0.0, -1e4), Vec3::new(1e4, 0.0, 1e4));
        assert!(f.overlaps_aabb(&floor));
        let sky = b(Vec3::new(-1e4, 2000.0, -1e4), Vec3::new(1e4, 2000.0, 1e4));
        assert!(!f.overlaps_aabb(&sky));
    }

    /// Sample-based lower bound: a box with a sample point inside the frustum overlaps
    /// it; fast culling never rejects what the exact test accepts.
    #[test]
    fn agrees_with_sampling_and_fast_culling() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let c = Camera::new(Vec3::new(0.0, 2.0, 0.0), 0.0, 0.0)
            .unwrap()
            .with_clip(1.0, 200.0)
            .unwrap();
        let f = c.frustum();
        let (mut hits, mut misses) = (0, 0);
        for _ in 0..3000 {
            let centre = Vec3::new(
                rng.gen_range(-60.0..260.0),
                rng.gen_range(-120.0..120.0),
                rng.gen_range(-150.0..150.0),
            );
            let half = Vec3::new(
                rng.gen_range(0.0..40.0),
                rng.gen_range(0.0..40.0),
                rng.gen_range(0.0..40.0),
            );
            let bx = Aabb::around(centre, half);
            let exact = f.overlaps_aabb(&bx);
            assert!(!exact || f.cull_fast(&bx));
            let sampled = (0..64).any(|_| {
                let t = Vec3::new(rng.gen(), rng.gen(), rng.gen());
                f.contains_point(bx.min + (bx.max - bx.min) * t)
            });
            assert!(!sampled || exact, "{bx} has a point inside the frustum");
            if exact {
                hits += 1
            } else {
                misses += 1
            }
        }
        assert!(hits > 300 && misses > 300, "{hits} hits, {misses} misses");
    }
}
