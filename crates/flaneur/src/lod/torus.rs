//! A procedural model for the LOD core's tests, examples and experiments: a bumpy torus
//! of any size, a stand-in for the scanned models of Zheng 2007 (Table 3.1) and
//! El-Sana & Varshney, which are not shipped.

use std::f64::consts::TAU;

use crate::scene::Mesh;

/// A closed, smooth, bumpy torus of about `triangles` triangles (at least 36): a
/// procedural stand-in for the thesis's scanned models of 70k and 1.1M triangles, with
/// curvature everywhere, so that no region simplifies for free.
///
/// ```
/// let torus = flaneur::lod::bumpy_torus(70_000);
/// assert!(torus.validate().is_ok());
/// assert!((torus.triangle_count() as i64 - 70_000).abs() < 1_500);
/// ```
pub fn bumpy_torus(triangles: usize) -> Mesh {
    // 2·rings·sides triangles with twice as many rings as sides.
    let sides = ((triangles as f64 / 4.0).sqrt().round() as u32).max(3);
    let rings = 2 * sides;
    let (major, minor) = (1.0f64, 0.4f64);
    let mut mesh = Mesh::default();
    for i in 0..rings {
        let u = TAU * i as f64 / rings as f64;
        for j in 0..sides {
            let v = TAU * j as f64 / sides as f64;
            let r = minor
                * (1.0
                    + 0.12 * (7.0 * u).sin() * (5.0 * v).sin()
                    + 0.04 * (23.0 * u + 11.0 * v).sin());
            let ring = major + r * v.cos();
            mesh.positions.push([
                (ring * u.cos()) as f32,
                (r * v.sin()) as f32,
                (ring * u.sin()) as f32,
            ]);
        }
    }
    let at = |i: u32, j: u32| (i % rings) * sides + j % sides;
    for i in 0..rings {
        for j in 0..sides {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            mesh.indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    mesh.compute_smooth_normals();
    if mesh.signed_volume() < 0.0 {
        mesh.flip();
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn torus_is_closed_and_outward() {
        let t = bumpy_torus(4_000);
        t.validate().unwrap();
        assert_eq!(t.triangle_count(), 2 * 64 * 32);
        assert!(t.signed_volume() > 0.0);
        assert_eq!(crate::lod::fixtures::boundary_length(&t), 0.0);
        assert!(bumpy_torus(0).validate().is_ok());
    }
}
