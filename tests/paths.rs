//! Camera paths (the motion patterns of Shou 2002 §4.4.1 and their CSV files) and the
//! view frustum's ViewCulling (§4.3, Fig. 4.15) against a brute-force reference.

use flaneur::geom::{Aabb, Camera, Frustum};
use flaneur::path::motion::{generate, Motion};
use flaneur::path::{CameraPath, Pose};
use flaneur::Error;
use glam::{DVec3, Vec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const FRAMES: usize = 600;
const FPS: f32 = 30.0;

/// A 2 km city, 120 m high, not at the origin.
fn city() -> Aabb {
    Aabb::new([-500.0, 0.0, 300.0], [1500.0, 120.0, 2300.0]).unwrap()
}

fn path(m: Motion, seed: u64) -> CameraPath {
    generate(&city(), m, FRAMES, FPS, seed).unwrap()
}

fn steps(p: &CameraPath) -> impl Iterator<Item = (&Pose, &Pose)> {
    p.poses.iter().zip(p.poses.iter().skip(1))
}

fn mean_speed(p: &CameraPath) -> f32 {
    let dist: f32 = steps(p)
        .map(|(a, b)| (b.position - a.position).length())
        .sum();
    dist / p.duration() as f32
}

/// Sum of |Δyaw| over the path, radians.
fn total_turn(p: &CameraPath) -> f32 {
    steps(p).map(|(a, b)| (b.yaw - a.yaw).abs()).sum()
}

fn forward(p: &Pose) -> Vec3 {
    p.camera().unwrap().forward()
}

#[test]
fn every_pattern_stays_in_the_city_and_is_finite() {
    let c = city();
    for m in Motion::ALL {
        for seed in 0..4 {
            let p = path(m, seed);
            assert_eq!(p.len(), FRAMES);
            p.validate().unwrap();
            for q in &p.poses {
                assert!(
                    c.contains_point(q.position),
                    "{m} seed {seed}: {} is outside",
                    q.position
                );
                assert!(
                    (q.position.y - 1.7).abs() < 1e-4,
                    "{m}: eye at {}",
                    q.position.y
                );
                assert!(q.pitch.abs() < 6f32.to_radians());
            }
            assert!((p.duration() - (FRAMES - 1) as f64 / FPS as f64).abs() < 1e-9);
        }
    }
}

#[test]
fn paths_are_deterministic_by_seed() {
    for m in Motion::ALL {
        assert_eq!(path(m, 11), path(m, 11), "{m}");
    }
    assert_ne!(path(Motion::Random, 11), path(Motion::Random, 12));
    // Street patterns differ by seed too, over a long enough walk.
    let long = |seed| generate(&city(), Motion::Turning, 3000, FPS, seed).unwrap();
    assert_ne!(long(1), long(2));
}

#[test]
fn speeds_are_as_documented() {
    let expect = [
        (Motion::Normal, 15.0, 15.0),
        (Motion::Fast, 40.0, 40.0),
        (Motion::Slow, 4.0, 4.0),
        (Motion::Turning, 15.0, 15.0),
        (Motion::Backward, 15.0, 15.0),
        (Motion::Random, 2.0, 40.0),
    ];
    for (m, lo, hi) in expect {
        assert_eq!(m.speed_range(), (lo, hi), "{m}");
        for seed in 0..4 {
            let p = path(m, seed);
            let max_step = steps(&p)
                .map(|(a, b)| (b.position - a.position).length())
                .fold(0.0, f32::max);
            assert!(max_step <= hi / FPS + 1e-3, "{m}: a step of {max_step} m");
            let v = mean_speed(&p);
            if lo == hi {
                // Only a corner cuts a step short.
                assert!(
                    v > 0.97 * lo && v <= hi + 1e-2,
                    "{m} seed {seed}: mean speed {v}"
                );
            } else {
                assert!(v > lo && v < hi, "{m} seed {seed}: mean speed {v}");
            }
            // Velocity by finite difference agrees with the steps.
            let vel = p.velocity_at(300).length();
            assert!(vel <= hi + 0.1, "{m}: velocity {vel}");
        }
    }
}

#[test]
fn turning_turns_more_than_normal() {
    for seed in 0..6 {
        let (t, n) = (
            total_turn(&path(Motion::Turning, seed)),
            total_turn(&path(Motion::Normal, seed)),
        );
        assert!(
            t > 2.0 * n && t > std::f32::consts::TAU,
            "seed {seed}: turning {t} rad, normal {n} rad"
        );
    }
}

#[test]
fn backward_moves_against_its_view() {
    let share_backward = |p: &CameraPath| {
        let moving: Vec<f32> = steps(p)
            .filter_map(|(a, b)| {
                let d = b.position - a.position;
                (d.length() > 1e-4).then(|| d.normalize().dot(forward(b)))
            })
            .collect();
        moving.iter().filter(|&&c| c < 0.0).count() as f32 / moving.len() as f32
    };
    for seed in 0..6 {
        let back = share_backward(&generate(&city(), Motion::Backward, 1800, FPS, seed).unwrap());
        assert!(back > 0.85, "seed {seed}: backward only {back} of the time");
        assert!(share_backward(&path(Motion::Normal, seed)) < 0.05);
    }
    // It does reverse: over a minute the direction of travel flips at least twice.
    let p = generate(&city(), Motion::Backward, 1800, FPS, 3).unwrap();
    let dirs: Vec<Vec3> = steps(&p)
        .map(|(a, b)| (b.position - a.position).normalize_or_zero())
        .collect();
    let flips = dirs.windows(2).filter(|w| w[0].dot(w[1]) < -0.9).count();
    assert!(flips >= 2, "{flips} reversals");
}

#[test]
fn csv_round_trips_exactly() {
    let dir = tempfile::tempdir().unwrap();
    for m in Motion::ALL {
        let p = path(m, 5);
        let file = dir.path().join(format!("{m}.csv"));
        p.save_csv(&file).unwrap();
        let q = CameraPath::load_csv(&file).unwrap();
        assert_eq!(p, q, "{m}");
        let text = std::fs::read_to_string(&file).unwrap();
        assert!(text.starts_with("time,x,y,z,yaw,pitch\n"));
        assert_eq!(text.lines().count(), FRAMES + 1);
    }
    // Awkward floats survive too.
    let odd = CameraPath::new(vec![
        Pose {
            time: 1e-9,
            position: Vec3::new(1e-30, -0.0, 3.4e38),
            yaw: -123.456_79,
            pitch: 1.569_9,
        },
        Pose {
            time: 1.0 / 3.0,
            position: Vec3::new(f32::MIN_POSITIVE, 1.0 / 3.0, -7.0),
            yaw: 0.1,
            pitch: -1e-7,
        },
    ])
    .unwrap();
    let file = dir.path().join("odd.csv");
    odd.save_csv(&file).unwrap();
    assert_eq!(CameraPath::load_csv(&file).unwrap(), odd);
}

#[test]
fn malformed_files_name_the_file_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("empty", "", 1),
        ("header-only", "time,x,y,z,yaw,pitch\n", 1),
        ("no-header", "0,1,2,3,0,0\n", 1),
        ("short", "time,x,y,z,yaw,pitch\n0,1,2,3,0,0\n1,1,2,3,0\n", 3),
        (
            "word",
            "time,x,y,z,yaw,pitch\n0,1,2,3,0,0\n1,1,two,3,0,0\n",
            3,
        ),
        (
            "nan",
            "time,x,y,z,yaw,pitch\n0,1,2,3,0,0\n0.5,1,2,3,0,0\n1,1,2,3,NaN,0\n",
            4,
        ),
        (
            "same-time",
            "time,x,y,z,yaw,pitch\n0,1,2,3,0,0\n0,1,2,3,0,0\n",
            3,
        ),
        (
            "backwards-time",
            "time,x,y,z,yaw,pitch\n2,1,2,3,0,0\n\n1,1,2,3,0,0\n",
            4,
        ),
    ];
    for (name, text, line) in cases {
        let file = dir.path().join(format!("{name}.csv"));
        std::fs::write(&file, text).unwrap();
        let e = CameraPath::load_csv(&file).unwrap_err();
        assert!(matches!(e, Error::BadInput { .. }), "{name}: {e:?}");
        let msg = e.to_string();
        assert!(
            msg.contains(&format!("{name}.csv")) && msg.contains(&format!("line {line}:")),
            "{name}: {msg}"
        );
    }
    let missing = CameraPath::load_csv(dir.path().join("missing.csv")).unwrap_err();
    assert!(matches!(missing, Error::Io { .. }) && missing.to_string().contains("missing.csv"));
    assert!(CameraPath::default()
        .save_csv(dir.path().join("none.csv"))
        .is_err());
}

