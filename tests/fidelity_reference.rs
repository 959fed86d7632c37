//! `flaneur bench fidelity --reference`: a walk of a format-version-2 file (quantised
//! meshes) drawn against full-detail pictures read from its version-1 twin (raw floats),
//! and a reference holding another city refused before anything is drawn. Both files are
//! built by the binary from one citygen scene; the pictures are drawn by Mesa's lavapipe
//! where there is no GPU.

mod common;

use common::{flaneur, succeeded, Csv};

/// A small city's scene (60 objects) written into `dir` with `seed`.
fn scene(dir: &std::path::Path, seed: u64) -> std::path::PathBuf {
    let scene = dir.join(format!("city-{seed}.scene"));
    let config = citygen::CityConfig {
        objects: 60,
        seed,
        landmarks: 0.0,
        ..Default::default()
    };
    citygen::write_city(&config, &scene).unwrap();
    scene
}

/// `scene` built by `flaneur build` with `codec` (raw or meshopt) into `dir`; no LODs,
/// which pictures at full detail do not use.
fn build(scene: &std::path::Path, dir: &std::path::Path, codec: &str) -> String {
    let db = dir.join(format!("{codec}.flaneur"));
    let db = db.to_str().unwrap().to_string();
    succeeded(&flaneur(&[
        "build",
        scene.to_str().unwrap(),
        "-o",
        &db,
        "--no-lod",
        "--codec",
        codec,
    ]));
    db
}

/// The criterion on a small city: every frame of the version-2 file's walk at
/// full detail identical to the version-1 file's picture or above 50 dB, the report
/// naming the file the reference came from and counting the frames either side.
#[test]
fn a_version_2_walk_matches_its_version_1_twin() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path(), 3);
    let (v1, v2) = (
        build(&scene, dir.path(), "raw"),
        build(&scene, dir.path(), "meshopt"),
    );
    let out = dir.path().join("out");
    let stdout = succeeded(&flaneur(&[
        "bench",
        "fidelity",
        &v2,
        "--reference",
        &v1,
        "--lod-tau",
        "0",
        "--frames",
        "12",
        "--size",
        "160x90",
        "--out",
        out.to_str().unwrap(),
    ]));
    let csv = Csv::read(&out.join("fidelity.csv"));
    assert_eq!(csv.rows.len(), 12, "{stdout}");
    let mut below = 0;
    for row in &csv.rows {
        // The same city: the walk loads every object in view before drawing it, so both
        // pictures draw the same objects' triangles.
        assert_eq!(
            csv.num(row, "triangles"),
            csv.num(row, "reference_triangles"),
            "{row:?}"
        );
        let psnr = csv.num(row, "psnr_db"); // "inf" parses as infinite
        below += usize::from(psnr < 50.0);
    }
    assert_eq!(below, 0, "frames below 50 dB:\n{stdout}");
    assert!(
        csv.rows.iter().any(|r| csv.num(r, "triangles") > 0.0),
        "nothing drawn: {stdout}"
    );
    let summary = std::fs::read_to_string(out.join("fidelity.md")).unwrap();
    assert!(
        summary.contains(&format!("against full detail from {v1}")),
        "{summary}"
    );
    assert!(
        summary.contains("| the others at 50 dB or more / below |") && summary.contains(" / 0 |"),
        "{summary}"
    );
}

/// The reference pictures are read from the reference file: against a twin whose every
/// normal points the other way (the same ids, boxes and triangles, so the same city to
/// the check, but lit otherwise), every frame that draws anything differs, while the
/// same walk against its own file is identical throughout.
#[test]
fn the_reference_pictures_come_from_the_reference_file() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path(), 3);
    let flipped_scene = dir.path().join("flipped.scene");
    let mut w = citygen::SceneWriter::create(&flipped_scene).unwrap();
    for o in citygen::SceneReader::open(&scene).unwrap() {
        let mut o = o.unwrap();
        for n in &mut o.mesh.normals {
            *n = n.map(|c| -c);
        }
        w.write(&o).unwrap();
    }
    w.finish().unwrap();
    let db = build(&scene, dir.path(), "raw");
    let flipped_dir = dir.path().join("flipped");
    std::fs::create_dir(&flipped_dir).unwrap();
    let flipped = build(&flipped_scene, &flipped_dir, "raw");
    let fidelity = |reference: Option<&str>, out: &str| {
        let out = dir.path().join(out);
        let mut args = vec!["bench", "fidelity", &db, "--lod-tau", "0", "--frames", "4"];
        args.extend(["--size", "96x54", "--out", out.to_str().unwrap()]);
        if let Some(r) = reference {
            args.extend(["--reference", r]);
        }
        succeeded(&flaneur(&args));
        Csv::read(&out.join("fidelity.csv"))
    };
    let own = fidelity(None, "own");
    assert!(own.rows.iter().all(|r| own.get(r, "psnr_db") == "inf"));
    let other = fidelity(Some(&flipped), "flipped");
    let drawn: Vec<_> = (other.rows.iter())
        .filter(|r| other.num(r, "triangles") > 0.0)
        .collect();
    assert!(!drawn.is_empty());
    for row in drawn {
        assert!(other.num(row, "psnr_db") < 50.0, "{row:?}");
    }
}

/// A reference of another city (another seed, as many objects) is refused with an error
/// naming the reference and what differs, before any picture is drawn or report written.
#[test]
fn a_reference_of_another_city_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mine = build(&scene(dir.path(), 3), dir.path(), "meshopt");
    let other_dir = dir.path().join("other");
    std::fs::create_dir(&other_dir).unwrap();
    let other = build(&scene(dir.path(), 4), &other_dir, "raw");
    let out = dir.path().join("out");
    let run = flaneur(&[
        "bench",
        "fidelity",
        &mine,
        "--reference",
        &other,
        "--frames",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success(), "{err}");
    assert!(
        err.contains(&other) && err.contains("the reference holds another city"),
        "{err}"
    );
    assert!(
        err.contains("in the database") && err.contains("in the reference"),
        "{err}"
    );
    assert!(!out.exists(), "a report was written: {err}");
    assert!(
        !String::from_utf8_lossy(&run.stdout).contains("drawn twice"),
        "drawing began"
    );
}
