//! An object's occluders: boxes inside its solid, for the conservative from-region test
//! (Shou 2002 §5.5.1), found in a frame turned so that the building's walls run along
//! the boxes' sides.
//!
//! A box whose sides run along x and z fits a building on a street grid; a real
//! city's buildings stand at every angle, and such a box covers little of a footprint
//! turned by 45°. The frame is the one the walls agree on: each near-vertical face
//! votes for its direction (taken modulo a quarter turn, so the four walls of a
//! rectangle agree) with its area; the heaviest direction, to a degree, refined by the
//! votes around it, wins. A generated city's walls all run along the axes and keep the
//! axes' frame exactly.
//!
//! Speed: every object's occluders are found before a visibility build's first cell.
//! The example `occluder_setup` times that alone (`cargo run --release -p flaneur
//! --example occluder_setup -- CITY.scene`). On two busy cores, the same run timing the
//! search before and after its enclosure rays were sorted by column and reach (see
//! [`solid`](self::solid)) with the same boxes: the 3,000-object city (`citygen
//! --objects 3000 --seed 1`, 12,663 boxes) 7.8 s against 12.9 s, the 20,000-object
//! demo city (83,371 boxes) 39 s against 91 s. Then a face was asked whether it is
//! on the outside only when a box being tested meets it (see [`boxes`](self::boxes)),
//! and the rays' columns were counted once per axis: with the same boxes again, best
//! of 3 runs in one run, CPU time (the wall clock was held back by a build beside it),
//! the 3,000-object city 1.9 s against 3.3 s, the demo city 12.7 s against 30.1 s.

mod boxes;
mod solid;

use glam::{Vec2, Vec3};

use super::intersect::triangles;
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::scene::Mesh;

/// One object's occluder boxes, in a frame turned about the vertical.
#[derive(Clone, Debug, PartialEq)]
pub struct Occluders {
    /// Where the frame's origin is in plan (x, z): near the object, so that its
    /// coordinates in the frame are small and turning them loses nothing that matters
    /// (a city tens of kilometres across has millimetre steps in f32).
    pub origin: Vec2,
    /// The unit plan direction (x, z) of the frame's first axis. Its third axis is
    /// `axis.perp()`, and a point (u, y, v) of the frame is at plan position
    /// `origin` + u·`axis` + v·`axis.perp()`, height y.
    pub axis: Vec2,
    /// Boxes inside the object's solid, in the frame.
    pub boxes: Vec<Aabb>,
}

impl Occluders {
    /// Boxes in the world's own frame.
    pub fn aligned(boxes: Vec<Aabb>) -> Occluders {
        Occluders {
            origin: Vec2::ZERO,
            axis: Vec2::X,
            boxes,
        }
    }

    /// `p` in the frame.
    pub fn to_frame(&self, p: Vec3) -> Vec3 {
        let plan = Vec2::new(p.x, p.z) - self.origin;
        Vec3::new(plan.dot(self.axis), p.y, plan.dot(self.axis.perp()))
    }

    /// The plan position of the frame's plan point `(u, v)`.
    pub fn plan_of(&self, local: Vec2) -> Vec2 {
        self.origin + local.x * self.axis + local.y * self.axis.perp()
    }

    /// Checks that the origin is finite, the axis a unit direction, and every box
    /// valid.
    pub fn validate(&self) -> Result<()> {
        if !self.origin.is_finite() {
            return Err(Error::Invalid(format!(
                "the occluders' origin {} is not finite",
                self.origin
            )));
        }
        if !(self.axis.is_finite() && (self.axis.length() - 1.0).abs() < 1e-3) {
            return Err(Error::Invalid(format!(
                "the occluders' axis {} is not a unit direction",
                self.axis
            )));
        }
        self.boxes.iter().try_for_each(Aabb::validate)
    }
}

/// The occluders of `mesh` (see the module's notes); no boxes when there is no
/// worthwhile one (the mesh is small, flat, open, broken, or does not stand on its
/// bounds' ground).
pub fn occluders(mesh: &Mesh) -> Occluders {
    if mesh.validate().is_err() || mesh.triangle_count() == 0 {
        return Occluders::aligned(Vec::new());
    }
    let world = triangles(mesh);
    let mut found = Occluders::aligned(Vec::new());
    found.axis = wall_axis(&world);
    if found.axis != Vec2::X {
        // Turned, about the middle of the object's plan bounds. (Along the axes the
        // world's own frame is kept: its coordinates are taken unchanged.)
        let (lo, hi) = mesh.bounds();
        found.origin = 0.5 * (Vec2::new(lo[0], lo[2]) + Vec2::new(hi[0], hi[2]));
    }
    let local = world.iter().map(|t| t.map(|v| found.to_frame(v))).collect();
    found.boxes = boxes::occluder_boxes(local);
    found
}

