//! A healthy city passes; each kind of page damaged, and each structural lie told with
//! valid checksums, is found and named.

use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use super::*;
use crate::hdov::{HdovOptions, Scheme};
use crate::lod::LodOptions;
use crate::rtree::Node;
use crate::store::Segment;
use crate::visibility::VisibilityOptions;
use crate::BuildOptions;

/// A small city with every structure: LODs with progressive meshes, visibility, and an
/// HDoV-tree under all three schemes.
fn city(dir: &Path) -> PathBuf {
    let scene = dir.join("c.scene");
    let path = dir.join("c.flaneur");
    let config = citygen::CityConfig {
        objects: 40,
        seed: 4,
        ..Default::default()
    };
    citygen::write_city(&config, &scene).unwrap();
    let opts = BuildOptions {
        page_size: 1024,
        lod: Some(LodOptions {
            pm_threshold: 50,
            ..Default::default()
        }),
        visibility: Some(VisibilityOptions {
            cell_size: 12.0,
            resolution: 16,
            ..Default::default()
        }),
        hdov: Some(HdovOptions {
            schemes: vec![Scheme::Horizontal, Scheme::Vertical, Scheme::Indexed],
            ..Default::default()
        }),
        ..Default::default()
    };
    crate::build_from_scene(&scene, &path, &opts).unwrap();
    path
}

fn kinds(path: &Path) -> Vec<(u64, PageKind)> {
    let s = Store::open(path, Backend::Mmap).unwrap();
    (1..s.page_count())
        .map(|p| (p, s.read_any_page(p).unwrap().0))
        .collect()
}

/// Flips one byte of `page`'s payload.
fn flip(path: &Path, page: u64, page_size: u64) {
    let f = std::fs::OpenOptions::new()
        .write(true)
        .read(true)
        .open(path)
        .unwrap();
    let at = page * page_size + crate::store::PAGE_HEADER_LEN as u64 + 1;
    let mut b = [0u8];
    f.read_exact_at(&mut b, at).unwrap();
    f.write_all_at(&[b[0] ^ 0x10], at).unwrap();
}

#[test]
fn a_healthy_city_passes_and_every_page_is_claimed() {
    let dir = tempfile::tempdir().unwrap();
    let path = city(dir.path());
    let r = check(&path).unwrap();
    assert!(r.ok(), "{:#?}", r.problems);
    assert_eq!(r.objects, 40);
    assert!(r.unclaimed.is_empty(), "{:?}", r.unclaimed);
    assert!(r.page_reads >= r.pages - 1);
}

#[test]
fn each_kind_of_page_damaged_is_named_with_what_it_belongs_to() {
    let dir = tempfile::tempdir().unwrap();
    let healthy = city(dir.path());
    let all = kinds(&healthy);
    let expect: [(PageKind, &[&str]); 6] = [
        (PageKind::RtreeNode, &["r-tree node"]),
        (PageKind::Mesh, &["mesh of object"]),
        (PageKind::Lod, &["LOD", "progressive mesh", "DAG"]),
        (PageKind::Visibility, &["visibility table"]),
        (PageKind::HdovNode, &["HDoV"]),
        (PageKind::VPage, &["V-pages"]),
    ];
    for (kind, parts) in expect {
        // The first and the last page of the kind.
        let of_kind: Vec<u64> = all
            .iter()
            .filter(|(_, k)| *k == kind)
            .map(|p| p.0)
            .collect();
        assert!(!of_kind.is_empty(), "the city has {} pages", kind.name());
        for page in [of_kind[0], *of_kind.last().unwrap()] {
            let damaged = dir.path().join("damaged.flaneur");
            std::fs::copy(&healthy, &damaged).unwrap();
            flip(&damaged, page, 1024);
            let r = check(&damaged).unwrap();
            assert!(!r.ok(), "{} page {page}", kind.name());
            let p = &r.problems[0];
            assert_eq!(p.page, Some(page), "{:#?}", r.problems);
            assert!(p.what.contains("checksum"), "{p:?}");
            assert!(
                parts.iter().any(|w| p.part.contains(w)),
                "{} page {page} named as {:?}",
                kind.name(),
                p.part
            );
        }
    }
    // The header.
    let damaged = dir.path().join("damaged.flaneur");
    std::fs::copy(&healthy, &damaged).unwrap();
    flip(&damaged, 0, 1024);
    let r = check(&damaged).unwrap();
    assert_eq!(r.problems.len(), 1, "{:#?}", r.problems);
    assert_eq!(r.problems[0].page, Some(0));
    assert_eq!(r.problems[0].part, "the file header");
}