// ---- the frustum -------------------------------------------------------------------

fn random_camera(rng: &mut ChaCha8Rng) -> Camera {
    let pos = Vec3::new(
        rng.gen_range(-500.0..1500.0),
        rng.gen_range(0.0..60.0),
        rng.gen_range(300.0..2300.0),
    );
    let cam = Camera::new(pos, rng.gen_range(-7.0..7.0), rng.gen_range(-1.3..1.3)).unwrap();
    if rng.gen_bool(0.3) {
        return cam; // the thesis's defaults
    }
    let near = rng.gen_range(0.1..20.0);
    cam.with_fov(rng.gen_range(0.1..2.8), rng.gen_range(0.1..2.8))
        .unwrap()
        .with_clip(near, near + rng.gen_range(1.0..1200.0))
        .unwrap()
}

/// Separating-axis reference in f64: the largest gap between the two shapes'
/// projections over the 3 + 6 face normals and the 18 edge × edge cross products.
/// Positive: separated by that much; zero or negative: overlapping.
fn sat_gap(f: &Frustum, b: &Aabb) -> f64 {
    let fc: Vec<DVec3> = f.corners().iter().map(|c| c.as_dvec3()).collect();
    let bc: Vec<DVec3> = (0..8)
        .map(|i| {
            DVec3::new(
                if i & 1 != 0 { b.max.x } else { b.min.x } as f64,
                if i & 2 != 0 { b.max.y } else { b.min.y } as f64,
                if i & 4 != 0 { b.max.z } else { b.min.z } as f64,
            )
        })
        .collect();
    let box_axes = [DVec3::X, DVec3::Y, DVec3::Z];
    // Across and up along the far face: the near face is too small (at f32 precision)
    // to give these directions accurately.
    let f_edges = [
        fc[5] - fc[4],
        fc[6] - fc[4],
        fc[4] - fc[0],
        fc[5] - fc[1],
        fc[6] - fc[2],
        fc[7] - fc[3],
    ];
    let mut axes: Vec<DVec3> = box_axes.to_vec();
    axes.extend(f.planes().iter().map(|p| p.normal.as_dvec3()));
    for e in f_edges {
        for a in box_axes {
            axes.push(e.cross(a));
        }
    }
    let mut gap = f64::NEG_INFINITY;
    for axis in axes {
        let Some(n) = axis.try_normalize() else {
            continue;
        };
        let span = |pts: &[DVec3]| {
            pts.iter()
                .map(|p| p.dot(n))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
                    (lo.min(d), hi.max(d))
                })
        };
        let ((a0, a1), (b0, b1)) = (span(&fc), span(&bc));
        gap = gap.max(b0 - a1).max(a0 - b1);
    }
    gap
}

