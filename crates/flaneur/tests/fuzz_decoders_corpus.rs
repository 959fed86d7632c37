//! The corpora of the engine's fuzz targets (`fuzz/corpus/<target>/`, README "Fuzzing")
//! replayed through the same functions the targets call (`flaneur::fuzzing`), so that an
//! input that once found a fault stays a test without libFuzzer or a nightly toolchain.
//!
//! `write_decoder_seeds` (ignored) wrote the seeds the corpora grew from: a small city
//! built with LODs (a low PM threshold, so that progressive meshes are stored),
//! visibility and an HDoV-tree in 1 KiB pages, cut into the pieces each decoder takes,
//! with scene files and OBJ files the engine's writers wrote.

use std::fs;
use std::panic::catch_unwind;
use std::path::{Path, PathBuf};

use flaneur::fuzzing::{corpus_dir, corpus_inputs, cut_seeds, TARGETS};
use flaneur::hdov::HdovOptions;
use flaneur::lod::{LodOptions, ProgressiveMesh};
use flaneur::scene::{MeshCodec, SceneObject, SceneWriter};
use flaneur::visibility::VisibilityOptions;
use flaneur::{BuildOptions, Database};

/// Every input of every target's corpus, through the target's body: none may panic.
#[test]
fn every_input_of_every_decoder_corpus_runs_without_a_panic() {
    let mut failed = Vec::new();
    for (target, run) in TARGETS {
        for (name, data) in corpus_inputs(target).unwrap() {
            if catch_unwind(|| run(&data)).is_err() {
                failed.push(format!("{target}/{name}"));
            }
        }
    }
    assert!(failed.is_empty(), "inputs that panicked: {failed:?}");
}

/// A scene of `objects` citygen buildings, each simplified by the engine to about
/// `triangles` triangles, so that the seeds stay small (a corpus lives in the
/// repository, and libFuzzer mutates small inputs faster).
fn small_city(path: &Path, objects: u64, triangles: usize) {
    let city = citygen::CityConfig {
        objects,
        seed: 5,
        landmarks: 0.0,
        ..Default::default()
    };
    let mut writer = SceneWriter::create(path).unwrap();
    citygen::generate(&city, |mut o: SceneObject| {
        let pm = ProgressiveMesh::build(&o.mesh).unwrap();
        o.mesh = pm.mesh_at_triangles(triangles).unwrap();
        writer.write(&o)
    })
    .unwrap();
    writer.finish().unwrap();
}

/// The city the seeds are cut from: a dozen small buildings with every kind of data a
/// build stores, in 1 KiB pages, its meshes in `codec` (format version 1 or 2), a
/// progressive mesh for each object over `pm_threshold` triangles, a chain of levels for
/// the rest. `larger` makes them half as many buildings of eight times the triangles.
fn build_city(
    dir: &Path,
    codec: MeshCodec,
    pm_threshold: usize,
    larger: bool,
) -> (PathBuf, PathBuf) {
    let name = format!("city-{pm_threshold}-{}-{larger}", codec.packs());
    let (scene, db) = (
        dir.join(format!("{name}.scene")),
        dir.join(format!("{name}.flaneur")),
    );
    if larger {
        small_city(&scene, 6, 192);
    } else {
        small_city(&scene, 12, 24);
    }
    let options = BuildOptions {
        page_size: 1024,
        codec,
        lod: Some(LodOptions {
            pm_threshold,
            min_triangles: 8,
            ..Default::default()
        }),
        visibility: Some(VisibilityOptions {
            resolution: 16,
            ..Default::default()
        }),
        hdov: Some(HdovOptions::default()),
        ..Default::default()
    };
    flaneur::build_from_scene(&scene, &db, &options).unwrap();
    (scene, db)
}

/// Writes the seeds: the database's pieces (`cut_seeds`) in format versions 1 and 2 (the
/// latter's names start `v2-`; a second version-2 city of larger buildings, without zstd
/// and with a chain of levels for every object, gives the chains and level blobs
/// `v2-plain-`), scene files
/// of one and of three objects and the city's, one cut short, and OBJ files of the
/// city's meshes and their coarsest levels. Run once (and again when a format's version
/// changes), then fuzz and minimise (README, "Fuzzing").
#[test]
#[ignore = "writes the fuzz corpora's seeds"]
fn write_decoder_seeds() {
    let dir = tempfile::tempdir().unwrap();
    let (scene, db_path) = build_city(dir.path(), MeshCodec::Raw, 16, false);
    let mut seeds: Vec<(&str, String, Vec<u8>)> = cut_seeds(&db_path)
        .unwrap()
        .into_iter()
        .map(|s| (s.target, s.name, s.bytes))
        .collect();
    let (_, v2) = build_city(dir.path(), MeshCodec::meshopt(), 16, false);
    seeds.extend(
        cut_seeds(&v2)
            .unwrap()
            .into_iter()
            .map(|s| (s.target, format!("v2-{}", s.name), s.bytes)),
    );
    let (_, plain) = build_city(dir.path(), MeshCodec::Meshopt { zstd: None }, 1 << 20, true);
    seeds.extend(
        cut_seeds(&plain)
            .unwrap()
            .into_iter()
            .filter(|s| s.target == "lod_chain" || s.name.starts_with("levels-"))
            .map(|s| (s.target, format!("v2-plain-{}", s.name), s.bytes)),
    );

    for objects in [1, 3] {
        let path = dir.path().join(format!("{objects}.scene"));
        small_city(&path, objects, 24);
        seeds.push((
            "scene_file",
            format!("{objects}-objects"),
            fs::read(&path).unwrap(),
        ));
    }
    let city = fs::read(&scene).unwrap();
    seeds.push(("scene_file", "cut".into(), city[..city.len() / 3].to_vec()));
    seeds.push(("scene_file", "city".into(), city));

    let db = Database::open(&db_path).unwrap();
    let objects = db.range(&db.bounds()).unwrap().objects;
    for o in objects.iter().take(4) {
        let mesh = db.mesh(o).unwrap();
        let mut obj = Vec::new();
        flaneur::scene::write_mesh_obj(&mut obj, &mesh, 1).unwrap();
        seeds.push(("obj", format!("object-{}", o.id), obj));
        let levels = db.lod_levels(o.id).unwrap().unwrap_or_default();
        if let Some(coarsest) = levels.last().filter(|l| l.level > 0) {
            let mesh = db.lod_mesh(o.id, coarsest.level).unwrap();
            let mut obj = format!("o object-{}-level-{}\n", o.id, coarsest.level).into_bytes();
            flaneur::scene::write_mesh_obj(&mut obj, &mesh, 1).unwrap();
            seeds.push(("obj", format!("object-{}-coarsest", o.id), obj));
        }
    }

    for (target, _) in TARGETS {
        fs::create_dir_all(corpus_dir(target)).unwrap();
    }
    for (target, name, bytes) in seeds {
        assert!(
            bytes.len() < 64 * 1024 || target == "database",
            "{target}/{name}"
        );
        fs::write(corpus_dir(target).join(format!("seed-{name}")), bytes).unwrap();
    }
}