/// Rewrites the first leaf of the R-tree with `edit` applied to its entries, checksums
/// valid: lies only the structure can show.
fn edit_first_leaf(path: &Path, edit: impl FnOnce(&mut Vec<crate::ObjectEntry>)) -> u64 {
    let mut s = Store::open_writable(path, Backend::Pread { direct: false }).unwrap();
    let leaf = kinds(path)
        .into_iter()
        .filter(|(_, k)| *k == PageKind::RtreeNode)
        .find_map(|(p, _)| {
            match Node::decode(&s.read_page(p, PageKind::RtreeNode).unwrap()).unwrap() {
                Node::Leaf(e) if e.len() >= 2 => Some((p, e)),
                _ => None,
            }
        })
        .unwrap();
    let (page, mut entries) = leaf;
    edit(&mut entries);
    s.write_page(page, PageKind::RtreeNode, &Node::Leaf(entries).encode())
        .unwrap();
    s.finish().unwrap();
    page
}

#[test]
fn structural_lies_with_valid_checksums_are_found() {
    let dir = tempfile::tempdir().unwrap();
    let healthy = city(dir.path());
    let copy = |name: &str| {
        let p = dir.path().join(name);
        std::fs::copy(&healthy, &p).unwrap();
        p
    };
    let find = |r: &CheckReport, what: &str| {
        assert!(
            r.problems.iter().any(|p| p.what.contains(what)),
            "no problem says {what:?}: {:#?}",
            r.problems
        );
    };

    // A mesh extent past the end of the file.
    let p = copy("beyond.flaneur");
    let pages = Store::open(&p, Backend::Mmap).unwrap().page_count();
    edit_first_leaf(&p, |e| e[0].mesh.first_page = pages + 5);
    let r = check(&p).unwrap();
    find(&r, "do not lie among the file's data pages");
    assert!(r
        .problems
        .iter()
        .any(|q| q.part.starts_with("mesh of object")));

    // Two objects on one mesh.
    let p = copy("shared.flaneur");
    edit_first_leaf(&p, |e| {
        e[1].mesh = e[0].mesh;
        e[1].triangles = e[0].triangles;
    });
    find(
        &check(&p).unwrap(),
        "the page also belongs to mesh of object",
    );

    // A triangle count the mesh does not have.
    let p = copy("triangles.flaneur");
    edit_first_leaf(&p, |e| e[0].triangles += 1);
    find(&check(&p).unwrap(), "its leaf entry (page");

    // A leaf entry's box that does not hold its mesh.
    let p = copy("box.flaneur");
    edit_first_leaf(&p, |e| {
        e[0].bounds = crate::geom::Aabb::new([0.0; 3], [0.001; 3]).unwrap();
    });
    find(&check(&p).unwrap(), "outside the box");

    // An object count the tree does not hold.
    let p = copy("count.flaneur");
    let mut s = Store::open_writable(&p, Backend::Mmap).unwrap();
    let seg = s.header().segment("objects").unwrap().clone();
    s.set_segment(Segment {
        a: seg.a + 1,
        ..seg
    })
    .unwrap();
    s.finish().unwrap();
    find(&check(&p).unwrap(), "it counts 41 objects");
}

#[test]
fn what_is_not_a_database_is_a_report_and_a_missing_file_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("x");
    std::fs::write(&p, vec![7u8; 5000]).unwrap();
    let r = check(&p).unwrap();
    assert_eq!(r.problems.len(), 1);
    assert!(
        r.problems[0].what.contains("not a flaneur database"),
        "{:?}",
        r.problems
    );
    assert!(matches!(
        check(&dir.path().join("missing")),
        Err(Error::Io { .. })
    ));
}

