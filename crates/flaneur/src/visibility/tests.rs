//! DoV against exact solid angles, occlusion, and the invariants of eq. 5.1–5.2 in a
//! generated city.

use std::collections::HashMap;
use std::f64::consts::PI;

use citygen::{CityConfig, Mesh};

use super::*;
use crate::error::Error;
use crate::geom::Aabb;

/// A sphere of radius `r` at `centre`: an icosahedron subdivided `levels` times, its
/// vertices pushed out onto the sphere.
fn icosphere(centre: [f64; 3], r: f64, levels: u32) -> Mesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut points: Vec<[f64; 3]> = vec![
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let unit = |p: [f64; 3]| {
        let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        p.map(|c| c / l)
    };
    points = points.into_iter().map(unit).collect();
    for _ in 0..levels {
        let mut middle: HashMap<(u32, u32), u32> = HashMap::new();
        let mut split = |a: u32, b: u32, points: &mut Vec<[f64; 3]>| {
            *middle.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (p, q) = (points[a as usize], points[b as usize]);
                points.push(unit([0, 1, 2].map(|k| p[k] + q[k])));
                points.len() as u32 - 1
            })
        };
        faces = faces
            .into_iter()
            .flat_map(|[a, b, c]| {
                let ab = split(a, b, &mut points);
                let bc = split(b, c, &mut points);
                let ca = split(c, a, &mut points);
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    Mesh {
        normals: points.iter().map(|p| p.map(|c| c as f32)).collect(),
        positions: points
            .iter()
            .map(|p| [0, 1, 2].map(|k| (centre[k] + r * p[k]) as f32))
            .collect(),
        indices: faces.into_iter().flatten().collect(),
    }
}

/// A closed box `[lo, hi]`, 12 triangles.
fn cuboid(lo: [f32; 3], hi: [f32; 3]) -> Mesh {
    let positions: Vec<[f32; 3]> = (0..8)
        .map(|i| std::array::from_fn(|k| if i >> k & 1 == 0 { lo[k] } else { hi[k] }))
        .collect();
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    Mesh {
        normals: vec![[0.0, 1.0, 0.0]; 8],
        positions,
        indices: quads
            .iter()
            .flat_map(|q| [q[0], q[1], q[2], q[0], q[2], q[3]])
            .collect(),
    }
}

/// The exact solid angle, over 4π, of the rectangle `[x0, x1] × [y0, y1]` in a plane at
/// distance `h` from the viewpoint, coordinates measured from the foot of the
/// perpendicular.
fn rectangle_dov(x: [f64; 2], y: [f64; 2], h: f64) -> f64 {
    let g = |x: f64, y: f64| (x * y / (h * (x * x + y * y + h * h).sqrt())).atan();
    (g(x[1], y[1]) - g(x[0], y[1]) - g(x[1], y[0]) + g(x[0], y[0])) / (4.0 * PI)
}

fn dov_of(seen: &PointDov, object: u32) -> f64 {
    seen.objects
        .iter()
        .find(|(o, _)| *o == object)
        .map_or(0.0, |&(_, d)| d as f64)
}

fn assert_close(got: f64, exact: f64, what: &str) {
    let err = (got / exact - 1.0).abs();
    assert!(
        err < 0.02,
        "{what}: DoV {got}, exact {exact} ({:.2} % off)",
        err * 100.0
    );
}

#[test]
fn a_lone_sphere_subtends_its_cap() {
    let cube = CubicProjection::default();
    let (r, d) = (2.0f64, 10.0f64);
    let exact = 2.0 * PI * (1.0 - (1.0 - (r / d).powi(2)).sqrt()) / (4.0 * PI);
    // Straight ahead of a face, across the seam of two faces, and across a cube corner.
    for dir in [
        [0.0f64, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [1.0, -1.0, 1.0],
        [0.3, 0.8, -0.5],
    ] {
        let l = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
        let eye = [3.0, 1.7, -2.0];
        let centre = [0, 1, 2].map(|k| eye[k] + d * dir[k] / l);
        let sphere = icosphere(centre, r, 5);
        let scene = RayScene::new([(5, &sphere)]).unwrap();
        let seen = point_dov(&scene, &cube, eye.map(|c| c as f32)).unwrap();
        assert_eq!(seen.objects.len(), 1);
        assert_close(dov_of(&seen, 0), exact, &format!("sphere towards {dir:?}"));
        assert!((seen.sky as f64 + dov_of(&seen, 0) - 1.0).abs() < 1e-5);
    }
}

#[test]
fn a_lone_box_face_on_subtends_its_near_face() {
    let cube = CubicProjection::default();
    // The eye's projection falls inside the near face, so that face is all that shows.
    // A near, off-centre box spanning five cube faces, and one within the +z face about
    // 100 pixels across (a box a few pixels across is off by its edge pixels, not 2 %).
    for (lo, hi) in [
        ([-3.0, -2.0, 2.0], [5.0, 4.0, 6.0]),
        ([-3.1, -2.3, 8.0], [4.2, 3.9, 10.0]),
    ] {
        let eye = [0.0f32; 3];
        let scene = RayScene::new([(1, &cuboid(lo, hi))]).unwrap();
        let seen = point_dov(&scene, &cube, eye).unwrap();
        let exact = rectangle_dov(
            [lo[0] as f64, hi[0] as f64],
            [lo[1] as f64, hi[1] as f64],
            lo[2] as f64,
        );
        assert_close(dov_of(&seen, 0), exact, &format!("box {lo:?}–{hi:?}"));
    }
}

#[test]
fn an_object_hidden_behind_a_wall_has_no_dov() {
    let wall = cuboid([-50.0, 0.0, 10.0], [50.0, 30.0, 11.0]);
    let hidden = cuboid([-2.0, 0.0, 20.0], [2.0, 4.0, 24.0]);
    let visible = cuboid([-2.0, 0.0, -20.0], [2.0, 4.0, -16.0]);
    let scene = RayScene::new([(0, &wall), (1, &hidden), (2, &visible)]).unwrap();
    let cube = CubicProjection::new(128).unwrap();
    let seen = point_dov(&scene, &cube, [0.0, 1.7, 0.0]).unwrap();
    let objects: Vec<u32> = seen.objects.iter().map(|&(o, _)| o).collect();
    assert_eq!(objects, [0, 2]);
    let cells = [Aabb::new([-3.0, 1.2, -2.0], [3.0, 2.0, 2.0]).unwrap()];
    let result = cell_dovs(&scene, &cube, &cells).unwrap();
    assert!(result.cells[0].iter().all(|&(o, d)| o != 1 && d > 0.0));
    // Without the wall the same cell sees it.
    let open = RayScene::new([(1, &hidden)]).unwrap();
    assert_eq!(cell_dovs(&open, &cube, &cells).unwrap().cells[0].len(), 1);
}

/// The objects of a small generated city (the module tests share it).
pub(super) fn city(objects: u64) -> Vec<citygen::SceneObject> {
    let config = CityConfig {
        objects,
        landmarks: 0.0,
        ..Default::default()
    };
    (0..objects)
        .map(|id| citygen::object(&config, id).unwrap())
        .collect()
}

/// Street-level points: on a 2 m grid at eye height, at least `clear` metres from every
/// object's footprint, the `count` nearest to the city's centre.
fn street_points(objects: &[citygen::SceneObject], clear: f32, count: usize) -> Vec<[f32; 3]> {
    let boxes: Vec<([f32; 3], [f32; 3])> = objects.iter().map(|o| o.mesh.bounds()).collect();
    let (lo, hi) = boxes.iter().fold(
        ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]),
        |(lo, hi), (a, b)| {
            (
                [lo[0].min(a[0]), lo[1].min(a[2])],
                [hi[0].max(b[0]), hi[1].max(b[2])],
            )
        },
    );
    let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let mut free: Vec<[f32; 3]> = Vec::new();
    let mut x = lo[0];
    while x <= hi[0] {
        let mut z = lo[1];
        while z <= hi[1] {
            if boxes.iter().all(|(a, b)| {
                x < a[0] - clear || x > b[0] + clear || z < a[2] - clear || z > b[2] + clear
            }) {
                free.push([x, 1.7, z]);
            }
            z += 2.0;
        }
        x += 2.0;
    }
    let dist = |p: &[f32; 3]| (p[0] - centre[0]).powi(2) + (p[2] - centre[1]).powi(2);
    free.sort_by(|p, q| dist(p).total_cmp(&dist(q)));
    free.truncate(count);
    assert_eq!(free.len(), count, "the city has street space");
    free
}

