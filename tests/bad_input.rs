//! Bad input of every kind gets a clear error naming what is wrong — never a panic,
//! never a silently wrong answer.

mod common;

use std::fs;
use std::io::Write;

use flaneur::geom::Aabb;
use flaneur::{BuildOptions, Database, Error};

fn city() -> common::City {
    common::city(
        200,
        3,
        &BuildOptions {
            page_size: 1024,
            ..Default::default()
        },
    )
}

fn flip(path: &std::path::Path, offset: u64) {
    let mut bytes = fs::read(path).unwrap();
    bytes[offset as usize] ^= 0x5a;
    fs::write(path, bytes).unwrap();
}

#[test]
fn a_flipped_byte_in_a_node_names_the_page() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    let root = db.tree().root;
    let page_size = db.store().page_size() as u64;
    drop(db);
    flip(&c.db, root * page_size + 40);
    let db = Database::open(&c.db).unwrap();
    let err = db.range(&c.bounds()).unwrap_err();
    assert!(
        matches!(err, Error::CorruptPage { page, .. } if page == root),
        "{err}"
    );
    assert!(err.to_string().contains(&format!("page {root}")), "{err}");
}

#[test]
fn a_flipped_byte_in_a_mesh_names_the_page() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    let obj = db.range(&c.bounds()).unwrap().objects[0];
    let page_size = db.store().page_size() as u64;
    drop(db);
    flip(&c.db, obj.mesh.first_page * page_size + 30);
    let db = Database::open(&c.db).unwrap();
    let err = db.mesh(&obj).unwrap_err();
    assert!(
        matches!(err, Error::CorruptPage { page, .. } if page == obj.mesh.first_page),
        "{err}"
    );
}

#[test]
fn truncated_databases_are_errors() {
    let c = city();
    let len = fs::metadata(&c.db).unwrap().len();
    for cut in [len - 1, len - 1024, 100, 0] {
        let f = fs::OpenOptions::new().write(true).open(&c.db).unwrap();
        f.set_len(cut).unwrap();
        drop(f);
        let err = Database::open(&c.db)
            .err()
            .unwrap_or_else(|| panic!("a file cut to {cut} bytes opened"));
        let msg = err.to_string();
        assert!(msg.contains(&c.db.display().to_string()), "{msg}");
    }
}

#[test]
fn bad_magic_and_foreign_files_are_errors() {
    let c = city();
    flip(&c.db, 0);
    assert!(matches!(
        Database::open(&c.db),
        Err(Error::NotADatabase { .. })
    ));
    let text = c.dir.path().join("notes.txt");
    fs::write(&text, "hello, this is not a database at all\n".repeat(200)).unwrap();
    assert!(Database::open(&text).is_err());
    assert!(Database::open(&c.dir.path().join("missing.flaneur")).is_err());
}

#[test]
fn bad_boxes_are_errors() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    let nan = Aabb {
        min: glam::Vec3::new(f32::NAN, 0.0, 0.0),
        max: glam::Vec3::ONE,
    };
    let inverted = Aabb {
        min: glam::Vec3::ONE,
        max: glam::Vec3::ZERO,
    };
    for bad in [nan, inverted] {
        assert!(matches!(db.range(&bad), Err(Error::BadBox(_))));
        assert!(matches!(db.csearch(&bad, &[]), Err(Error::BadBox(_))));
        assert!(matches!(
            db.csearch(&c.bounds(), &[bad]),
            Err(Error::BadBox(_))
        ));
    }
}

#[test]
fn malformed_obj_files_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("empty.obj", "# nothing here\n"),
        ("bad_vertex.obj", "v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n"),
        ("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"),
        ("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"),
    ];
    for (name, text) in cases {
        let obj = dir.path().join(name);
        fs::File::create(&obj)
            .unwrap()
            .write_all(text.as_bytes())
            .unwrap();
        let out = dir.path().join("out.flaneur");
        let err =
            flaneur::build_from_obj(std::slice::from_ref(&obj), &out, &BuildOptions::default())
                .err();
        let err = err.unwrap_or_else(|| panic!("{name} built"));
        assert!(err.to_string().contains(name), "{name}: {err}");
        assert!(!out.exists(), "{name}: a failed build left a database");
    }
}

#[test]
fn a_scene_file_cut_short_fails_the_build_and_leaves_no_database() {
    let c = city();
    let len = fs::metadata(&c.scene).unwrap().len();
    let f = fs::OpenOptions::new().write(true).open(&c.scene).unwrap();
    f.set_len(len / 2).unwrap();
    drop(f);
    let out = c.dir.path().join("half.flaneur");
    let err = flaneur::build_from_scene(&c.scene, &out, &BuildOptions::default()).unwrap_err();
    assert!(err.to_string().contains("city.scene"), "{err}");
    assert!(!out.exists());
}