#[test]
fn an_imported_citys_names_are_checked_and_a_bad_offset_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("two.obj");
    let tetra = |x: f32| format!("v {x} 0 0\nv {} 0 0\nv {x} 1 0\nv {x} 0 1\n", x + 1.0);
    let faces = |b: u32| {
        format!(
            "f {} {} {}\nf {} {} {}\nf {} {} {}\nf {} {} {}\n",
            b,
            b + 2,
            b + 1,
            b,
            b + 1,
            b + 3,
            b,
            b + 3,
            b + 2,
            b + 1,
            b + 2,
            b + 3
        )
    };
    let text = format!(
        "o left\n{}{}o right\n{}{}",
        tetra(0.0),
        faces(1),
        tetra(10.0),
        faces(5)
    );
    std::fs::write(&obj, text).unwrap();
    let path = dir.path().join("two.flaneur");
    let opts = BuildOptions {
        page_size: 1024,
        lod: None,
        ..Default::default()
    };
    crate::build_from_obj(&[obj], &path, &opts).unwrap();
    let db = crate::Database::open(&path).unwrap();
    assert_eq!(db.object_name(1).unwrap().as_deref(), Some("right"));
    drop(db);
    let report = check(&path).unwrap();
    assert!(report.ok(), "{:?}", report.problems);
    assert!(report.unclaimed.is_empty(), "{:?}", report.unclaimed);

    // Name 1 said to end past the text, the page's checksum made to match.
    let mut s = Store::open_writable(&path, Backend::Pread { direct: false }).unwrap();
    let (extent, _) = s
        .segment_extent(crate::names::NAMES_SEGMENT, |_, _| Ok(()))
        .unwrap()
        .unwrap();
    let mut page = s.read_page(extent.first_page, PageKind::Meta).unwrap();
    page[16 + 16..16 + 24].copy_from_slice(&999u64.to_le_bytes());
    s.write_page(extent.first_page, PageKind::Meta, &page)
        .unwrap();
    s.finish().unwrap();
    let report = check(&path).unwrap();
    let found = report
        .problems
        .iter()
        .find(|p| p.part == "the object names")
        .unwrap();
    assert!(found.what.contains("name 1 at bytes"), "{found:?}");
    assert_eq!(found.page, Some(extent.first_page));
}

#[test]
fn packed_extents_share_pages_and_overlapping_claims_are_found() {
    use super::claims::Claims;
    use crate::store::Extent;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.db");
    let mut s = Store::create(&path, 1024).unwrap();
    let p = s.payload_size();
    let m = PageKind::Mesh;
    let a = s.append_packed(m, &[1; 100]).unwrap(); // page 1, bytes 0..100
    let b = s.append_packed(m, &vec![2; 2 * p]).unwrap(); // pages 1..=3, to byte 100 of 3
    let c = s.append_packed(m, &[3; 50]).unwrap(); // page 3, bytes 100..150
    let whole = s.append_extent(m, &[4; 10]).unwrap(); // page 4
    assert_eq!(
        (b.first_page, b.page_count, c.first_page, c.offset),
        (1, 3, 3, 100)
    );
    s.finish().unwrap();
    let s = Store::open(&path, Backend::Mmap).unwrap();
    let claimed = || {
        let mut claims = Claims::scan(&s);
        for (i, e) in [a, b, c, whole].iter().enumerate() {
            assert!(claims.claim_extent(e, m, &format!("blob {i}")));
        }
        claims
    };
    let claims = claimed();
    assert!(claims.unclaimed().is_empty());
    assert!(claims.into_problems().is_empty());
    let packed = |first_page, offset, byte_len| Extent {
        first_page,
        page_count: 1,
        byte_len,
        offset,
        packed: true,
    };
    // The free bytes after the last blob of page 3 may be claimed.
    let mut claims = claimed();
    assert!(claims.claim_extent(&packed(3, 150, 10), m, "more"));
    assert!(claims.into_problems().is_empty());
    let cases = [
        (
            packed(1, 60, 100),
            m,
            "the page also belongs to blob 0 (over bytes 60..160)",
        ),
        (
            packed(3, 110, 10),
            m,
            "the page also belongs to blob 2 (over bytes 110..120)",
        ),
        (
            packed(3, 90, 5),
            m,
            "also belongs to blob 1 (over bytes 90..95)",
        ),
        (
            packed(4, 20, 5),
            m,
            "also belongs to blob 3 (over bytes 20..25)",
        ),
        (
            Extent {
                packed: false,
                offset: 0,
                ..packed(3, 0, 10)
            },
            m,
            "the page also belongs to blob 1",
        ),
        (packed(3, 150, 10), PageKind::Lod, "page where a"),
        (
            Extent {
                offset: p as u32,
                ..a
            },
            m,
            "packed extent of 100 bytes starts at byte",
        ),
        (Extent { page_count: 2, ..a }, m, "needs 1 pages"),
        (
            packed(9, 0, 10),
            m,
            "do not lie among the file's data pages",
        ),
    ];
    for (bad, kind, says) in cases {
        let mut claims = claimed();
        claims.claim_extent(&bad, kind, "bad");
        let problems = claims.into_problems();
        assert_eq!(problems.len(), 1, "{bad:?}: {problems:?}");
        assert_eq!(problems[0].part, "bad");
        assert!(problems[0].what.contains(says), "{bad:?}: {problems:?}");
    }
}