#[test]
fn dovs_from_one_viewpoint_in_a_city_sum_to_at_most_one() {
    let objects = city(300);
    let scene = RayScene::new(objects.iter().map(|o| (o.id, &o.mesh))).unwrap();
    let cube = CubicProjection::default();
    for p in street_points(&objects, 2.0, 4) {
        let seen = point_dov(&scene, &cube, p).unwrap();
        let total: f64 = seen.objects.iter().map(|&(_, d)| d as f64).sum();
        assert!(
            seen.objects.len() > 3,
            "{p:?} sees {} objects",
            seen.objects.len()
        );
        assert!(total <= 1.0 + 1e-6, "{p:?}: DoVs sum to {total}");
        assert!(
            (total + seen.sky as f64 - 1.0).abs() < 1e-5,
            "{p:?}: {total} + sky"
        );
        assert!(seen.objects.windows(2).all(|w| w[0].0 < w[1].0));
        assert!(seen.objects.iter().all(|&(_, d)| d > 0.0));
    }
    // Inside a building every direction meets it: its DoV is the whole sphere.
    let (a, b) = objects[0].mesh.bounds();
    let inside = [0, 1, 2].map(|k| (a[k] + b[k]) / 2.0);
    let seen = point_dov(&scene, &CubicProjection::new(32).unwrap(), inside).unwrap();
    let total: f64 = seen.objects.iter().map(|&(_, d)| d as f64).sum();
    assert!(total <= 1.0 + 1e-6 && total > 0.99, "{total}");
}

