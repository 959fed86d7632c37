// Triangle budgets and spacing of the generated objects: the figures the rest of the
// engine plans around (buildings 200–2,000 triangles with a mean that keeps a million-
// object city near 20 GB, landmarks 50,000–200,000) and the promise that neighbouring
// buildings never intersect.

use citygen::{object, CityConfig, ObjectKind};

fn bounds_overlap(a: ([f32; 3], [f32; 3]), b: ([f32; 3], [f32; 3])) -> bool {
    (0..3).all(|k| a.0[k] < b.1[k] && b.0[k] < a.1[k])
}

#[test]
fn building_triangle_counts_are_in_range() {
    let mut bad = Vec::new();
    for spacing in [10.0, 20.0, 30.0] {
        let config = CityConfig {
            objects: 10_000,
            landmarks: 0.0,
            spacing,
            ..Default::default()
        };
        let mut per_kind = std::collections::BTreeMap::<&str, (u64, usize, usize, usize)>::new();
        let mut total = 0u64;
        let n = 500;
        for id in 0..n {
            let o = object(&config, id * 19).unwrap();
            o.mesh.validate().unwrap();
            let t = o.mesh.triangle_count();
            if !(200..=2000).contains(&t) {
                bad.push(format!(
                    "spacing {spacing}: {} {} has {t} triangles",
                    o.kind.name(),
                    o.id
                ));
            }
            assert!(!o.kind.is_landmark());
            total += t as u64;
            let e = per_kind
                .entry(o.kind.name())
                .or_insert((0, 0, usize::MAX, 0));
            e.0 += t as u64;
            e.1 += 1;
            e.2 = e.2.min(t);
            e.3 = e.3.max(t);
        }
        let mean = total as f64 / n as f64;
        for (k, (sum, count, min, max)) in &per_kind {
            println!(
                "spacing {spacing}: {k}: {count} objects, mean {:.0}, min {min}, max {max}",
                *sum as f64 / *count as f64
            );
        }
        println!("spacing {spacing}: mean {mean:.0}");
        if !(400.0..=900.0).contains(&mean) {
            bad.push(format!("spacing {spacing}: mean {mean}"));
        }
    }
    assert!(bad.is_empty(), "{bad:#?}");
}

#[test]
fn buildings_are_closed_and_outward() {
    let config = CityConfig {
        objects: 1000,
        landmarks: 0.0,
        ..Default::default()
    };
    for id in 0..100 {
        let o = object(&config, id).unwrap();
        assert!(o.mesh.signed_volume() > 0.0, "{} {id}", o.kind.name());
    }
}

#[test]
fn landmarks_are_in_the_landmark_range() {
    let config = CityConfig {
        objects: 1000,
        landmarks: 1.0,
        ..Default::default()
    };
    let mut kinds = Vec::new();
    for id in 0..9 {
        let o = object(&config, id).unwrap();
        o.mesh.validate().unwrap();
        let t = o.mesh.triangle_count();
        assert!(o.kind.is_landmark());
        assert!(
            (50_000..=200_000).contains(&t),
            "{} {id} has {t} triangles",
            o.kind.name()
        );
        assert!(o.mesh.signed_volume() > 0.0);
        if o.kind == ObjectKind::Bunny {
            assert_eq!(t, 58_784);
            let (min, max) = o.mesh.bounds();
            assert!(
                min[1].abs() < 1e-3 && max[1] > 9.0,
                "bunny stands on the ground"
            );
        }
        kinds.push(o.kind);
    }
    assert!(
        kinds.contains(&ObjectKind::Bunny) && kinds.contains(&ObjectKind::Sculpture),
        "{kinds:?}"
    );
}

#[test]
fn neighbouring_objects_do_not_intersect_and_stay_in_the_city() {
    for spacing in [10.0, 20.0] {
        let config = CityConfig {
            objects: 400,
            landmarks: 0.05,
            spacing,
            ..Default::default()
        };
        let extent = config.extent();
        let objects: Vec<_> = (0..config.objects)
            .map(|id| object(&config, id).unwrap())
            .collect();
        for (i, a) in objects.iter().enumerate() {
            let ba = a.mesh.bounds();
            assert!(ba.0[0] >= 0.0 && ba.0[2] >= 0.0 && ba.1[0] <= extent && ba.1[2] <= extent);
            assert!(
                ba.0[1] >= -1e-3,
                "{} {} is below ground",
                a.kind.name(),
                a.id
            );
            for b in &objects[i + 1..] {
                assert!(
                    !bounds_overlap(ba, b.mesh.bounds()),
                    "objects {} and {} intersect",
                    a.id,
                    b.id
                );
            }
        }
    }
}

#[test]
fn towers_reach_their_heights() {
    let config = CityConfig {
        objects: 10_000,
        landmarks: 0.0,
        ..Default::default()
    };
    let heights: Vec<f32> = (0..3000)
        .map(|id| object(&config, id).unwrap())
        .filter(|o| o.kind == ObjectKind::Tower)
        .map(|o| o.mesh.bounds().1[1])
        .collect();
    let max = heights.iter().cloned().fold(0.0, f32::max);
    let min = heights.iter().cloned().fold(f32::INFINITY, f32::min);
    println!("{} towers, {min:.1}..{max:.1} m", heights.len());
    assert!(min >= 20.0 && (90.0..=160.0).contains(&max), "{min}..{max}");
}
