//! Every build option is checked, with what it implies over the city, before the build's
//! slow work: a sample spacing or a viewcell size that would make trillions of sample
//! points or cells is refused naming the option before any object is written (the
//! progress never reports the objects' step, where the LODs are made), by the library
//! and by `flaneur build`, for a whole build, a shard and a merge. A refused or failed
//! build leaves nothing in the output folder: no database, no temporary.

mod common;

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use flaneur::progress::{Progress, Step};
use flaneur::visibility::{SampleOptions, Shard, ShardCells, VisibilityOptions};
use flaneur::{BuildOptions, WriteOrder};

/// The steps a job reported, each once, in the order they first reported.
#[derive(Default)]
struct Steps(Mutex<Vec<Step>>);

impl Progress for Steps {
    fn update(&self, step: Step, _: u64, _: Option<u64>) {
        let mut steps = self.0.lock().unwrap();
        if !steps.contains(&step) {
            steps.push(step);
        }
    }
}

impl Steps {
    fn saw(&self, step: Step) -> bool {
        self.0.lock().unwrap().contains(&step)
    }
}

/// A 40-object city's scene in a folder of its own.
fn scene(dir: &Path) -> PathBuf {
    let scene = dir.join("city.scene");
    let config = citygen::CityConfig {
        objects: 40,
        seed: 3,
        landmarks: 0.0,
        ..Default::default()
    };
    citygen::write_city(&config, &scene).unwrap();
    scene
}

/// The files of `dir` other than `keep`: what a build left there.
fn left_in(dir: &Path, keep: &[&Path]) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| !keep.contains(&p.as_path()))
        .map(|p| p.display().to_string())
        .collect()
}

/// Visibility with `spacing` between samples in `cell`-metre cells, LODs on.
fn visibility(cell: f32, spacing: f32) -> BuildOptions {
    BuildOptions {
        visibility: Some(VisibilityOptions {
            cell_size: cell,
            resolution: 16,
            samples: SampleOptions {
                spacing,
                ..Default::default()
            },
            ..Default::default()
        }),
        ..Default::default()
    }
}

/// The refusals of these tests: each option with a value far past what a city takes.
const REFUSED: [(&str, f32, f32); 2] =
    [("--sample-spacing", 20.0, 1e-9), ("--cell-size", 1e-9, 3.0)];

#[test]
fn a_sampling_or_a_grid_past_its_limit_is_refused_before_any_object_is_built() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    let db = dir.path().join("city.flaneur");
    for (option, cell, spacing) in REFUSED {
        for order in [WriteOrder::Hilbert, WriteOrder::Input] {
            let steps = Steps::default();
            let opts = BuildOptions {
                order,
                ..visibility(cell, spacing)
            };
            let e = flaneur::build_from_scene_with_progress(&scene, &db, &opts, &steps)
                .unwrap_err()
                .to_string();
            assert!(e.contains(option) && e.contains("1e-9"), "{option}: {e}");
            assert!(
                !steps.saw(Step::Objects),
                "{option}: objects were built first"
            );
            assert_eq!(left_in(dir.path(), &[&scene]), Vec::<String>::new());
        }
    }
}

#[test]
fn model_files_and_a_shard_are_checked_before_their_slow_steps() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("two.obj");
    // Two boxes 30 m apart.
    let cube = |x: f32, b: u32| {
        let mut t = String::from("o b\n");
        for k in 0..8 {
            let (dx, dy, dz) = ((k & 1) as f32, ((k >> 1) & 1) as f32, ((k >> 2) & 1) as f32);
            t += &format!("v {} {} {}\n", x + 10.0 * dx, 10.0 * dy, 10.0 * dz);
        }
        for f in [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ] {
            t += &format!("f {} {} {} {}\n", b + f[0], b + f[1], b + f[2], b + f[3]);
        }
        t
    };
    std::fs::write(&obj, cube(0.0, 1) + &cube(40.0, 9)).unwrap();
    let db = dir.path().join("two.flaneur");
    for (option, cell, spacing) in REFUSED {
        let steps = Steps::default();
        let e = flaneur::build_from_obj_with_progress(
            std::slice::from_ref(&obj),
            &db,
            &visibility(cell, spacing),
            &steps,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains(option), "{e}");
        assert!(!steps.saw(Step::Objects));
        let shard = dir.path().join("part.shard");
        let e = flaneur::build_visibility_shard(
            std::slice::from_ref(&obj),
            &shard,
            &visibility(cell, spacing),
            Shard { index: 0, count: 2 },
            &steps,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains(option), "{e}");
        assert!(!steps.saw(Step::Visibility), "the shard started its cells");
        assert_eq!(left_in(dir.path(), &[&obj]), Vec::<String>::new());
    }
    // A scale that puts the files past the largest coordinate there is says so.
    let huge = BuildOptions {
        obj_axes: flaneur::scene::ObjAxes {
            scale: 1e38,
            ..Default::default()
        },
        ..Default::default()
    };
    let e = flaneur::build_from_obj(std::slice::from_ref(&obj), &db, &huge)
        .unwrap_err()
        .to_string();
    assert!(e.contains("--scale"), "{e}");
    assert_eq!(left_in(dir.path(), &[&obj]), Vec::<String>::new());
}

