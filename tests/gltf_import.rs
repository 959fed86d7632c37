//! glTF import, on files other tools wrote: a citygen city written as OBJ, converted by
//! assimp (the Open Asset Import Library, a `.glb` of one node and mesh per object) and
//! by gltfpack (a `.gltf` with its `.bin` beside it, every object merged into one mesh),
//! is built as the OBJ is, then walked in REVIEW, BOX and PVS and drawn. Malformed files
//! are errors naming what is wrong. `.ci/run` installs both tools; without them here the
//! tests that need them say so and skip.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use flaneur::scene::{load_gltf, GltfObjects};
use flaneur::Database;

/// A 40-object city as an OBJ file in `dir`.
fn city_obj(dir: &Path) -> PathBuf {
    let obj = dir.join("city.obj");
    let config = citygen::CityConfig {
        objects: 40,
        seed: 3,
        ..Default::default()
    };
    let all = ([-1.0e5, -1.0e5], [1.0e5, 1.0e5]);
    assert_eq!(citygen::export_obj(&config, all, &obj).unwrap(), 40);
    obj
}

/// Runs `tool args`; false (with a word) when the tool is not installed.
fn converted(tool: &str, args: &[&Path]) -> bool {
    match Command::new(tool).args(args).output() {
        Ok(out) => {
            assert!(out.status.success(), "{tool}: {out:?}");
            true
        }
        Err(e) => {
            eprintln!("skipped: {tool} is not installed ({e}); .ci/run installs it");
            false
        }
    }
}

fn build(inputs: &[&Path], out: &Path, extra: &[&str]) -> String {
    let mut args = vec!["build"];
    args.extend(inputs.iter().map(|p| p.to_str().unwrap()));
    args.extend(["-o", out.to_str().unwrap()]);
    args.extend_from_slice(extra);
    common::succeeded(&common::flaneur(&args))
}

#[test]
fn a_glb_from_assimp_builds_walks_and_draws_as_its_obj_does() {
    let dir = tempfile::tempdir().unwrap();
    let obj = city_obj(dir.path());
    let glb = dir.path().join("city.glb");
    if !converted("assimp", &[Path::new("export"), &obj, &glb]) {
        return;
    }
    // One object per node, as the OBJ's objects.
    let objects = load_gltf(&glb, GltfObjects::PerNode).unwrap();
    let from_obj = flaneur::scene::load_obj(&obj).unwrap();
    assert_eq!(objects.len(), from_obj.len());
    let names: Vec<&str> = objects.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names[0], from_obj[0].0, "{names:?}");
    let triangles = |v: &[(String, flaneur::scene::Mesh)]| -> usize {
        v.iter().map(|(_, m)| m.triangle_count()).sum()
    };
    assert_eq!(triangles(&objects), triangles(&from_obj));

    let visibility = [
        "--visibility",
        "--cell-size",
        "12",
        "--dov-resolution",
        "16",
    ];
    let (a, b) = (
        dir.path().join("glb.flaneur"),
        dir.path().join("obj.flaneur"),
    );
    build(&[&glb], &a, &visibility);
    build(&[&obj], &b, &visibility);
    let (ga, gb) = (Database::open(&a).unwrap(), Database::open(&b).unwrap());
    let (ia, ib) = (ga.info().unwrap(), gb.info().unwrap());
    assert_eq!((ia.objects, ia.triangles), (ib.objects, ib.triangles));
    let (ba, bb) = (ga.bounds(), gb.bounds());
    assert!(
        (ba.min - bb.min).abs().max_element() < 1e-3
            && (ba.max - bb.max).abs().max_element() < 1e-3,
        "{ba} against {bb}"
    );
    let db = a.to_str().unwrap();
    for mode in [
        &["--config", "optimal"][..],
        &["--config", "box"],
        &["--mode", "pvs"],
    ] {
        let mut args = vec!["walk", db, "--frames", "90", "--quiet"];
        args.extend_from_slice(mode);
        let text = common::succeeded(&common::flaneur(&args));
        assert!(
            text.contains("frames") || text.contains("walk"),
            "{mode:?}: {text}"
        );
    }
    let frames = dir.path().join("frames");
    let text = common::succeeded(&common::drawn_walk(&a, &frames, &["--frames", "20"]));
    assert!(text.contains("frames"), "{text}");
    assert!(std::fs::read_dir(&frames).unwrap().count() >= 1);
}

#[test]
fn a_gltf_with_its_bin_from_gltfpack_builds_one_object_per_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let obj = city_obj(dir.path());
    let gltf = dir.path().join("city.gltf");
    // No quantization: flaneur reads float positions, as the core glTF has them.
    if !converted(
        "gltfpack",
        &[
            Path::new("-noq"),
            Path::new("-i"),
            &obj,
            Path::new("-o"),
            &gltf,
        ],
    ) {
        return;
    }
    assert!(dir.path().join("city.bin").exists(), "the buffer beside it");
    let objects = load_gltf(&gltf, GltfObjects::PerMesh).unwrap();
    let from_obj = flaneur::scene::load_obj(&obj).unwrap();
    let sum = |v: &[(String, flaneur::scene::Mesh)]| -> usize {
        v.iter().map(|(_, m)| m.triangle_count()).sum()
    };
    assert_eq!(sum(&objects), sum(&from_obj), "every triangle, merged");
    let out = dir.path().join("city.flaneur");
    let text = build(&[&gltf], &out, &["--gltf-objects", "mesh", "--no-lod"]);
    assert!(
        text.contains(&format!("{} objects", objects.len())),
        "{text}"
    );
    // The buffer gone: the error names it.
    std::fs::remove_file(dir.path().join("city.bin")).unwrap();
    let err = load_gltf(&gltf, GltfObjects::PerNode)
        .unwrap_err()
        .to_string();
    assert!(err.contains("city.bin"), "{err}");
}