#[test]
fn a_cells_dov_is_the_maximum_over_its_corners() {
    let objects = city(200);
    let scene = RayScene::new(objects.iter().map(|o| (o.id, &o.mesh))).unwrap();
    let cube = CubicProjection::new(96).unwrap();
    // A 2×2 grid of 4 m cells around a street point, eye height 1.2–2.0 m.
    let p = street_points(&objects, 6.0, 1)[0];
    let cells: Vec<Aabb> = (0..4)
        .map(|c| {
            let (x, z) = (
                p[0] + 4.0 * (c % 2) as f32 - 4.0,
                p[2] + 4.0 * (c / 2) as f32 - 4.0,
            );
            Aabb::new([x, 1.2, z], [x + 4.0, 2.0, z + 4.0]).unwrap()
        })
        .collect();
    let result = cell_dovs(&scene, &cube, &cells).unwrap();
    assert_eq!(result.stats.corners, 18); // 3 × 3 × 2, not 4 × 8
    assert_eq!(result.stats.rays, 18 * cube.rays_per_point());
    assert!(result.stats.rays_per_second() > 0.0);
    for (cell, dovs) in cells.iter().zip(&result.cells) {
        let mut best: HashMap<u32, f32> = HashMap::new();
        for corner in dov::corners(cell) {
            for (o, d) in point_dov(&scene, &cube, corner).unwrap().objects {
                let cell_dov = dovs.iter().find(|e| e.0 == o).map(|e| e.1);
                assert!(
                    cell_dov >= Some(d),
                    "object {o}: cell {cell_dov:?} < corner {d}"
                );
                let b = best.entry(o).or_insert(0.0);
                *b = b.max(d);
            }
        }
        let mut expect: Vec<(u32, f32)> = best.into_iter().collect();
        expect.sort_unstable_by_key(|e| e.0);
        assert_eq!(dovs, &expect);
    }
    // The same cells one at a time give the same DoVs, from 8 corners each.
    let single = cell_dovs(&scene, &cube, &cells[..1]).unwrap();
    assert_eq!(
        (single.stats.corners, &single.cells[0]),
        (8, &result.cells[0])
    );
    // In batches one after another (bottom row, then top row), the second casts only
    // the corners it does not share with the first, and the DoVs are the same.
    let mut memo = CornerMemo::default();
    let bottom = cell_dovs_after(&scene, &cube, &cells[..2], &mut memo).unwrap();
    let top = cell_dovs_after(&scene, &cube, &cells[2..], &mut memo).unwrap();
    assert_eq!((bottom.stats.corners, top.stats.corners), (12, 6));
    assert_eq!([bottom.cells, top.cells].concat(), result.cells);
}

