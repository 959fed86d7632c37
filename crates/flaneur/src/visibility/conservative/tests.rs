use super::*;

fn b(min: [f32; 3], max: [f32; 3]) -> Aabb {
    Aabb::new(min, max).unwrap()
}

#[test]
fn a_wall_hides_what_is_behind_it_only() {
    let cell = b([0.0, 1.2, 0.0], [10.0, 2.0, 10.0]);
    let wall = b([-50.0, 0.0, 20.0], [60.0, 30.0, 28.0]);
    let behind = b([2.0, 0.0, 40.0], [6.0, 5.0, 44.0]);
    let tall_behind = b([2.0, 0.0, 40.0], [6.0, 80.0, 44.0]);
    let beside = b([200.0, 0.0, 40.0], [204.0, 5.0, 44.0]);
    let front = b([2.0, 0.0, 12.0], [6.0, 5.0, 16.0]);
    let objects = [wall, behind, tall_behind, beside, front];
    let none = || Occluders::aligned(vec![]);
    let occluders = [
        Occluders::aligned(vec![wall]),
        none(),
        none(),
        none(),
        none(),
    ];
    let scene = Scene::new(&objects, &occluders).unwrap();
    assert_eq!(scene.prism_count(), 1);
    let opts = SampleOptions::default();
    assert_eq!(
        scene.visible_from(&cell, &opts, &[]).unwrap(),
        vec![0, 2, 3, 4]
    );
    // What a ray saw is kept untested, and nothing else changes.
    let told = scene.visible_from(&cell, &opts, &[1, 3]).unwrap();
    assert_eq!(told, vec![0, 1, 2, 3, 4]);
    assert!(scene.visible_from(&cell, &opts, &[3, 1]).is_err());
    assert!(scene.visible_from(&cell, &opts, &[9]).is_err());
    // Occluders further than the radius are not used.
    let short = SampleOptions {
        radius: 5.0,
        ..opts
    };
    assert_eq!(
        scene.visible_from(&cell, &short, &[]).unwrap(),
        vec![0, 1, 2, 3, 4]
    );
}

#[test]
fn a_floating_box_is_no_prism() {
    let ground = b([0.0, 0.0, 0.0], [10.0, 10.0, 10.0]);
    let on_it = b([2.0, 10.0, 2.0], [8.0, 20.0, 8.0]);
    let floating = b([20.0, 5.0, 0.0], [30.0, 10.0, 10.0]);
    let overhang = b([-5.0, 10.0, 2.0], [8.0, 20.0, 8.0]);
    let boxes = vec![ground, on_it, floating, overhang];
    let p = prisms(&Occluders::aligned(boxes.clone()), 0.0);
    assert_eq!(p.len(), 2);
    assert_eq!(p[1].top, 20.0);
    // The same boxes in a frame turned a quarter: the same prisms, turned.
    let turned = Occluders {
        origin: Vec2::ZERO,
        axis: Vec2::Y,
        boxes,
    };
    let q = prisms(&turned, 0.0);
    assert_eq!(q.len(), 2);
    assert!(
        (q[0].centre - Vec2::new(-5.0, 5.0)).length() < 1e-5,
        "{q:?}"
    );
    assert!(
        (q[1].bounds().0 - Vec2::new(-8.0, 2.0)).length() < 1e-5,
        "{q:?}"
    );
    // And with the frame's origin moved: moved with it.
    let moved = Occluders {
        origin: Vec2::new(1000.0, -2000.0),
        ..turned
    };
    let r = prisms(&moved, 0.0);
    assert!(
        (r[0].centre - Vec2::new(995.0, -1995.0)).length() < 1e-3,
        "{r:?}"
    );
}

#[test]
fn bad_input_is_refused() {
    let ok = b([0.0; 3], [1.0; 3]);
    assert!(Scene::new(&[ok], &[]).is_err());
    let nan = Aabb {
        min: Vec3::splat(f32::NAN),
        max: Vec3::ONE,
    };
    let none = || Occluders::aligned(vec![]);
    assert!(Scene::new(&[nan], &[none()]).is_err());
    for axis in [Vec2::ZERO, Vec2::NAN, Vec2::new(1.0, 1.0)] {
        let bad = Occluders {
            origin: Vec2::ZERO,
            axis,
            boxes: vec![],
        };
        assert!(Scene::new(&[ok], &[bad]).is_err(), "{axis}");
    }
    let far = Occluders {
        origin: Vec2::new(f32::INFINITY, 0.0),
        ..Occluders::aligned(vec![])
    };
    assert!(Scene::new(&[ok], &[far]).is_err());
    assert!(Scene::new(&[ok], &[Occluders::aligned(vec![nan])]).is_err());
    let scene = Scene::new(&[ok], &[none()]).unwrap();
    let opts = SampleOptions::default();
    assert!(scene.visible_from(&nan, &opts, &[]).is_err());
    for bad in [
        SampleOptions {
            spacing: 0.0,
            ..opts
        },
        SampleOptions {
            spacing: f32::NAN,
            ..opts
        },
        SampleOptions {
            radius: -1.0,
            ..opts
        },
    ] {
        assert!(scene.visible_from(&ok, &bad, &[]).is_err());
    }
}