/// The JSON of a glTF of one triangle (its buffer in a data URI), as `edit` makes it
/// from a valid one.
fn triangle_json(edit: impl Fn(&mut serde_json::Value)) -> serde_json::Value {
    use base64::Engine;
    let mut bytes = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0] {
        bytes.extend(v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0] {
        bytes.extend(i.to_le_bytes());
    }
    let data = base64::engine::general_purpose::STANDARD.encode(&bytes);
    let mut json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "tri", "mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 0, 1]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6}
        ],
        "buffers": [{"byteLength": 44, "uri": format!("data:application/octet-stream;base64,{data}")}]
    });
    edit(&mut json);
    json
}

/// `json` written as `t.gltf` and imported.
fn read(json: &serde_json::Value) -> flaneur::Result<Vec<(String, flaneur::scene::Mesh)>> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.gltf");
    std::fs::write(&path, serde_json::to_vec(json).unwrap()).unwrap();
    load_gltf(&path, GltfObjects::PerNode)
}

fn one_triangle(edit: impl Fn(&mut serde_json::Value)) -> flaneur::Result<usize> {
    read(&triangle_json(edit)).map(|o| o.len())
}

/// A change to a glTF file's JSON.
type Edit = Box<dyn Fn(&mut serde_json::Value)>;

#[test]
fn malformed_gltf_files_are_errors_that_say_what_is_wrong() {
    assert_eq!(
        one_triangle(|_| {}).unwrap(),
        1,
        "the file the others break"
    );
    let cases: Vec<(&str, Edit)> = vec![
        (
            "only triangle lists",
            Box::new(|j| j["meshes"][0]["primitives"][0]["mode"] = 1.into()),
        ),
        (
            "past its 3 vertices",
            Box::new(|j| {
                let mut b = j["buffers"][0]["uri"].as_str().unwrap().to_string();
                // The index bytes: 0, 1, 2 becomes 0, 1, 7.
                use base64::Engine;
                let e = base64::engine::general_purpose::STANDARD;
                let data = b.split_off(b.find("base64,").unwrap() + 7);
                let mut bytes = e.decode(data).unwrap();
                bytes[40] = 7;
                j["buffers"][0]["uri"] = format!("{b}{}", e.encode(bytes)).into();
            }),
        ),
        (
            "reaches past its buffer view",
            Box::new(|j| j["accessors"][0]["count"] = 4.into()),
        ),
        (
            "reaches past its buffer",
            Box::new(|j| j["bufferViews"][1]["byteLength"] = 60.into()),
        ),
        (
            "holds 44 bytes, the file says 80",
            Box::new(|j| j["buffers"][0]["byteLength"] = 80.into()),
        ),
        (
            "not a path relative to the file",
            Box::new(|j| j["buffers"][0]["uri"] = "http://example.com/a.bin".into()),
        ),
        (
            "POSITION\"]: Missing data",
            Box::new(|j| {
                j["meshes"][0]["primitives"][0]["attributes"] = serde_json::json!({"NORMAL": 0});
            }),
        ),
        (
            "no triangles",
            Box::new(|j| j["scenes"][0]["nodes"] = serde_json::json!([])),
        ),
        (
            "not a finite point",
            Box::new(|j| {
                j["nodes"][0]["scale"] = serde_json::json!([3e38, 1, 1]);
                j["nodes"][0]["translation"] = serde_json::json!([3e38, 0, 0]);
            }),
        ),
        (
            "malformed glTF",
            Box::new(|j| j["accessors"][0]["bufferView"] = 9.into()),
        ),
        // gltf-json 1.4's validation panics on this one; it is checked before.
        (
            "POSITION is accessor 9, of 2",
            Box::new(|j| j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 9.into()),
        ),
    ];
    for (want, edit) in cases {
        let err = match one_triangle(edit) {
            Ok(n) => panic!("wanted '{want}', read {n} objects"),
            Err(e) => e.to_string(),
        };
        assert!(err.contains(want), "wanted '{want}', got: {err}");
        assert!(err.contains("t.gltf"), "the file is named: {err}");
    }
    // Bytes that are no glTF at all.
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("broken.glb");
    std::fs::write(&glb, b"glTF\x02\x00\x00\x00\xff\xff\xff\x7f").unwrap();
    let err = load_gltf(&glb, GltfObjects::PerNode)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("malformed glTF") && err.contains("broken.glb"),
        "{err}"
    );
    // A GLB header naming fewer bytes than itself (gltf 1.4 overflows on it).
    std::fs::write(&glb, b"glTF\x02\x00\x00\x00\x08\x00\x00\x00JSON").unwrap();
    let err = load_gltf(&glb, GltfObjects::PerNode)
        .unwrap_err()
        .to_string();
    assert!(err.contains("a GLB of 8 bytes"), "{err}");
}

#[test]
fn a_mirroring_node_keeps_its_triangles_facing_out() {
    let normal_of = |scale: [f32; 3]| {
        let json = triangle_json(|j| j["nodes"][0]["scale"] = serde_json::json!(scale));
        let m = read(&json).unwrap().remove(0).1;
        let [a, b, c] = [0, 1, 2].map(|k| glam::Vec3::from(m.positions[m.indices[k] as usize]));
        (b - a).cross(c - a).normalize()
    };
    // The triangle (0,0,0), (1,0,0), (0,0,1) faces -y; mirrored in x it still must.
    assert!(normal_of([1.0, 1.0, 1.0]).y < -0.99);
    assert!(normal_of([-1.0, 1.0, 1.0]).y < -0.99);
}
