// Procedural sculptures: the city's high-detail landmarks (50,000–200,000 triangles),
// whose triangle count is set by tessellation rather than by modelling, so a city can
// hold objects two orders of magnitude denser than its buildings — the objects LOD and
// visibility work exists for. Three smooth closed shapes: a torus-knot tube, a
// superformula solid ("supershape") and a twisted, tapering star column, each on a plinth.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use glam::{DVec3, Vec3};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::archetypes::place;
use crate::builder::MeshBuilder;
use crate::layout::Lot;
use flaneur_scene::Mesh;

/// Height of the plinth every sculpture stands on, in metres.
const PLINTH: f32 = 1.0;

/// A sculpture for `lot`: one of the three shapes, tessellated to 60,000–180,000
/// triangles, scaled to 8–30 m tall within the lot, on a plinth.
pub(crate) fn sculpture(rng: &mut ChaCha8Rng, lot: &Lot) -> Mesh {
    let target = rng.gen_range(60_000..=180_000_u32);
    let mut mesh = match rng.gen_range(0..3) {
        0 => torus_knot(rng, target),
        1 => supershape(rng, target),
        _ => twisted_column(rng, target),
    };
    if mesh.signed_volume() < 0.0 {
        mesh.flip();
    }
    // Fit: centred over the origin, standing on the plinth, inside the lot.
    let (min, max) = mesh.bounds();
    let c = [(min[0] + max[0]) / 2.0, (min[2] + max[2]) / 2.0];
    let half_width = (max[0] - min[0]).max(max[2] - min[2]) / 2.0;
    let tall = rng.gen_range(8.0..=30.0_f32);
    let s = (tall / (max[1] - min[1])).min((lot.half - 0.2) / half_width);
    mesh.scale_translate(s, [-c[0] * s, PLINTH - min[1] * s, -c[1] * s]);
    let mut plinth = MeshBuilder::new();
    let p = lot.half * 0.7;
    plinth.cuboid(Vec3::new(-p, 0.0, -p), Vec3::new(p, PLINTH, p));
    mesh.append(&plinth.finish());
    place(mesh, lot)
}

