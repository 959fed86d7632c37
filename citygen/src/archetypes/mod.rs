// The building archetypes and what they share: choosing one for a lot, roofs, and
// moving a building from lot-local space (centred on the origin, front facing −z) onto
// its lot. Each archetype lives in its own file and builds with `facade`.

mod facade;
mod house;
mod terrace;
mod tower;

use glam::Vec3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::builder::MeshBuilder;
use crate::layout::Lot;
use flaneur_scene::Mesh;
use flaneur_scene::ObjectKind;

/// A building for `lot`: the archetype is drawn first from `rng`, then its parameters.
/// Shares: houses 55 %, terraces 25 %, towers 20 %.
pub(crate) fn building(rng: &mut ChaCha8Rng, lot: &Lot) -> (ObjectKind, Mesh) {
    match rng.gen_range(0..100) {
        0..=54 => (ObjectKind::House, house::house(rng, lot)),
        55..=79 => (ObjectKind::Terrace, terrace::terrace(rng, lot)),
        _ => (ObjectKind::Tower, tower::tower(rng, lot)),
    }
}

/// The shape of a pitched roof.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum RoofStyle {
    /// Two slopes and two vertical gable ends.
    Gable,
    /// Four slopes.
    Hip,
}

/// A closed pitched roof over the rectangle `±half` (x, z) at height `base`, its ridge
/// along the longer side, rising `pitch` metres per metre. Returns the ridge height.
pub(crate) fn roof(
    m: &mut MeshBuilder,
    style: RoofStyle,
    half: [f32; 2],
    base: f32,
    pitch: f32,
) -> f32 {
    let (ax, az, ra, rb) = if half[0] >= half[1] {
        (Vec3::X, Vec3::Z, half[0], half[1])
    } else {
        (Vec3::Z, Vec3::X, half[1], half[0])
    };
    let ridge = base + rb * pitch;
    let p = |a: f32, b: f32, y: f32| ax * a + az * b + Vec3::Y * y;
    let inset = match style {
        RoofStyle::Gable => 0.0,
        RoofStyle::Hip => rb.min(ra * 0.8),
    };
    let (r0, r1) = (p(-ra + inset, 0.0, ridge), p(ra - inset, 0.0, ridge));
    let c = [
        p(-ra, -rb, base),
        p(ra, -rb, base),
        p(ra, rb, base),
        p(-ra, rb, base),
    ];
    m.quad(c, -Vec3::Y);
    m.quad([c[0], c[1], r1, r0], Vec3::Y - az);
    m.quad([c[3], c[2], r1, r0], Vec3::Y + az);
    m.tri([c[0], c[3], r0], -ax);
    m.tri([c[1], c[2], r1], ax);
    ridge
}

/// Moves a lot-local building onto its lot, turning it to face the nearer street.
pub(crate) fn place(mut mesh: Mesh, lot: &Lot) -> Mesh {
    if lot.faces_north {
        mesh.rotate_y_quarter(2);
    }
    mesh.scale_translate(1.0, [lot.center[0], 0.0, lot.center[1]]);
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roofs_are_closed_and_outward() {
        for style in [RoofStyle::Gable, RoofStyle::Hip] {
            for half in [[5.0, 3.0], [3.0, 5.0], [4.0, 4.0]] {
                let mut m = MeshBuilder::new();
                let top = roof(&mut m, style, half, 6.0, 0.8);
                let mesh = m.finish();
                assert!(mesh.validate().is_ok());
                assert_eq!(mesh.triangle_count(), 8);
                assert!(mesh.signed_volume() > 0.0, "{style:?} {half:?}");
                assert!((top - (6.0 + 3.0_f32.min(4.0) * 0.8)).abs() < 1e-5 || half == [4.0, 4.0]);
            }
        }
    }
}