/// A point inside the frustum: `u, v` in [-1, 1] across, `t` in [0, 1] from near to far.
fn inside_point(c: &Camera, u: f32, v: f32, t: f32) -> Vec3 {
    let d = c.near + (c.far - c.near) * t;
    c.position
        + c.forward() * d
        + c.right() * (u * d * (c.fov_x * 0.5).tan())
        + c.up() * (v * d * (c.fov_y * 0.5).tan())
}

fn random_box(rng: &mut ChaCha8Rng, c: &Camera, f: &Frustum, kind: usize) -> Aabb {
    let scale = c.far;
    let half = |rng: &mut ChaCha8Rng, s: f32| {
        Vec3::new(
            rng.gen_range(0.0..s),
            rng.gen_range(0.0..s),
            rng.gen_range(0.0..s),
        )
    };
    let mut b = match kind {
        // Anywhere around the frustum, any size.
        0 => {
            let cell = f.aabb();
            let pad = cell.extent() * 0.3;
            let p = Vec3::new(
                rng.gen_range(cell.min.x - pad.x..=cell.max.x + pad.x),
                rng.gen_range(cell.min.y - pad.y..=cell.max.y + pad.y),
                rng.gen_range(cell.min.z - pad.z..=cell.max.z + pad.z),
            );
            let s = scale * 0.2;
            Aabb::around(p, half(rng, s))
        }
        // Small, inside.
        1 => {
            let p = inside_point(
                c,
                rng.gen_range(-0.9..0.9),
                rng.gen_range(-0.9..0.9),
                rng.gen_range(0.05..0.95),
            );
            Aabb::around(p, half(rng, c.near * 0.1))
        }
        // Straddling a corner of the frustum.
        2 => Aabb::around(f.corners()[rng.gen_range(0..8)], half(rng, scale * 0.05)),
        // Containing the whole frustum.
        3 => {
            let cell = f.aabb();
            Aabb {
                min: cell.min - half(rng, scale),
                max: cell.max + half(rng, scale),
            }
        }
        // Just outside the middle of a side edge, pushed out by a little: the hard case
        // for the plane test.
        _ => {
            let k = rng.gen_range(0..4);
            let (a, z) = (f.corners()[k], f.corners()[k + 4]);
            let on_edge = a + (z - a) * rng.gen_range(0.1..0.9);
            let (px, py) = (
                if k & 1 != 0 { 3 } else { 2 },
                if k & 2 != 0 { 5 } else { 4 },
            );
            let out = -(f.planes()[px].normal + f.planes()[py].normal).normalize();
            let s = rng.gen_range(0.01..5.0f32);
            Aabb::around(on_edge + out * (s * rng.gen_range(0.5..3.0)), half(rng, s))
        }
    };
    // Some boxes flat on one axis, some zero-sized, through their centre (so that a box
    // inside stays inside); a box containing the frustum stays whole.
    let centre = b.center();
    match rng.gen_range(0..6) {
        _ if kind == 3 => {}
        0 => {
            let axis = rng.gen_range(0..3);
            (b.min[axis], b.max[axis]) = (centre[axis], centre[axis]);
        }
        1 => (b.min, b.max) = (centre, centre),
        _ => {}
    }
    b
}

