//! The visibility build split across processes: four `flaneur build --visibility
//! --shard K/4` processes run at once, then `flaneur merge`, give the very bytes of one
//! `flaneur build --visibility` (both `--reproducible`), for a generated city with an
//! HDoV-tree and for an OpenStreetMap extract. Shards that do not belong together are
//! refused, each naming what is wrong.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The visibility settings of these tests: small cells, coarse cube faces.
const VISIBILITY: [&str; 6] = [
    "--visibility",
    "--cell-size",
    "20",
    "--dov-resolution",
    "16",
    "--reproducible",
];

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A 150-object generated city in `dir`.
fn scene(dir: &Path) -> PathBuf {
    let scene = dir.join("c.scene");
    let config = citygen::CityConfig {
        objects: 150,
        seed: 8,
        landmarks: 0.0,
        ..Default::default()
    };
    citygen::write_city(&config, &scene).unwrap();
    scene
}

/// Runs `count` shard processes at once, each `build INPUT --shard K/count -o shard-K`
/// with `extra`; the shard files.
fn shards(input: &Path, dir: &Path, count: u32, extra: &[&str]) -> Vec<PathBuf> {
    let running: Vec<(PathBuf, std::process::Child)> = (0..count)
        .map(|k| {
            let out = dir.join(format!("shard-{k}"));
            let child = Command::new(env!("CARGO_BIN_EXE_flaneur"))
                .args([
                    "build",
                    s(input),
                    "-o",
                    s(&out),
                    "-q",
                    "--shard",
                    &format!("{k}/{count}"),
                ])
                .args(extra)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap();
            (out, child)
        })
        .collect();
    running
        .into_iter()
        .map(|(out, child)| {
            let done = child.wait_with_output().unwrap();
            let text = common::succeeded(&done);
            assert!(text.contains("visibility shard"), "{text}");
            out
        })
        .collect()
}

fn merge(input: &Path, shards: &[PathBuf], out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["merge", s(input), "-o", s(out), "-q", "--shards"];
    args.extend(shards.iter().map(|p| s(p)));
    args.extend_from_slice(extra);
    common::flaneur(&args)
}

#[test]
fn four_shard_processes_merged_give_the_bytes_of_one_build() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    let whole = dir.path().join("whole.flaneur");
    let mut args = vec![
        "build",
        s(&scene),
        "-o",
        s(&whole),
        "-q",
        "--hdov",
        "horizontal,indexed",
    ];
    args.extend_from_slice(&VISIBILITY);
    common::succeeded(&common::flaneur(&args));

    let parts = shards(&scene, dir.path(), 4, &VISIBILITY);
    // Each shard holds about a quarter of the cells.
    let cells: Vec<usize> = parts
        .iter()
        .map(|p| {
            flaneur::visibility::ShardCells::read(p)
                .unwrap()
                .cells
                .len()
        })
        .collect();
    let total: usize = cells.iter().sum();
    assert!(
        cells
            .iter()
            .all(|&n| n * 4 >= total - 4 && n * 4 <= total + 4),
        "{cells:?}"
    );
    // Given in any order.
    let shuffled = [
        parts[2].clone(),
        parts[0].clone(),
        parts[3].clone(),
        parts[1].clone(),
    ];
    let merged = dir.path().join("merged.flaneur");
    let text = common::succeeded(&merge(
        &scene,
        &shuffled,
        &merged,
        &["--hdov", "horizontal,indexed", "--reproducible"],
    ));
    assert!(text.contains(&format!("{total} walkable cells")), "{text}");
    assert!(
        std::fs::read(&whole).unwrap() == std::fs::read(&merged).unwrap(),
        "the merge's bytes differ from the build's"
    );
    let check = common::succeeded(&common::flaneur(&["check", s(&merged)]));
    assert!(check.starts_with("ok"), "{check}");
}

#[test]
fn an_openstreetmap_extract_merges_from_two_shards_as_it_builds() {
    let dir = tempfile::tempdir().unwrap();
    let extract = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/osm/helsinki.osm.pbf");
    let settings = [
        "--visibility",
        "--cell-size",
        "100",
        "--dov-resolution",
        "16",
        "--reproducible",
        "--no-lod",
    ];
    let whole = dir.path().join("whole.flaneur");
    let mut args = vec!["build", s(&extract), "-o", s(&whole), "-q"];
    args.extend_from_slice(&settings);
    common::succeeded(&common::flaneur(&args));
    let parts = shards(&extract, dir.path(), 2, &settings);
    let merged = dir.path().join("merged.flaneur");
    common::succeeded(&merge(
        &extract,
        &parts,
        &merged,
        &["--reproducible", "--no-lod"],
    ));
    assert!(std::fs::read(&whole).unwrap() == std::fs::read(&merged).unwrap());
}