/// A closed tube of radius `radius` along the closed curve `curve(t)`, `t` in [0, 1):
/// `segments` rings of `sides` vertices, 2 × segments × sides triangles.
fn tube(curve: impl Fn(f64) -> DVec3, radius: f64, segments: u32, sides: u32) -> Mesh {
    let h = 1e-4;
    let mut positions = Vec::with_capacity((segments * sides) as usize);
    let mut normals = Vec::with_capacity(positions.capacity());
    for i in 0..segments {
        let t = i as f64 / segments as f64;
        let (p, a, b) = (curve(t), curve(t - h), curve(t + h));
        let tangent = (b - a).normalize();
        // Frenet frame: the curvature vector never vanishes on the curves used here.
        let normal = (a + b - 2.0 * p).reject_from(tangent).normalize();
        let binormal = tangent.cross(normal);
        for j in 0..sides {
            let th = TAU * j as f64 / sides as f64;
            let dir = normal * th.cos() + binormal * th.sin();
            positions.push((p + dir * radius).as_vec3().to_array());
            normals.push(dir.as_vec3().to_array());
        }
    }
    let mut indices = Vec::with_capacity((6 * segments * sides) as usize);
    for i in 0..segments {
        for j in 0..sides {
            let v = |i: u32, j: u32| (i % segments) * sides + j % sides;
            let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
            indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    let mut mesh = Mesh {
        positions,
        normals,
        indices,
    };
    // The normals are exact and outward; make the winding agree with them.
    if mesh.signed_volume() < 0.0 {
        for t in mesh.indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
    }
    mesh
}

/// A (p, q) torus knot, standing upright, as a tube: about `target` triangles.
fn torus_knot(rng: &mut ChaCha8Rng, target: u32) -> Mesh {
    const KNOTS: [(f64, f64); 5] = [(2.0, 3.0), (3.0, 2.0), (2.0, 5.0), (3.0, 4.0), (3.0, 5.0)];
    let (p, q) = KNOTS[rng.gen_range(0..KNOTS.len())];
    let sides = rng.gen_range(24..=48_u32);
    let segments = target / (2 * sides);
    let radius = rng.gen_range(0.3..=0.45);
    let curve = move |t: f64| {
        let phi = TAU * t;
        let r = 2.0 + (q * phi).cos();
        DVec3::new(r * (p * phi).cos(), r * (p * phi).sin(), -(q * phi).sin())
    };
    tube(curve, radius, segments, sides)
}

/// The superformula r(θ) of Gielis (2003).
fn superformula(theta: f64, m: f64, n1: f64, n2: f64, n3: f64) -> f64 {
    let a = (m * theta / 4.0).cos().abs().powf(n2);
    let b = (m * theta / 4.0).sin().abs().powf(n3);
    (a + b).powf(-1.0 / n1)
}

/// A supershape: the spherical product of two superformulas, y up: about `target`
/// triangles on a latitude–longitude grid with a vertex at each pole.
fn supershape(rng: &mut ChaCha8Rng, target: u32) -> Mesh {
    let m1 = rng.gen_range(3..=8) as f64;
    let (a1, b1, c1) = (
        rng.gen_range(1.0..=4.0),
        rng.gen_range(0.8..=3.0),
        rng.gen_range(0.8..=3.0),
    );
    let m2 = [0.0, 2.0, 4.0][rng.gen_range(0..3)];
    let n2 = rng.gen_range(1.0..=3.0);
    let r1 = |t: f64| superformula(t, m1, a1, b1, c1);
    let r2 = |t: f64| superformula(t, m2, n2, n2, n2);
    // 2 × lon × (lat − 2) + 2 × lon triangles with lon = 2 × lat: about 4 lat².
    let lat = ((target as f64 / 4.0).sqrt() as u32).max(4);
    let lon = 2 * lat;
    let point = |theta: f64, phi: f64| {
        let (a, b) = (r1(theta), r2(phi));
        // x–z from longitude, y (up) from latitude.
        [
            (a * theta.cos() * b * phi.cos()) as f32,
            (b * phi.sin()) as f32,
            (a * theta.sin() * b * phi.cos()) as f32,
        ]
    };
    let mut positions = vec![point(0.0, -FRAC_PI_2)];
    for i in 1..lat {
        let phi = -FRAC_PI_2 + PI * i as f64 / lat as f64;
        for j in 0..lon {
            positions.push(point(-PI + TAU * j as f64 / lon as f64, phi));
        }
    }
    positions.push(point(0.0, FRAC_PI_2));
    let top = positions.len() as u32 - 1;
    let ring = |i: u32, j: u32| 1 + (i - 1) * lon + j % lon;
    let mut indices = Vec::new();
    for j in 0..lon {
        indices.extend_from_slice(&[0, ring(1, j), ring(1, j + 1)]);
        indices.extend_from_slice(&[top, ring(lat - 1, j + 1), ring(lat - 1, j)]);
    }
    for i in 1..lat - 1 {
        for j in 0..lon {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i + 1, j),
                ring(i + 1, j + 1),
                ring(i, j + 1),
            );
            indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    let mut mesh = Mesh {
        positions,
        normals: Vec::new(),
        indices,
    };
    if mesh.signed_volume() < 0.0 {
        mesh.flip();
    }
    mesh.compute_smooth_normals();
    mesh
}

/// A star-section column, twisted and tapering as it rises, with flat caps: about
/// `target` triangles.
fn twisted_column(rng: &mut ChaCha8Rng, target: u32) -> Mesh {
    let points = rng.gen_range(4..=8) as f64;
    let depth = rng.gen_range(0.15..=0.35);
    let twist = rng.gen_range(FRAC_PI_2..=2.0 * TAU);
    let taper = rng.gen_range(0.3..=0.7);
    let height = rng.gen_range(4.0..=8.0);
    let around = rng.gen_range(96..=256_u32);
    let rings = (target / (2 * around)).max(2);
    let at = |i: u32, j: u32| {
        let t = i as f64 / (rings - 1) as f64;
        let a = TAU * j as f64 / around as f64;
        let r = (1.0 + depth * (points * a).cos()) * (1.0 - taper * t);
        let a = a + twist * t;
        [
            (r * a.cos()) as f32,
            (height * t) as f32,
            (r * a.sin()) as f32,
        ]
    };
    let mut positions = Vec::new();
    for i in 0..rings {
        for j in 0..around {
            positions.push(at(i, j));
        }
    }
    let v = |i: u32, j: u32| i * around + j % around;
    let mut indices = Vec::new();
    for i in 0..rings - 1 {
        for j in 0..around {
            let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
            indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    let mut side = Mesh {
        positions,
        normals: Vec::new(),
        indices,
    };
    side.compute_smooth_normals();
    // Caps with their own vertices, so they shade flat.
    for (i, up) in [(0, -1.0_f32), (rings - 1, 1.0)] {
        let mut cap = Mesh::default();
        let centre = [0.0, at(i, 0)[1], 0.0];
        cap.positions.push(centre);
        for j in 0..around {
            cap.positions.push(at(i, j));
        }
        cap.normals = vec![[0.0, up, 0.0]; cap.positions.len()];
        for j in 0..around {
            let (a, b) = (1 + j, 1 + (j + 1) % around);
            // Counter-clockwise seen from the side the cap faces.
            if up > 0.0 {
                cap.indices.extend_from_slice(&[0, b, a]);
            } else {
                cap.indices.extend_from_slice(&[0, a, b]);
            }
        }
        side.append(&cap);
    }
    side
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn shapes_are_closed_valid_and_near_their_target() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for make in [torus_knot, supershape, twisted_column] {
            let m = make(&mut rng, 60_000);
            m.validate().unwrap();
            let t = m.triangle_count();
            assert!((55_000..=62_000).contains(&t), "{t}");
            let mut flipped = m.clone();
            if flipped.signed_volume() < 0.0 {
                flipped.flip();
            }
            assert!(flipped.signed_volume() > 0.0);
        }
    }
}