/// Degrees of the quarter turn that the walls' directions are sorted into.
const BINS: usize = 90;
/// A face counts as a wall when its normal leans less than this from level (its
/// vertical part, as a share of its length).
const WALL_LEAN: f32 = 0.1;

/// The direction, within a quarter turn, that the walls of `triangles` agree on.
fn wall_axis(triangles: &[[Vec3; 3]]) -> Vec2 {
    // Per wall: its direction in [0, 90°) and its weight (twice its area).
    let walls: Vec<(f32, f32)> = triangles
        .iter()
        .filter_map(|t| {
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            let area = n.length();
            if !(area.is_finite() && area > 0.0) || n.y.abs() > WALL_LEAN * area {
                return None;
            }
            // Turned a quarter at a time into the first quadrant: exact, so walls along
            // the axes give exactly 0.
            let (mut x, mut z) = (n.x, n.z);
            while !(x > 0.0 && z >= 0.0) {
                (x, z) = (z, -x);
            }
            Some((z.atan2(x), area))
        })
        .collect();
    if walls.is_empty() {
        return Vec2::X;
    }
    let quarter = std::f32::consts::FRAC_PI_2;
    let bin = |a: f32| ((a / quarter * BINS as f32) as usize).min(BINS - 1);
    let mut votes = [0.0f32; BINS];
    for &(a, w) in &walls {
        votes[bin(a)] += w;
    }
    // The heaviest degree with its neighbours (around the quarter's wrap).
    let around = |b: usize| {
        (0..3)
            .map(|d| votes[(b + BINS + d - 1) % BINS])
            .sum::<f32>()
    };
    let best = (0..BINS)
        .max_by(|&a, &b| around(a).total_cmp(&around(b)).then(b.cmp(&a)))
        .unwrap_or(0);
    // Refined by the votes within two degrees of it: their mean direction, taken on
    // four times the angle, where a quarter turn is a whole one.
    let centre = (best as f32 + 0.5) / BINS as f32 * quarter;
    let (mut s, mut c) = (0.0f32, 0.0f32);
    for &(a, w) in &walls {
        let off = (4.0 * (a - centre)).sin_cos();
        // Within two degrees, around the wrap too: cos(4·2°) and more.
        if off.1 >= (4.0 * 2.0f32.to_radians()).cos() {
            let (sa, ca) = (4.0 * a).sin_cos();
            s += w * sa;
            c += w * ca;
        }
    }
    let angle = s.atan2(c) / 4.0;
    Vec2::from_angle(angle)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::visibility::intersect::ray_triangle_distance;

    /// `mesh`'s triangles and bounds in the frame of `found`.
    fn in_frame(mesh: &Mesh, found: &Occluders) -> (Vec<[Vec3; 3]>, Aabb) {
        let local: Vec<[Vec3; 3]> = triangles(mesh)
            .iter()
            .map(|t| t.map(|v| found.to_frame(v)))
            .collect();
        let bounds = local
            .iter()
            .flatten()
            .fold(Aabb::EMPTY, |b, v| b.union(&Aabb { min: *v, max: *v }));
        (local, bounds)
    }

    /// Every box of `found` lies inside `mesh`'s bounds, and every point of it is
    /// enclosed, as seen along 26 directions with no columns: a 5 × 5 × 5 grid over it,
    /// corners included.
    fn assert_enclosed(mesh: &Mesh, found: &Occluders, name: &str) {
        let (triangles, bounds) = in_frame(mesh, found);
        let tilt = Vec3::new(0.0031, 0.0017, 0.0027);
        let dirs: Vec<Vec3> = (0..27)
            .filter(|&i| i != 13)
            .map(|i| Vec3::new((i % 3) as f32, (i / 3 % 3) as f32, (i / 9) as f32) - 1.0)
            .map(|d| d + tilt)
            .collect();
        for b in &found.boxes {
            let grown = Aabb {
                min: bounds.min - Vec3::splat(1e-3),
                max: bounds.max + Vec3::splat(1e-3),
            };
            assert!(grown.contains(b), "{name}: {b} outside {bounds}");
            for i in 0..125 {
                let f = Vec3::new((i % 5) as f32, (i / 5 % 5) as f32, (i / 25) as f32) / 4.0;
                let p = b.min + f * b.extent();
                for d in &dirs {
                    assert!(
                        triangles
                            .iter()
                            .any(|t| ray_triangle_distance(p, *d, t).is_some()),
                        "{name}: {p} of {b} sees out along {d}"
                    );
                }
            }
        }
    }

    #[test]
    fn buildings_get_an_occluder_inside_them() {
        let objects = crate::visibility::tests::city(60);
        let (mut found, mut total) = (0, 0.0);
        for o in &objects {
            let occ = occluders(&o.mesh);
            // Generated walls run along the axes: the frame is the world's, exactly.
            assert_eq!(occ.axis, Vec2::X, "object {}", o.id);
            let boxes = occ.boxes.clone();
            if boxes.is_empty() {
                continue;
            }
            found += 1;
            let (lo, hi) = o.mesh.bounds();
            let bounds = Aabb::new(lo, hi).unwrap();
            // The stacked boxes, then the others standing on the ground.
            let on_ground = |b: &Aabb| b.min.y <= boxes[0].min.y + 1e-4;
            let stacked = 1 + boxes[1..].iter().take_while(|b| !on_ground(b)).count();
            assert!(boxes[stacked..].iter().all(on_ground));
            for w in boxes[..stacked].windows(2) {
                assert!(
                    w[1].min.y >= w[0].max.y,
                    "object {}: stacked boxes overlap",
                    o.id
                );
            }
            assert_enclosed(&o.mesh, &occ, &format!("object {}", o.id));
            // A worthwhile part of the building (a house under a tall roof keeps the
            // least, about a tenth of its bounds).
            let share = boxes.iter().map(Aabb::volume).sum::<f32>() / bounds.volume();
            assert!(
                share > 0.05,
                "object {}: {boxes:?} is {share} of {bounds}",
                o.id
            );
            total += share;
        }
        assert!(
            total / found as f32 > 0.3,
            "mean share {}",
            total / found as f32
        );
        assert_eq!(found, objects.len(), "every building has an occluder");
    }

    /// The eight corners of a 10 × 6 × 4 m block with the faces `indices` gives.
    fn block(indices: Vec<u32>) -> Mesh {
        let p = |x: f32, y: f32, z: f32| [x, y, z];
        Mesh {
            positions: vec![
                p(0., 0., 0.),
                p(10., 0., 0.),
                p(10., 0., 4.),
                p(0., 0., 4.),
                p(0., 6., 0.),
                p(10., 6., 0.),
                p(10., 6., 4.),
                p(0., 6., 4.),
            ],
            normals: vec![[0.0, 1.0, 0.0]; 8],
            indices,
        }
    }

    #[test]
    fn a_closed_block_is_filled_by_its_occluder() {
        // A closed 10 × 6 × 4 m block: its occluder fills it, less the safety margin.
        let mesh = block(vec![
            0, 1, 2, 0, 2, 3, 4, 6, 5, 4, 7, 6, 0, 4, 5, 0, 5, 1, 1, 5, 6, 1, 6, 2, 2, 6, 7, 2, 7,
            3, 3, 7, 4, 3, 4, 0,
        ]);
        let boxes = occluders(&mesh).boxes;
        assert_eq!(boxes.len(), 1);
        let b = boxes[0];
        assert!(b.extent().x > 9.9 && b.extent().y > 5.9 && b.extent().z > 3.9);
    }

    #[test]
    fn flat_open_and_broken_meshes_give_none() {
        let mut m = Mesh::default();
        assert!(occluders(&m).boxes.is_empty());
        m.positions = vec![[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 0.0, 10.0]];
        m.normals = vec![[0.0, 1.0, 0.0]; 3];
        m.indices = vec![0, 1, 2];
        assert!(occluders(&m).boxes.is_empty(), "flat");
        m.positions[2] = [0.0, 10.0, f32::NAN];
        assert!(occluders(&m).boxes.is_empty(), "NaN");
        // An open box (no top, no bottom) has no inside.
        let m = block(vec![
            0, 4, 5, 0, 5, 1, 1, 5, 6, 1, 6, 2, 2, 6, 7, 2, 7, 3, 3, 7, 4, 3, 4, 0,
        ]);
        assert!(occluders(&m).boxes.is_empty(), "open");
    }

    /// `ring` (map metres) turned by `angle` about the origin.
    fn turned(ring: &[[f64; 2]], angle: f64) -> Vec<[f64; 2]> {
        let (sin, cos) = angle.sin_cos();
        ring.iter()
            .map(|p| [p[0] * cos - p[1] * sin, p[0] * sin + p[1] * cos])
            .collect()
    }

    /// The share of the footprint (the map points on a 0.5 m grid for which `inside`
    /// holds, before turning) that the ground boxes of `found` cover.
    fn covered(found: &Occluders, angle: f64, inside: impl Fn(f64, f64) -> bool) -> f64 {
        let (mut all, mut under) = (0, 0);
        let ground = found
            .boxes
            .iter()
            .map(|b| b.min.y)
            .fold(f32::INFINITY, f32::min);
        for i in 0..200 {
            for j in 0..200 {
                let (e, n) = (i as f64 * 0.5 + 0.25, j as f64 * 0.5 + 0.25);
                if !inside(e, n) {
                    continue;
                }
                all += 1;
                let m = turned(&[[e, n]], angle)[0];
                // Map (east, north) is world (x, −z).
                let p = found.to_frame(Vec3::new(m[0] as f32, 1.0, -m[1] as f32));
                if found.boxes.iter().any(|b| {
                    b.min.y <= ground + 0.1
                        && (b.min.x..=b.max.x).contains(&p.x)
                        && (b.min.z..=b.max.z).contains(&p.z)
                }) {
                    under += 1;
                }
            }
        }
        under as f64 / all as f64
    }

    /// A test footprint: its name, its extruded mesh, and which map points are on it.
    type Shape<'a> = (&'a str, Mesh, &'a dyn Fn(f64, f64) -> bool);

    /// An L and a block around a courtyard, as footprints are drawn (extruded
    /// outlines), at several angles: the frame follows the walls, the boxes stay
    /// inside, and together they cover most of the footprint, which boxes about the
    /// bounds' centre alone do not.
    #[test]
    fn turned_and_hollow_footprints_are_mostly_covered() {
        let l = vec![
            [0.0, 0.0],
            [30.0, 0.0],
            [30.0, 10.0],
            [10.0, 10.0],
            [10.0, 25.0],
            [0.0, 25.0],
        ];
        let in_l = |e: f64, n: f64| (e < 30.0 && n < 10.0) || (e < 10.0 && n < 25.0);
        let block = vec![[0.0, 0.0], [40.0, 0.0], [40.0, 30.0], [0.0, 30.0]];
        let yard = vec![[10.0, 10.0], [10.0, 20.0], [30.0, 20.0], [30.0, 10.0]];
        let in_block = |e: f64, n: f64| {
            e < 40.0 && n < 30.0 && !((10.0..30.0).contains(&e) && (10.0..20.0).contains(&n))
        };
        for angle in [0.0, 0.5, 1.2, -0.3] {
            let shapes: [Shape; 2] = [
                (
                    "L",
                    crate::scene::extruded(turned(&l, angle), vec![], 15.0),
                    &in_l,
                ),
                (
                    "courtyard block",
                    crate::scene::extruded(turned(&block, angle), vec![turned(&yard, angle)], 15.0),
                    &in_block,
                ),
            ];
            for (name, mesh, inside) in shapes {
                let name = format!("{name} turned {angle}");
                let found = occluders(&mesh);
                // The frame's axis, modulo a quarter turn, is the turn (map north is −z).
                let got = (-found.axis.y).atan2(found.axis.x) as f64;
                let off = (got - angle).rem_euclid(std::f64::consts::FRAC_PI_2);
                let off = off.min(std::f64::consts::FRAC_PI_2 - off);
                assert!(off < 1e-3, "{name}: frame at {got}");
                assert_enclosed(&mesh, &found, &name);
                let share = covered(&found, angle, inside);
                assert!(share > 0.97, "{name}: {share} covered by {:?}", found.boxes);
            }
        }
    }
}