#[test]
fn shards_that_do_not_belong_together_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    let parts = shards(&scene, dir.path(), 3, &VISIBILITY);
    let out = dir.path().join("m.flaneur");
    let refused = |shards: &[PathBuf], input: &Path, says: &str| {
        let done = merge(input, shards, &out, &[]);
        assert!(!done.status.success(), "{shards:?}");
        let err = String::from_utf8_lossy(&done.stderr);
        assert!(err.contains(says), "{says:?} not in: {err}");
        assert!(!out.exists(), "a refused merge writes nothing");
    };
    refused(&parts[..2], &scene, "shard 2/3 is missing");
    refused(
        &[parts[0].clone(), parts[0].clone(), parts[1].clone()],
        &scene,
        "is given twice",
    );
    // Another split of the same city.
    let other_dir = dir.path().join("other");
    std::fs::create_dir(&other_dir).unwrap();
    let two = shards(&scene, &other_dir, 2, &VISIBILITY);
    refused(
        &[parts[0].clone(), parts[1].clone(), two[1].clone()],
        &scene,
        "of another split",
    );
    // Other settings, and another city.
    let coarse = [
        "--visibility",
        "--cell-size",
        "30",
        "--dov-resolution",
        "16",
    ];
    let coarse_dir = dir.path().join("coarse");
    std::fs::create_dir(&coarse_dir).unwrap();
    let c = shards(&scene, &coarse_dir, 3, &coarse);
    refused(
        &[parts[0].clone(), parts[1].clone(), c[2].clone()],
        &scene,
        "other visibility settings",
    );
    let city2 = dir.path().join("city2");
    std::fs::create_dir(&city2).unwrap();
    let scene2 = city2.join("c.scene");
    citygen::write_city(
        &citygen::CityConfig {
            objects: 150,
            seed: 9,
            landmarks: 0.0,
            ..Default::default()
        },
        &scene2,
    )
    .unwrap();
    refused(&parts, &scene2, "computed from other objects");
    // A damaged shard file, and something else.
    let mut bytes = std::fs::read(&parts[1]).unwrap();
    let at = bytes.len() / 2;
    bytes[at] ^= 0x40;
    let damaged = dir.path().join("damaged");
    std::fs::write(&damaged, bytes).unwrap();
    refused(
        &[parts[0].clone(), damaged, parts[2].clone()],
        &scene,
        "checksum",
    );
    refused(
        &[parts[0].clone(), scene.clone(), parts[2].clone()],
        &scene,
        "not a flaneur visibility shard",
    );
    // A shard needs --visibility, and merge makes no shard: it has no such option.
    let done = common::flaneur(&["build", s(&scene), "-o", s(&out), "--shard", "0/2"]);
    assert!(String::from_utf8_lossy(&done.stderr).contains("give --visibility too"));
    let done = merge(&scene, &parts, &out, &["--shard", "0/2"]);
    assert!(String::from_utf8_lossy(&done.stderr).contains("unexpected argument '--shard'"));
    let done = common::flaneur(&[
        "build",
        s(&scene),
        "-o",
        s(&out),
        "--visibility",
        "--shard",
        "3/3",
    ]);
    assert!(String::from_utf8_lossy(&done.stderr).contains("K must be below N"));
}

/// Shards record whether their DoVs drew far objects through coarse LOD levels: shards
/// of a `--no-lod` build merged into a build with LODs (or the other way round, or
/// mixed) would give DoVs no whole build gives, so the merge refuses them, naming the
/// shard and what differs.
#[test]
fn shards_and_a_merge_that_disagree_on_lods_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    let flat_dir = dir.path().join("flat");
    std::fs::create_dir(&flat_dir).unwrap();
    let mut no_lod = VISIBILITY.to_vec();
    no_lod.push("--no-lod");
    let flat = shards(&scene, &flat_dir, 2, &no_lod);
    let coarse = shards(&scene, dir.path(), 2, &VISIBILITY);
    let out = dir.path().join("m.flaneur");
    let refused = |shards: &[PathBuf], extra: &[&str], says: &[&str]| {
        let done = merge(&scene, shards, &out, extra);
        assert!(!done.status.success(), "{shards:?} merged with {extra:?}");
        let err = String::from_utf8_lossy(&done.stderr);
        for s in says {
            assert!(err.contains(s), "{s:?} not in: {err}");
        }
        assert!(!out.exists(), "a refused merge writes nothing");
    };
    refused(&flat, &[], &["shard 0/2", "full meshes", "--no-lod"]);
    refused(&coarse, &["--no-lod"], &["shard 0/2", "coarse LOD levels"]);
    refused(
        &[coarse[0].clone(), flat[1].clone()],
        &[],
        &["shard 1/2", "full meshes"],
    );
    // Shards and a merge that agree merge, either way.
    common::succeeded(&merge(&scene, &flat, &out, &["--no-lod"]));
}