#[test]
fn view_culling_matches_separating_axes() {
    let mut rng = ChaCha8Rng::seed_from_u64(2002);
    let mut counts = [[0usize; 2]; 5];
    let mut near_misses = 0;
    for _ in 0..400 {
        let c = random_camera(&mut rng);
        let f = c.frustum();
        for _ in 0..40 {
            let kind = rng.gen_range(0..5);
            let b = random_box(&mut rng, &c, &f, kind);
            let exact = f.overlaps_aabb(&b);
            let gap = sat_gap(&f, &b);
            let tol = 1e-5 * (c.far as f64).max(c.position.abs().max_element() as f64);
            if exact != (gap <= 0.0) {
                // Only rounding may disagree, and then toward "overlaps".
                assert!(
                    exact && gap < tol,
                    "kind {kind}: {b} against {c:?}: exact {exact}, gap {gap}"
                );
                near_misses += 1;
            }
            assert!(
                !exact || f.cull_fast(&b),
                "the plane test rejected an overlapping box"
            );
            counts[kind][exact as usize] += 1;
        }
    }
    // Near misses come from boxes that touch the frustum (at its corners, kind 2).
    assert!(near_misses < 400 * 40 / 100, "{near_misses} near misses");
    // Every kind of box produced the answers it should.
    let [anywhere, inside, corner, containing, beside] = counts;
    assert!(anywhere[0] > 200 && anywhere[1] > 200, "{anywhere:?}");
    assert_eq!(inside[0], 0);
    assert!(
        corner[1] > 0 && containing[0] == 0,
        "{corner:?} {containing:?}"
    );
    assert!(beside[0] > 200, "{beside:?}");
}

#[test]
fn the_plane_test_keeps_what_the_exact_test_drops() {
    // Boxes just beside a side edge pass the plane test but not ViewCulling.
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let c = Camera::new(Vec3::new(0.0, 1.7, 0.0), 0.3, 0.0).unwrap();
    let f = c.frustum();
    let kept = (0..20_000)
        .map(|_| random_box(&mut rng, &c, &f, 4))
        .filter(|b| f.cull_fast(b) && !f.overlaps_aabb(b))
        .count();
    assert!(kept > 100, "{kept}");
}

#[test]
fn frustum_geometry() {
    let mut rng = ChaCha8Rng::seed_from_u64(45);
    for _ in 0..500 {
        let c = random_camera(&mut rng);
        let f = c.frustum();
        let tol = 2e-6 * c.far.max(c.position.abs().max_element());
        // Each corner lies on three planes and inside the other three.
        for (i, &k) in f.corners().iter().enumerate() {
            let on = [
                i & 4 == 0,
                i & 4 != 0,
                i & 1 == 0,
                i & 1 != 0,
                i & 2 == 0,
                i & 2 != 0,
            ];
            for (pl, on) in f.planes().iter().zip(on) {
                let d = pl.signed_distance(k);
                assert!(
                    if on { d.abs() <= tol * 4.0 } else { d > -tol },
                    "corner {i}: {d}"
                );
            }
        }
        let cell = f.aabb();
        assert!(f.corners().iter().all(|&k| cell.contains_point(k)));
        assert_eq!(cell, Aabb::from_points(f.corners().iter().copied()));
        // F of §4.2.5.
        let fc = c.far_center();
        assert!(((fc - c.position).length() - c.far).abs() <= tol * 4.0);
        assert!((fc - c.position).normalize().dot(c.forward()) > 0.99999);
        assert!(f.planes()[1].signed_distance(fc).abs() <= tol * 4.0);
        // Points inside by construction are inside.
        for _ in 0..10 {
            let p = inside_point(
                &c,
                rng.gen_range(-0.99..0.99),
                rng.gen_range(-0.99..0.99),
                rng.gen_range(0.01..0.99),
            );
            assert!(f.contains_point(p));
        }
    }
}

#[test]
fn thesis_defaults() {
    let c = Camera::new(Vec3::new(0.0, 1.7, 0.0), 0.0, 0.0).unwrap();
    assert_eq!(
        (c.far, c.fov_x, c.fov_y),
        (1000.0, 45f32.to_radians(), 45f32.to_radians())
    );
    // The frustum cell of a level view is 1 km deep and 2·tan(22.5°) km wide at the far end.
    let cell = c.frustum().aabb();
    assert!((cell.extent().x - 999.5).abs() < 0.01);
    assert!((cell.extent().z - 2000.0 * 22.5f32.to_radians().tan()).abs() < 0.01);
}
