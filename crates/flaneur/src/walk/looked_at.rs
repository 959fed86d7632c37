//! The object straight ahead: the nearest of the objects drawn that the ray along the
//! camera's view meets, tested against their boxes first and then their triangles (the
//! level each is held at), so that the window can say which building is in the middle
//! of the picture and what it was called where it came from.

use obvhs::aabb::Aabb as RayBox;
use obvhs::ray::Ray;
use obvhs::triangle::Triangle;

use super::buffer::Loaded;
use crate::geom::Camera;

/// The id of the nearest object of `objects` straight ahead of `camera`, and its
/// distance in metres; `None` when the view meets none of them.
pub(crate) fn looked_at(camera: &Camera, objects: &[&Loaded]) -> Option<(u64, f32)> {
    let ray = Ray::new(
        camera.position.to_array().into(),
        camera.forward().to_array().into(),
        0.0,
        camera.far,
    );
    // Boxes the view meets, nearest first: an object whose box lies beyond the nearest
    // triangle met so far cannot be nearer, so most meshes are never looked into.
    let mut met: Vec<(f32, &Loaded)> = objects
        .iter()
        .filter_map(|o| {
            let b = &o.entry.bounds;
            let reach =
                RayBox::new(b.min.to_array().into(), b.max.to_array().into()).intersect_ray(&ray);
            reach.is_finite().then_some((reach, *o))
        })
        .collect();
    met.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    let mut nearest: Option<(u64, f32)> = None;
    for (reach, o) in met {
        if nearest.is_some_and(|(_, t)| reach >= t) {
            break;
        }
        let p = &o.mesh.positions;
        for t in o.mesh.indices.chunks_exact(3) {
            let corner = |i: u32| p[i as usize].into();
            let tri = Triangle {
                v0: corner(t[0]),
                v1: corner(t[1]),
                v2: corner(t[2]),
            };
            let d = tri.intersect(&ray);
            if d.is_finite() && d >= 0.0 && nearest.is_none_or(|(_, best)| d < best) {
                nearest = Some((o.entry.id, d));
            }
        }
    }
    nearest
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use glam::Vec3;

    use super::*;
    use crate::lod::fixtures::cube;

    /// A held object whose mesh is a 2 m cube centred at `centre`.
    fn held(id: u64, centre: [f32; 3]) -> Loaded {
        let mut o = crate::walk::buffer::tests::loaded(id, 0.0, 100);
        let mesh = cube(centre, 0);
        let (min, max) = mesh.bounds();
        o.entry.bounds = crate::geom::Aabb::new(min, max).unwrap();
        o.mesh = Arc::new(mesh);
        o
    }

    #[test]
    fn the_nearest_object_met_by_the_view_is_found_and_a_box_alone_is_not_enough() {
        // Cubes straight ahead along +x at 10 m and 20 m, and one off to the side.
        let (near, far) = (held(1, [10.0, 0.0, 0.0]), held(2, [20.0, 0.0, 0.0]));
        let side = held(3, [10.0, 0.0, 30.0]);
        let camera = Camera::new(Vec3::new(0.0, 0.2, 0.1), 0.0, 0.0).unwrap();
        let (id, d) = looked_at(&camera, &[&far, &side, &near]).unwrap();
        assert_eq!(id, 1);
        assert!((d - 9.0).abs() < 1e-3, "{d}");
        // A box met with no triangle of its mesh there is not looked at.
        let mut hollow = held(4, [5.0, 0.0, 0.0]);
        hollow.mesh = Arc::new(crate::scene::Mesh::default());
        assert_eq!(looked_at(&camera, &[&hollow, &far]).unwrap().0, 2);
        let behind = Camera::new(camera.position, std::f32::consts::PI, 0.0).unwrap();
        assert_eq!(looked_at(&behind, &[&near, &far]), None, "nothing behind");
    }
}
