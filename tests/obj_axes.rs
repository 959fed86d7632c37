//! OBJ axes and units: a citygen city written as OBJ, then turned z-up or written in
//! centimetres as GIS and CAD exports are, builds back to the city's own bounds with
//! `--up z` and `--scale 0.01`, or unasked when it is plainly z-up, the build saying
//! which axis it took and why.

mod common;

use std::path::Path;

use flaneur::geom::Aabb;
use flaneur::Database;

/// A 300-object city (about 480 m across, 60 m tall) as OBJ in `dir`.
fn city_obj(dir: &Path) -> std::path::PathBuf {
    let obj = dir.join("city.obj");
    let config = citygen::CityConfig {
        objects: 300,
        seed: 4,
        landmarks: 0.0,
        ..Default::default()
    };
    citygen::export_obj(&config, ([-1.0e5, -1.0e5], [1.0e5, 1.0e5]), &obj).unwrap();
    obj
}

/// `from` with every vertex and normal rewritten by `f`.
fn rewrite(from: &Path, to: &Path, f: impl Fn([f64; 3]) -> [f64; 3], normals: bool) {
    let text = std::fs::read_to_string(from).unwrap();
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        let mut parts = line.split_whitespace();
        let tag = parts.next();
        if tag == Some("v") || (normals && tag == Some("vn")) {
            let v: Vec<f64> = parts.map(|p| p.parse().unwrap()).collect();
            let [x, y, z] = f([v[0], v[1], v[2]]);
            out.push_str(&format!("{} {x} {y} {z}\n", tag.unwrap()));
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    std::fs::write(to, out).unwrap();
}

fn build(obj: &Path, db: &Path, extra: &[&str]) -> (String, Aabb) {
    let mut args = vec!["build", obj.to_str().unwrap(), "-o", db.to_str().unwrap()];
    args.extend_from_slice(&["--no-lod"]);
    args.extend_from_slice(extra);
    let text = common::succeeded(&common::flaneur(&args));
    (text, Database::open(db).unwrap().bounds())
}

fn close(a: &Aabb, b: &Aabb) -> bool {
    (a.min - b.min).abs().max_element() < 1e-2 && (a.max - b.max).abs().max_element() < 1e-2
}

#[test]
fn z_up_and_centimetre_cities_build_back_to_their_own_bounds() {
    let dir = tempfile::tempdir().unwrap();
    let obj = city_obj(dir.path());
    let (text, city) = build(&obj, &dir.path().join("y.flaneur"), &[]);
    assert!(text.contains("OBJ inputs: y up, as flaneur"), "{text}");
    assert!(text.contains("1 m a unit"), "{text}");

    // z up, as GIS exports: (x, y, z) written as (x, -z, y).
    let z_up = dir.path().join("z.obj");
    rewrite(&obj, &z_up, |[x, y, z]| [x, -z, y], true);
    let (text, bounds) = build(&z_up, &dir.path().join("z.flaneur"), &[]);
    assert!(
        text.contains("plainly z-up, 454 × 339 wide and 140 tall (--up y keeps them as they are)"),
        "{text}"
    );
    assert!(close(&bounds, &city), "{bounds} against {city}");
    let (text, told) = build(&z_up, &dir.path().join("z2.flaneur"), &["--up", "z"]);
    assert!(text.contains("z up (--up z), turned to y up"), "{text}");
    assert!(close(&told, &city));
    // Told y, it is kept as it is: on its side.
    let (_, kept) = build(&z_up, &dir.path().join("z3.flaneur"), &["--up", "y"]);
    assert!(!close(&kept, &city));
    assert!(kept.max.y - kept.min.y > 300.0, "{kept}");

    // Centimetres.
    let cm = dir.path().join("cm.obj");
    rewrite(
        &obj,
        &cm,
        |[x, y, z]| [x * 100.0, y * 100.0, z * 100.0],
        false,
    );
    let (text, scaled) = build(&cm, &dir.path().join("cm.flaneur"), &["--scale", "0.01"]);
    assert!(text.contains("0.01 m a unit"), "{text}");
    assert!(close(&scaled, &city), "{scaled} against {city}");

    // A scale that is no scale fails before any work.
    for bad in ["0", "-1", "nan", "inf"] {
        let out = common::flaneur(&[
            "build",
            obj.to_str().unwrap(),
            "-o",
            "x.flaneur",
            "--scale",
            bad,
        ]);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("scale") || err.contains("finite"),
            "{bad}: {err}"
        );
    }
    let out = common::flaneur(&[
        "build",
        obj.to_str().unwrap(),
        "-o",
        "x.flaneur",
        "--up",
        "x",
    ]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("y, z or auto"));
}

#[test]
fn insert_turns_and_scales_its_obj_files_as_build_does() {
    let dir = tempfile::tempdir().unwrap();
    let obj = city_obj(dir.path());
    let (_, city) = build(&obj, &dir.path().join("y.flaneur"), &[]);
    // The city in centimetres and z up, inserted into a database of one far-off object.
    let cm_z = dir.path().join("cm-z.obj");
    rewrite(
        &obj,
        &cm_z,
        |[x, y, z]| [x * 100.0, -z * 100.0, y * 100.0],
        true,
    );
    let seed = dir.path().join("seed.obj");
    std::fs::write(
        &seed,
        "o seed\nv 2000 0 2000\nv 2001 0 2000\nv 2000 1 2000\nv 2000 0 2001\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    let db = dir.path().join("insert.flaneur");
    build(&seed, &db, &[]);
    let text = common::succeeded(&common::flaneur(&[
        "insert",
        db.to_str().unwrap(),
        cm_z.to_str().unwrap(),
        "--up",
        "z",
        "--scale",
        "0.01",
    ]));
    assert!(text.contains("inserted 300 objects"), "{text}");
    assert!(
        text.contains("z up (--up z), turned to y up; 0.01 m a unit"),
        "{text}"
    );
    let d = Database::open(&db).unwrap();
    assert_eq!(d.objects(), 301);
    // The inserted city stands where the city does, the seed beside it.
    let inserted = d.range(&city).unwrap();
    assert_eq!(inserted.objects.len(), 300);
    let union = inserted
        .objects
        .iter()
        .fold(Aabb::EMPTY, |a, o| a.union(&o.bounds));
    assert!(close(&union, &city), "{union} against {city}");
    // Unasked, plainly z-up files are turned, and saying so.
    let db2 = dir.path().join("insert2.flaneur");
    build(&seed, &db2, &[]);
    let text = common::succeeded(&common::flaneur(&[
        "insert",
        db2.to_str().unwrap(),
        cm_z.to_str().unwrap(),
        "--scale",
        "0.01",
    ]));
    assert!(text.contains("plainly z-up"), "{text}");
}
