//! What the truly selective tests share: meshes compared whatever their triangles'
//! order and turn, and random views of a mesh.

use glam::Vec3;
use rand::Rng;

use super::NodeName;
use crate::lod::refine::View;

/// Triangles turned to start at their smallest corner, sorted.
pub(crate) fn canonical(mut triangles: Vec<[NodeName; 3]>) -> Vec<[NodeName; 3]> {
    for t in &mut triangles {
        let k = (0..3).min_by_key(|&k| t[k].clone()).unwrap();
        t.rotate_left(k);
    }
    triangles.sort_unstable();
    triangles
}

/// A random view of `mesh` from about one to three of its sizes away, looking near
/// its middle.
pub(crate) fn random_view(rng: &mut impl Rng, mesh: &crate::scene::Mesh) -> View {
    let (lo, hi) = mesh.positions.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), &p| (lo.min(Vec3::from(p)), hi.max(Vec3::from(p))),
    );
    let (centre, size) = ((lo + hi) / 2.0, (hi - lo).max_element());
    let mut off = || rng.gen_range(-1.5..1.5) * size;
    let eye = centre + Vec3::new(off(), off(), off());
    let aim = centre + Vec3::new(off(), off(), off()) * 0.2;
    View::new(eye, aim - eye, 1.0).unwrap()
}
