//! The rasteriser on hand-made geometry, each case against the ray-cast reference.

use super::RasterScene;
use crate::scene::Mesh;
use crate::visibility::{point_dov, CubicProjection, PointDov, RayScene, SKY};

/// A quad with corners `a`, `b`, `c`, `d` (in order round it), as two triangles sharing
/// the diagonal a–c.
fn quad(a: [f32; 3], b: [f32; 3], c: [f32; 3], d: [f32; 3]) -> Mesh {
    Mesh {
        positions: vec![a, b, c, d],
        normals: vec![[0.0, 1.0, 0.0]; 4],
        indices: vec![0, 1, 2, 0, 2, 3],
    }
}

fn triangle(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Mesh {
    Mesh {
        positions: vec![a, b, c],
        normals: vec![[0.0, 1.0, 0.0]; 3],
        indices: vec![0, 1, 2],
    }
}

/// A viewpoint off every symmetry of the hand-made scenes: from the origin, their edges
/// pass exactly through pixel centres, where the ray-cast's Möller–Trumbore test may let
/// a ray through between two triangles (the rasteriser's fixed-point edges do not).
const EYE: [f32; 3] = [0.0123, 0.0071, -0.0037];

/// Both DoVs of `eye` over `meshes` (ids 0, 1, …) at N = `n`.
fn both(meshes: &[&Mesh], n: u32, eye: [f32; 3]) -> (PointDov, PointDov) {
    let pairs = || meshes.iter().enumerate().map(|(k, m)| (k as u64, *m));
    let cube = CubicProjection::new(n).unwrap();
    let rays = RayScene::new(pairs()).unwrap();
    let raster = RasterScene::new(pairs()).unwrap();
    (
        point_dov(&rays, &cube, eye).unwrap(),
        raster.point_dov_checked(&cube, eye),
    )
}

/// The sum over objects and sky of the DoVs' absolute differences.
fn difference(a: &PointDov, b: &PointDov) -> f64 {
    let dov = |p: &PointDov, o: u32| {
        p.objects
            .iter()
            .find(|s| s.0 == o)
            .map_or(0.0, |s| s.1 as f64)
    };
    let objects: std::collections::BTreeSet<u32> =
        a.objects.iter().chain(&b.objects).map(|s| s.0).collect();
    objects
        .iter()
        .map(|&o| (dov(a, o) - dov(b, o)).abs())
        .sum::<f64>()
        + (a.sky as f64 - b.sky as f64).abs()
}

#[test]
fn a_quad_covering_a_face_is_a_sixth_of_the_sphere() {
    // The +x face exactly: its pixels are the whole face, every centre well inside.
    let wall = quad(
        [1.0, -1.0, -1.0],
        [1.0, 1.0, -1.0],
        [1.0, 1.0, 1.0],
        [1.0, -1.0, 1.0],
    );
    let (rays, drawn) = both(&[&wall], 32, [0.0; 3]);
    assert_eq!(drawn.objects.len(), 1);
    assert!((drawn.objects[0].1 - 1.0 / 6.0).abs() < 1e-6, "{drawn:?}");
    // The diagonal runs through 32 pixel centres, some of which the rays slip through.
    let diagonal = 32.0 * CubicProjection::new(32).unwrap().pixel_dov(16, 16).unwrap();
    assert!(
        difference(&rays, &drawn) < 2.0 * diagonal as f64,
        "{rays:?} {drawn:?}"
    );
}

#[test]
fn pixel_centres_on_a_shared_edge_are_drawn_once_not_missed() {
    // A square face-on at distance 1 spanning u, v in [−½, ½]; at N = 8 its diagonal
    // passes through four pixel centres, and 16 centres lie inside it. Without the
    // top-left rule (every edge strict) the four on the diagonal would be sky.
    let square = quad(
        [-0.5, -0.5, 1.0],
        [0.5, -0.5, 1.0],
        [0.5, 0.5, 1.0],
        [-0.5, 0.5, 1.0],
    );
    let raster = RasterScene::new([(0, &square)]).unwrap();
    let cube = CubicProjection::new(8).unwrap();
    let ids = raster.item_buffer(&cube, [0.0; 3]).unwrap();
    let plus_z = &ids[4 * 64..5 * 64];
    assert_eq!(plus_z.iter().filter(|&&id| id == 0).count(), 16);
    assert!(ids[..4 * 64]
        .iter()
        .chain(&ids[5 * 64..])
        .all(|&id| id == SKY));
    for (j, i) in [(2, 2), (3, 3), (4, 4), (5, 5)] {
        assert_eq!(plus_z[j * 8 + i], 0, "the diagonal's pixel ({i}, {j})");
    }
}

#[test]
fn a_triangle_behind_the_viewpoint_shows_on_the_faces_behind() {
    let behind = triangle([-1.0, -1.0, -3.0], [1.0, -1.0, -3.0], [0.0, 1.0, -3.0]);
    let (rays, drawn) = both(&[&behind], 64, EYE);
    assert_eq!(drawn.objects.len(), 1);
    assert!(difference(&rays, &drawn) < 1e-6, "{rays:?} {drawn:?}");
    let cube = CubicProjection::new(64).unwrap();
    let ids = RasterScene::new([(0, &behind)])
        .unwrap()
        .item_buffer(&cube, EYE)
        .unwrap();
    let n2 = 64 * 64;
    assert!(
        ids[..5 * n2].iter().all(|&id| id == SKY),
        "only −z shows it"
    );
}

#[test]
fn a_floor_reaching_past_the_viewpoint_is_clipped_not_lost() {
    // A floor under the eye, reaching 50 m every way: it crosses the planes of four
    // faces, behind and in front of the viewpoint, and fills the −y face.
    let floor = quad(
        [-50.0, -1.5, -50.0],
        [50.0, -1.5, -50.0],
        [50.0, -1.5, 50.0],
        [-50.0, -1.5, 50.0],
    );
    let (rays, drawn) = both(&[&floor], 64, [0.3123, 0.0071, -0.2037]);
    assert!(drawn.objects[0].1 > 0.45, "{drawn:?}");
    assert!(difference(&rays, &drawn) < 1e-6, "{rays:?} {drawn:?}");
}

#[test]
fn a_triangle_through_the_viewpoint_is_seen_on_its_side() {
    // The eye on the triangle (its plane z = 0): a ray from it meets the triangle at
    // distance 0 in every direction not along its plane, so nothing behind it shows.
    // (The ray-cast itself misses it at exactly 0: its BVH's flat box; and it sees it
    // only partly 0.05 mm off the plane, by rounding.)
    let through = triangle([-4.0, -4.0, 0.0], [4.0, -4.0, 0.0], [0.0, 4.0, 0.0]);
    let wall = quad(
        [-5.0, -5.0, 3.0],
        [5.0, -5.0, 3.0],
        [5.0, 5.0, 3.0],
        [-5.0, 5.0, 3.0],
    );
    let (_, drawn) = both(&[&through, &wall], 16, [0.0; 3]);
    assert_eq!(drawn.objects.len(), 1, "{drawn:?}");
    assert!((drawn.objects[0].1 - 1.0).abs() < 1e-6, "{drawn:?}");
    // Just off its plane, on the side towards it only: half the sphere, as the rays
    // see it from 1 mm off.
    let (_, drawn) = both(&[&through], 16, [0.0, 0.0, -5e-5]);
    let (rays, _) = both(&[&through], 16, [0.0, 0.0, -1e-3]);
    assert!((drawn.objects[0].1 - 0.5).abs() < 1e-6, "{drawn:?}");
    assert!(difference(&rays, &drawn) < 1e-6, "{rays:?} {drawn:?}");
}

#[test]
fn of_two_coincident_walls_one_shows_and_nothing_behind_them() {
    let wall = |x: f32| {
        quad(
            [x, -2.0, -2.0],
            [x, 2.0, -2.0],
            [x, 2.0, 2.0],
            [x, -2.0, 2.0],
        )
    };
    let (a, b, behind) = (wall(3.0), wall(3.0), wall(6.0));
    let (rays, drawn) = both(&[&a, &b, &behind], 64, EYE);
    let total = |p: &PointDov| p.objects.iter().map(|s| s.1 as f64).sum::<f64>();
    assert!(drawn.objects.iter().all(|s| s.0 != 2), "{drawn:?}");
    assert!((total(&rays) - total(&drawn)).abs() < 1e-6);
    assert!((rays.sky - drawn.sky).abs() < 1e-6);
}

#[test]
fn a_sliver_takes_the_pixels_whose_centres_it_covers() {
    // A needle 4 m away across the +z face, widening from nothing to 6 cm, where a pixel
    // is 3 cm: a broken line of pixels along most of it, the same as the rays see.
    let sliver = triangle([-4.0, 0.0, 4.0], [4.0, 0.03, 4.0], [4.0, -0.03, 4.0]);
    let (rays, drawn) = both(&[&sliver], 256, EYE);
    let cube = CubicProjection::new(256).unwrap();
    let ray_ids = cube
        .identity_buffer(&RayScene::new([(0, &sliver)]).unwrap(), EYE)
        .unwrap();
    let ids = RasterScene::new([(0, &sliver)])
        .unwrap()
        .item_buffer(&cube, EYE)
        .unwrap();
    let shown = |b: &[u32]| b.iter().filter(|&&id| id == 0).count();
    assert!(shown(&ids) > 20, "{}", shown(&ids));
    let differing = ids.iter().zip(&ray_ids).filter(|(a, b)| a != b).count();
    assert!(
        differing <= 2,
        "{differing} of {} pixels differ",
        shown(&ids)
    );
    assert!(difference(&rays, &drawn) < 1e-5);
}

#[test]
fn a_near_wall_hides_what_is_behind_it_but_not_what_shows_past_its_edge() {
    let near = quad(
        [-1.0, -1.0, 2.0],
        [1.0, -1.0, 2.0],
        [1.0, 1.0, 2.0],
        [-1.0, 1.0, 2.0],
    );
    let hidden = quad(
        [-0.5, -0.5, 9.0],
        [0.5, -0.5, 9.0],
        [0.5, 0.5, 9.0],
        [-0.5, 0.5, 9.0],
    );
    let peeking = quad(
        [3.0, -1.0, 9.0],
        [6.0, -1.0, 9.0],
        [6.0, 1.0, 9.0],
        [3.0, 1.0, 9.0],
    );
    let (rays, drawn) = both(&[&hidden, &near, &peeking], 64, EYE);
    let seen: Vec<u32> = drawn.objects.iter().map(|s| s.0).collect();
    assert_eq!(seen, [1, 2]);
    assert!(difference(&rays, &drawn) < 1e-6, "{rays:?} {drawn:?}");
}
