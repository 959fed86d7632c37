//! The exact tests the conservative visibility rests on: does a triangle meet a box, does
//! a segment meet a box, where does a ray cross a triangle.
//!
//! Each is used where a wrong "no" would make the PVS drop a visible object, so each is
//! written to err towards "yes" on a tie (a touching triangle overlaps, a grazing
//! segment meets), and callers shrink occluders a little before asking whether a segment
//! meets them.

use glam::Vec3;

use crate::geom::Aabb;
use crate::scene::Mesh;

/// `mesh`'s triangles as corner positions, in index order.
pub(crate) fn triangles(mesh: &Mesh) -> Vec<[Vec3; 3]> {
    mesh.indices
        .chunks_exact(3)
        .map(|t| [0, 1, 2].map(|k| Vec3::from(mesh.positions[t[k] as usize])))
        .collect()
}

/// Whether the triangle `t` meets the closed box `b`: the separating-axis test of
/// Akenine-Möller (the box's three axes, the triangle's normal, and the nine cross
/// products of their edges). Touching counts as meeting.
pub fn triangle_meets_box(t: &[Vec3; 3], b: &Aabb) -> bool {
    let c = b.center();
    let h = b.extent() * 0.5;
    let v = [t[0] - c, t[1] - c, t[2] - c];
    // The box's own axes: the triangle's bounds against the box's.
    let lo = v[0].min(v[1]).min(v[2]);
    let hi = v[0].max(v[1]).max(v[2]);
    if lo.cmpgt(h).any() || hi.cmplt(-h).any() {
        return false;
    }
    let e = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    let separated = |axis: Vec3| {
        if axis.length_squared() < 1e-20 {
            return false;
        }
        let p = [axis.dot(v[0]), axis.dot(v[1]), axis.dot(v[2])];
        let r = h.x * axis.x.abs() + h.y * axis.y.abs() + h.z * axis.z.abs();
        let (min, max) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        min > r || max < -r
    };
    if separated(e[0].cross(e[1])) {
        return false;
    }
    for edge in e {
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            if separated(axis.cross(edge)) {
                return false;
            }
        }
    }
    true
}

/// Whether the closed segment from `p` to `q` meets the closed box `b` (the slab test).
#[cfg(test)]
pub fn segment_meets_box(p: Vec3, q: Vec3, b: &Aabb) -> bool {
    let d = q - p;
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for axis in 0..3 {
        let (o, dir, lo, hi) = (p[axis], d[axis], b.min[axis], b.max[axis]);
        if dir == 0.0 {
            if o < lo || o > hi {
                return false;
            }
            continue;
        }
        let (a, c) = ((lo - o) / dir, (hi - o) / dir);
        let (near, far) = if a <= c { (a, c) } else { (c, a) };
        t0 = t0.max(near);
        t1 = t1.min(far);
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// The distance along `dir` (in units of its length) at which the ray from `origin`
/// crosses the triangle `t`, when it does at a distance greater than zero
/// (Möller–Trumbore, both faces). The occluder search's solid keeps to its answers
/// with each face's share of it computed once; the tests check it against this.
#[cfg(test)]
pub fn ray_triangle_distance(origin: Vec3, dir: Vec3, t: &[Vec3; 3]) -> Option<f32> {
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = origin - t[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let d = e2.dot(q) * inv;
    (d > 0.0).then_some(d)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Aabb {
        Aabb::new([0.0; 3], [1.0; 3]).unwrap()
    }

    #[test]
    fn triangles_inside_touching_and_apart() {
        let b = unit();
        let tri = |a: [f32; 3], c: [f32; 3], d: [f32; 3]| [a.into(), c.into(), d.into()];
        assert!(triangle_meets_box(
            &tri([0.2, 0.2, 0.2], [0.4, 0.2, 0.2], [0.2, 0.4, 0.2]),
            &b
        ));
        // A big triangle whose corners are all outside but which cuts through the box.
        assert!(triangle_meets_box(
            &tri([-5.0, 0.5, -5.0], [5.0, 0.5, -5.0], [0.0, 0.5, 10.0]),
            &b
        ));
        // Touching a face.
        assert!(triangle_meets_box(
            &tri([1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 0.0, 1.0]),
            &b
        ));
        // Apart, though its bounds overlap the box's: only an edge axis separates.
        assert!(!triangle_meets_box(
            &tri([2.2, 0.0, 0.5], [0.0, 2.2, 0.5], [2.2, 2.2, 0.5]),
            &b
        ));
        assert!(!triangle_meets_box(
            &tri([2.0, 0.0, 0.0], [3.0, 0.0, 0.0], [2.0, 1.0, 0.0]),
            &b
        ));
    }

    #[test]
    fn segments_through_past_and_grazing() {
        let b = unit();
        let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        assert!(segment_meets_box(v(-1.0, 0.5, 0.5), v(2.0, 0.5, 0.5), &b));
        assert!(!segment_meets_box(v(-1.0, 0.5, 0.5), v(-0.1, 0.5, 0.5), &b));
        assert!(!segment_meets_box(v(-1.0, 2.0, 0.5), v(2.0, 2.0, 0.5), &b));
        assert!(segment_meets_box(v(-1.0, 1.0, 0.5), v(2.0, 1.0, 0.5), &b));
        assert!(segment_meets_box(v(0.5, 0.5, 0.5), v(0.5, 0.5, 0.5), &b));
        // Diagonal that misses the corner.
        assert!(!segment_meets_box(v(1.5, 0.0, 0.5), v(2.5, 1.0, 0.5), &b));
    }

    #[test]
    fn ray_crossings() {
        let t = [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        ];
        let d = ray_triangle_distance(Vec3::new(0.2, 0.2, 0.0), Vec3::Z * 2.0, &t);
        assert_eq!(d, Some(0.5));
        assert_eq!(
            ray_triangle_distance(Vec3::new(0.2, 0.2, 0.0), -Vec3::Z, &t),
            None
        );
        assert_eq!(
            ray_triangle_distance(Vec3::new(0.8, 0.8, 0.0), Vec3::Z, &t),
            None
        );
    }
}
