//! A footprint extruded into a closed prism: a wall quad on every edge of every ring, a
//! flat roof and a floor triangulated with their holes (earcut). Map points (east,
//! north) become world points (x = east, z = −north, y up); every face gets its own
//! vertices so that its normal is flat, and every triangle is wound counter-clockwise
//! from outside.

use super::report::Skip;
use super::rings::{Polygon, P2};
use crate::scene::Mesh;

/// The prism of `polys` from height `base` to `top`, in metres.
pub(super) fn extrude(polys: &[Polygon], base: f64, top: f64) -> Result<Mesh, Skip> {
    let mut mesh = Mesh::default();
    for poly in polys {
        for ring in std::iter::once(&poly.outer).chain(&poly.holes) {
            walls(&mut mesh, ring, base, top);
        }
        let caps = triangulate(poly)?;
        let corners: Vec<P2> = std::iter::once(&poly.outer)
            .chain(&poly.holes)
            .flatten()
            .copied()
            .collect();
        for (y, up) in [(top, 1.0), (base, -1.0)] {
            let first = mesh.positions.len() as u32;
            for p in &corners {
                mesh.positions.push(world(*p, y));
                mesh.normals.push([0.0, up, 0.0]);
            }
            for t in caps.chunks_exact(3) {
                let tri = [
                    t[0] as u32 + first,
                    t[1] as u32 + first,
                    t[2] as u32 + first,
                ];
                push_facing(&mut mesh, tri, [0.0, up, 0.0]);
            }
        }
    }
    Ok(mesh)
}

/// The world point of map point `p` at height `y`.
fn world(p: P2, y: f64) -> [f32; 3] {
    [p[0] as f32, y as f32, -p[1] as f32]
}

/// One quad per edge. Outer rings run counter-clockwise and holes clockwise (seen from
/// above), so the solid lies left of every edge and its outside to the right.
fn walls(mesh: &mut Mesh, ring: &[P2], base: f64, top: f64) {
    let n = ring.len();
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = dx.hypot(dy);
        if len == 0.0 {
            continue;
        }
        // Right of (dx, dy) on the map is (dy, −dx); north is −z in the world.
        let normal = [(dy / len) as f32, 0.0, (dx / len) as f32];
        let first = mesh.positions.len() as u32;
        for (p, y) in [(a, base), (b, base), (b, top), (a, top)] {
            mesh.positions.push(world(p, y));
            mesh.normals.push(normal);
        }
        push_facing(mesh, [first, first + 1, first + 2], normal);
        push_facing(mesh, [first, first + 2, first + 3], normal);
    }
}

/// Pushes a triangle wound so that its face normal agrees with `normal`.
fn push_facing(mesh: &mut Mesh, [a, b, c]: [u32; 3], normal: [f32; 3]) {
    let p = |i: u32| glam::Vec3::from(mesh.positions[i as usize]);
    let face = (p(b) - p(a)).cross(p(c) - p(a));
    if face.dot(glam::Vec3::from(normal)) >= 0.0 {
        mesh.indices.extend([a, b, c]);
    } else {
        mesh.indices.extend([a, c, b]);
    }
}

/// The triangles of a polygon with holes, as indices into its corners (outer first,
/// then each hole's).
fn triangulate(poly: &Polygon) -> Result<Vec<usize>, Skip> {
    // Earcut works best near the origin: coordinates relative to the first corner.
    let o = poly.outer[0];
    let mut flat = Vec::new();
    let mut holes = Vec::new();
    for (k, ring) in std::iter::once(&poly.outer).chain(&poly.holes).enumerate() {
        if k > 0 {
            holes.push(flat.len() / 2);
        }
        for p in ring {
            flat.extend([p[0] - o[0], p[1] - o[1]]);
        }
    }
    match earcutr::earcut(&flat, &holes, 2) {
        Ok(t) if !t.is_empty() => Ok(t),
        _ => Err(Skip::Untriangulated),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_square_with_a_hole_is_a_closed_outward_prism() {
        let outer = vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        let hole = vec![[4.0, 4.0], [4.0, 6.0], [6.0, 6.0], [6.0, 4.0]];
        let poly = Polygon {
            outer,
            holes: vec![hole],
        };
        let mesh = extrude(&[poly], 2.0, 12.0).unwrap();
        mesh.validate().unwrap();
        // Walls: 8 edges × 2; caps: earcut gives 8 triangles for a square ring around a
        // square hole, top and bottom.
        assert_eq!(mesh.triangle_count(), 16 + 2 * 8);
        // Volume of the solid: (100 − 4) m² × 10 m; positive means facing out.
        assert!(
            (mesh.signed_volume() - 960.0).abs() < 1e-3,
            "{}",
            mesh.signed_volume()
        );
        let (min, max) = mesh.bounds();
        assert_eq!((min, max), ([0.0, 2.0, -10.0], [10.0, 12.0, 0.0]));
    }
}
