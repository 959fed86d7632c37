// OBJ export of a region: the file loads in a standard OBJ reader with one group per
// object overlapping the region, and bad regions are configuration errors.

use citygen::{export_obj, object, CityConfig, SceneError};

#[test]
fn export_writes_one_group_per_object_in_the_region() {
    let dir = tempfile::tempdir().unwrap();
    let config = CityConfig {
        objects: 200,
        landmarks: 0.0,
        ..Default::default()
    };
    // The region around objects 0..3 of the first row.
    let (a, _) = object(&config, 0).unwrap().mesh.bounds();
    let (_, b) = object(&config, 2).unwrap().mesh.bounds();
    let region = ([a[0], a[2]], [b[0], a[2] + 1.0]);
    let out = dir.path().join("region.obj");
    let n = export_obj(&config, region, &out).unwrap();
    assert_eq!(n, 3);
    let (models, _) = tobj::load_obj(
        &out,
        &tobj::LoadOptions {
            single_index: true,
            triangulate: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(models.len(), 3);
    let names: Vec<&str> = models.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["object_0", "object_1", "object_2"]);
    for (id, m) in models.iter().enumerate() {
        let want = object(&config, id as u64).unwrap().mesh;
        assert_eq!(m.mesh.indices.len(), want.indices.len());
        assert_eq!(m.mesh.normals.len(), m.mesh.positions.len());
    }
    // The whole city.
    let e = config.extent();
    assert_eq!(
        export_obj(&config, ([0.0, 0.0], [e, e]), &out).unwrap(),
        200
    );
    // Nothing.
    assert_eq!(
        export_obj(&config, ([-50.0, -50.0], [-40.0, -40.0]), &out).unwrap(),
        0
    );
}

#[test]
fn bad_regions_are_config_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r.obj");
    let config = CityConfig {
        objects: 10,
        ..Default::default()
    };
    for region in [
        ([f32::NAN, 0.0], [1.0, 1.0]),
        ([5.0, 0.0], [1.0, 1.0]),
        ([0.0, 0.0], [f32::INFINITY, 1.0]),
    ] {
        assert!(matches!(
            export_obj(&config, region, &out),
            Err(SceneError::Config(_))
        ));
    }
    let bad = CityConfig {
        objects: 0,
        ..Default::default()
    };
    assert!(matches!(
        export_obj(&bad, ([0.0, 0.0], [1.0, 1.0]), &out),
        Err(SceneError::Config(_))
    ));
}