#[test]
fn bad_viewpoints_and_cells_are_errors_that_say_what_is_wrong() {
    let scene = RayScene::new([(0, &cuboid([0.0; 3], [1.0; 3]))]).unwrap();
    let cube = CubicProjection::new(4).unwrap();
    for p in [[f32::NAN, 0.0, 0.0], [0.0, f32::NEG_INFINITY, 0.0]] {
        let err = point_dov(&scene, &cube, p).unwrap_err();
        assert!(matches!(err, Error::BadViewpoint(_)), "{err}");
        let msg = err.to_string();
        assert!(
            msg.starts_with("viewpoint [") && msg.contains("not finite"),
            "{msg}"
        );
        assert!(cube.identity_buffer(&scene, p).is_err());
    }
    let ok = Aabb::new([0.0; 3], [1.0; 3]).unwrap();
    let nan = Aabb {
        min: glam::Vec3::new(0.0, f32::NAN, 0.0),
        ..ok
    };
    let flat = Aabb::new([0.0, 1.7, 0.0], [4.0, 1.7, 4.0]).unwrap();
    let inverted = Aabb {
        min: glam::Vec3::new(5.0, 0.0, 0.0),
        ..ok
    };
    for (bad, words) in [
        (nan, "not finite"),
        (flat, "zero size on y"),
        (inverted, "inverted on x"),
    ] {
        let err = cell_dovs(&scene, &cube, &[ok, bad]).unwrap_err();
        let msg = err.to_string();
        assert!(matches!(err, Error::BadViewcell { cell: 1, .. }), "{msg}");
        assert!(msg.contains("viewcell 1") && msg.contains(words), "{msg}");
    }
    let none = cell_dovs(&scene, &cube, &[]).unwrap();
    assert_eq!((none.cells.len(), none.stats.rays), (0, 0));
}

#[test]
fn the_identity_buffer_matches_single_rays() {
    let scene = RayScene::new([(3, &cuboid([-1.0, -1.0, 2.0], [1.0, 1.0, 3.0]))]).unwrap();
    let cube = CubicProjection::new(16).unwrap();
    let buffer = cube.identity_buffer(&scene, [0.0; 3]).unwrap();
    assert_eq!(buffer.len() as u64, cube.rays_per_point());
    for face in 0..6 {
        for j in 0..16 {
            for i in 0..16 {
                let d = cube.direction(face, i, j).unwrap();
                let expect = scene
                    .first_hit([0.0; 3], d)
                    .unwrap()
                    .map_or(SKY, |h| h.object);
                assert_eq!(buffer[(face * 16 + j as usize) * 16 + i as usize], expect);
            }
        }
    }
    // The +z face's centre shows the box; the −z face shows sky.
    assert_eq!(buffer[(4 * 16 + 8) * 16 + 8], 0);
    assert_eq!(buffer[(5 * 16 + 8) * 16 + 8], SKY);
}

#[test]
fn point_dov_is_the_identity_buffer_weighed() {
    let objects = city(100);
    let scene = RayScene::new(objects.iter().map(|o| (o.id, &o.mesh))).unwrap();
    // N = 37 is not a multiple of the bands a face is cut into.
    for n in [37, 64] {
        let cube = CubicProjection::new(n).unwrap();
        let p = street_points(&objects, 2.0, 1)[0];
        let buffer = cube.identity_buffer(&scene, p).unwrap();
        let mut sums: HashMap<u32, f64> = HashMap::new();
        for (k, &id) in buffer.iter().enumerate() {
            let (i, j) = (
                (k % n as usize) as u32,
                (k / n as usize % n as usize) as u32,
            );
            *sums.entry(id).or_default() += cube.pixel_dov(i, j).unwrap() as f64;
        }
        let seen = point_dov(&scene, &cube, p).unwrap();
        assert_eq!(
            seen.objects.len(),
            sums.len() - sums.contains_key(&SKY) as usize
        );
        for (o, d) in seen.objects {
            assert!(
                (sums[&o] - d as f64).abs() < 1e-6,
                "object {o}: {} vs {d}",
                sums[&o]
            );
        }
        assert!((sums.get(&SKY).copied().unwrap_or(0.0) - seen.sky as f64).abs() < 1e-6);
    }
}
