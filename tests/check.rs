//! `flaneur check` end to end: a healthy database passes (exit 0), one with a damaged
//! page fails (exit 1) naming the page and what it belongs to, in text and JSON; the
//! node copies inserts leave behind are noted, not failed.

mod common;

use std::os::unix::fs::FileExt;

use common::flaneur;
use flaneur::{BuildOptions, Database};

#[test]
fn check_passes_a_healthy_database_and_names_a_damaged_page() {
    let c = common::city(80, 6, &common::with_visibility());
    let db = c.db.to_str().unwrap();
    let out = flaneur(&["check", db]);
    let text = common::succeeded(&out);
    assert!(
        text.contains("ok: ") && text.contains("80 objects"),
        "{text}"
    );
    let out = flaneur(&["check", db, "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["objects"], 80);
    assert_eq!(v["problems"].as_array().unwrap().len(), 0);

    // One byte of the first object's mesh.
    let opened = Database::open(&c.db).unwrap();
    let first = opened.range(&opened.bounds()).unwrap().objects[0];
    let page_size = opened.store().page_size() as u64;
    drop(opened);
    let file = std::fs::OpenOptions::new().write(true).open(&c.db).unwrap();
    file.write_all_at(&[0xAB], first.mesh.first_page * page_size + 20)
        .unwrap();
    let out = flaneur(&["check", db]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert_eq!(out.status.code(), Some(1), "{stdout}{stderr}");
    // Meshes are packed several to a page: the damaged page names every owner.
    let line = stdout
        .lines()
        .find(|l| l.contains(&format!("page {} (", first.mesh.first_page)))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(
        line.contains(&format!("mesh of object {}", first.id))
            && line.contains("): checksum mismatch"),
        "{line}"
    );
    assert!(stderr.contains("1 problem found"), "{stderr}");
    let out = flaneur(&["check", db, "--json"]);
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["problems"][0]["page"], first.mesh.first_page);
    let part = v["problems"][0]["part"].as_str().unwrap();
    assert!(part.starts_with("mesh of object "), "{part}");
    assert!(
        part.split(", ")
            .any(|p| p == format!("mesh of object {}", first.id)),
        "{part}"
    );
}

#[test]
fn inserts_leave_node_copies_that_check_notes_and_passes() {
    let c = common::city(50, 7, &BuildOptions::default());
    let mut db = Database::open_writable(&c.db, flaneur::Backend::Mmap).unwrap();
    let b = db.bounds();
    for i in 0..30u64 {
        let x = b.min.x + i as f32 * 3.0;
        db.insert(
            500 + i,
            &common::box_mesh([x, 0.0, b.min.z], [x + 2.0, 4.0, b.min.z + 2.0]),
        )
        .unwrap();
    }
    drop(db);
    let text = common::succeeded(&flaneur(&["check", c.db.to_str().unwrap()]));
    assert!(
        text.contains("rtree-node pages belong to no structure") && text.contains("80 objects"),
        "{text}"
    );
}
