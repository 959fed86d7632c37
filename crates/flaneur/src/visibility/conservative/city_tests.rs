use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;
use crate::visibility::cells::{object_boxes, ViewcellGrid, DEFAULT_EYE_RANGE};
use crate::visibility::intersect::{ray_triangle_distance, triangles};
use crate::visibility::occluder::occluders;

/// Rays from random walkable points of random cells of a small generated city: the
/// first object each ray meets is in the cell's PVS.
#[test]
fn no_object_a_ray_from_inside_the_cell_meets_is_dropped() {
    let objects = crate::visibility::tests::city(64);
    let (boxes, city) = object_boxes(objects.iter().map(|o| (o.id, &o.mesh))).unwrap();
    let occluders: Vec<Occluders> = objects.iter().map(|o| occluders(&o.mesh)).collect();
    let triangles: Vec<Vec<[Vec3; 3]>> = objects.iter().map(|o| triangles(&o.mesh)).collect();
    let scene = Scene::new(&boxes, &occluders).unwrap();
    let grid = ViewcellGrid::new(&city, 10.0, DEFAULT_EYE_RANGE).unwrap();
    let cells = grid.walkable(&boxes);
    assert!(cells.len() > 20);
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let (mut rays, mut hidden_total, mut hits) = (0, 0, 0);
    for _ in 0..60 {
        let cell = cells[rng.gen_range(0..cells.len())];
        let pvs = scene
            .visible_from(&cell.bounds, &SampleOptions::default(), &[])
            .unwrap();
        hidden_total += objects.len() - pvs.len();
        for _ in 0..100 {
            let f = Vec3::new(rng.gen(), rng.gen(), rng.gen());
            let p = cell.bounds.min + f * cell.bounds.extent();
            if boxes.iter().any(|b| b.contains_point(p)) {
                continue; // not where a walker stands
            }
            let dir = loop {
                let d = Vec3::new(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                );
                if (0.01..1.0).contains(&d.length_squared()) {
                    break d.normalize();
                }
            };
            rays += 1;
            let mut nearest: Option<(f32, usize)> = None;
            for (i, tris) in triangles.iter().enumerate() {
                for t in tris {
                    if let Some(d) = ray_triangle_distance(p, dir, t) {
                        if nearest.is_none_or(|(n, _)| d < n) {
                            nearest = Some((d, i));
                        }
                    }
                }
            }
            if let Some((_, i)) = nearest {
                hits += 1;
                assert!(
                    pvs.binary_search(&(i as u32)).is_ok(),
                    "cell {}: a ray from {p} along {dir} meets object {i}, not in its PVS",
                    cell.id
                );
            }
        }
    }
    assert!(rays > 3000 && hits > 1500, "{rays} rays, {hits} hits");
    // The test is not empty: occluders do hide objects.
    assert!(hidden_total > 0, "nothing was ever hidden");
}