#[test]
fn a_merge_takes_its_shards_settings_through_the_same_checks() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    let inputs = [scene.clone()];
    let opts = BuildOptions {
        lod: None,
        ..visibility(20.0, 3.0)
    };
    let silent = flaneur::progress::Silent;
    let parts: Vec<PathBuf> = (0..2)
        .map(|k| {
            let part = dir.path().join(format!("part{k}.shard"));
            let shard = Shard { index: k, count: 2 };
            flaneur::build_visibility_shard(&inputs, &part, &opts, shard, &silent).unwrap();
            part
        })
        .collect();
    // Shards whose cells are a nanometre wide: refused before the merge builds its
    // objects, not after.
    for part in &parts {
        let mut cells = ShardCells::read(part).unwrap();
        cells.options.cell_size = 1e-9;
        cells.write(part).unwrap();
    }
    let db = dir.path().join("merged.flaneur");
    let steps = Steps::default();
    // No LODs, as the shards drew none (a merge refuses shards that disagree).
    let e = flaneur::merge_visibility_shards(&inputs, &parts, &db, &opts, &steps)
        .unwrap_err()
        .to_string();
    assert!(e.contains("--cell-size") && e.contains("1e-9"), "{e}");
    assert!(
        !steps.saw(Step::Objects),
        "the merge built its objects first"
    );
    let mut keep: Vec<&Path> = parts.iter().map(|p| p.as_path()).collect();
    keep.push(&scene);
    assert_eq!(left_in(dir.path(), &keep), Vec::<String>::new());
}

#[test]
fn a_build_that_fails_after_its_temporary_exists_removes_it() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    let other = dir.path().join("other.scene");
    citygen::write_city(
        &citygen::CityConfig {
            objects: 40,
            seed: 4,
            landmarks: 0.0,
            ..Default::default()
        },
        &other,
    )
    .unwrap();
    let opts = BuildOptions {
        lod: None,
        ..visibility(20.0, 3.0)
    };
    let part = dir.path().join("whole.shard");
    let whole = Shard { index: 0, count: 1 };
    flaneur::build_visibility_shard(
        &[other.clone()],
        &part,
        &opts,
        whole,
        &flaneur::progress::Silent,
    )
    .unwrap();
    // The shard is of another city: the merge finds out once it has written the objects.
    let db = dir.path().join("merged.flaneur");
    let steps = Steps::default();
    let e = flaneur::merge_visibility_shards(&[scene.clone()], &[part.clone()], &db, &opts, &steps)
        .unwrap_err()
        .to_string();
    assert!(e.contains("other objects"), "{e}");
    assert!(
        steps.saw(Step::Objects),
        "the merge failed where this test means"
    );
    assert_eq!(
        left_in(dir.path(), &[&scene, &other, &part]),
        Vec::<String>::new()
    );
}

/// `flaneur build` with `args` after the scene and the output in `dir`; its output.
fn build_cli(scene: &Path, db: &Path, args: &[&str]) -> std::process::Output {
    let mut all = vec!["build", scene.to_str().unwrap(), "-o", db.to_str().unwrap()];
    all.extend_from_slice(args);
    common::flaneur(&all)
}

#[test]
fn flaneur_build_refuses_each_dangerous_value_naming_it_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    let db = dir.path().join("c.flaneur");
    // Each option with a value that would be absurd, and the words the error names it by.
    let cases: &[(&[&str], &[&str])] = &[
        (
            &["--visibility", "--sample-spacing", "1e-9"],
            &["--sample-spacing", "1e-9"],
        ),
        (
            &["--visibility", "--cell-size", "1e-9"],
            &["--cell-size", "1e-9"],
        ),
        (
            &["--visibility", "--cell-size", "0"],
            &["viewcell size", "--cell-size"],
        ),
        (
            &["--visibility", "--sample-spacing", "0"],
            &["--sample-spacing"],
        ),
        (
            &["--visibility", "--sample-spacing", "nan"],
            &["--sample-spacing"],
        ),
        (
            &["--visibility", "--occluder-radius", "-1"],
            &["--occluder-radius"],
        ),
        (
            &["--visibility", "--dov-resolution", "0"],
            &["--dov-resolution"],
        ),
        (
            &["--visibility", "--dov-resolution", "100000"],
            &["--dov-resolution"],
        ),
        (&["--page-size", "0"], &["--page-size"]),
        (&["--page-size", "3000"], &["--page-size"]),
        (&["--page-size", "1048576"], &["--page-size"]),
        (&["--fill", "nan"], &["--fill"]),
        (&["--fill", "0"], &["fill"]),
        (&["--hdov", "vertical"], &["--visibility"]),
        (&["--visibility", "--shard", "4/4"], &["shard"]),
    ];
    for (args, named) in cases {
        let out = build_cli(&scene, &db, args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} was built");
        // An exit code, not a signal: nothing aborted.
        assert!(out.status.code().is_some(), "{args:?}: {err}");
        for word in *named {
            assert!(err.contains(word), "{args:?}: {err}");
        }
        assert_eq!(
            left_in(dir.path(), &[&scene]),
            Vec::<String>::new(),
            "{args:?}"
        );
    }
}

#[test]
fn a_packed_build_with_visibility_reads_its_levels_through_the_dictionaries_it_trained() {
    // The visibility step reads back the coarse levels the LOD writer just stored,
    // compressed with the dictionaries it trained after the store had first been asked
    // for them (and had none).
    let opts = BuildOptions {
        codec: flaneur::scene::MeshCodec::meshopt(),
        ..visibility(40.0, 20.0)
    };
    let city = common::city(60, 5, &opts);
    let db = flaneur::Database::open(&city.db).unwrap();
    assert!(db.store().dictionaries().unwrap().is_some());
}
