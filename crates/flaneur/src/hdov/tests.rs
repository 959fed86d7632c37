//! The HDoV-tree built into a small city's database and searched: every scheme gives
//! the same answers, η = 0 gives exactly the PVS, a larger η stops at internal LODs and
//! reads less, the schemes' sizes order as the thesis's, and damage is named.

use std::collections::BTreeSet;
use std::sync::OnceLock;

use super::node::HNodeKind;
use super::*;
use crate::error::Error;
use crate::visibility::VisibilityOptions;
use crate::{BuildOptions, BuildSummary, Database};

/// One small city with every scheme, built once for the tests here: 1 KiB pages, so
/// that its 500 objects make a tree of three levels, most of it hidden from any cell.
fn city() -> &'static (tempfile::TempDir, BuildSummary) {
    static CITY: OnceLock<(tempfile::TempDir, BuildSummary)> = OnceLock::new();
    CITY.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("c.scene");
        let config = citygen::CityConfig {
            objects: 500,
            seed: 11,
            landmarks: 0.01,
            ..Default::default()
        };
        citygen::write_city(&config, &scene).unwrap();
        let opts = BuildOptions {
            page_size: 1024,
            visibility: Some(VisibilityOptions {
                resolution: 24,
                ..Default::default()
            }),
            hdov: Some(HdovOptions::default()),
            ..Default::default()
        };
        let built = crate::build_from_scene(&scene, &dir.path().join("c.flaneur"), &opts).unwrap();
        (dir, built)
    })
}

fn open() -> Database {
    Database::open(&city().0.path().join("c.flaneur")).unwrap()
}

#[test]
fn the_tree_has_internal_lods_below_its_childrens_faces() {
    let report = city().1.hdov.as_ref().expect("built with an HDoV-tree");
    assert!(report.height >= 3, "{report:?}");
    assert!(
        report.nodes_with_lods > 0 && report.lod_pages > 0,
        "{report:?}"
    );
    let db = open();
    let tree = db.hdov_tree().unwrap();
    let root = tree.node(db.store(), 0).unwrap();
    let HNodeKind::Internal { children, .. } = &root.kind else {
        panic!("the root of a three-level tree is internal");
    };
    for c in children {
        assert!(c.s > 0.0 && c.s < 1.0, "{c:?}");
        assert!(c.h > 0.0 && c.objects > 1, "{c:?}");
        assert!(!c.lods.is_empty(), "{c:?}");
    }
    let below: u32 = children.iter().map(|c| c.objects).sum();
    assert_eq!(below as u64, db.objects());
}

#[test]
fn eta_zero_finds_exactly_each_cells_pvs_under_every_scheme() {
    let db = open();
    let cells = db.hdov().unwrap().unwrap().cells.clone();
    assert!(cells.len() > 5, "{} cells", cells.len());
    for &cell in &cells {
        let pvs = db.pvs(cell).unwrap().unwrap();
        let want: BTreeSet<u64> = pvs.ids.iter().copied().collect();
        for scheme in Scheme::ALL {
            let r = db.hdov_search_with(cell, 0.0, scheme).unwrap();
            assert_eq!(r.internal(), 0, "cell {cell}, {scheme:?}");
            let got: BTreeSet<u64> = r.objects().map(|o| o.id).collect();
            assert_eq!(got, want, "cell {cell}, {scheme:?}");
            assert_eq!(r.found.len(), want.len());
            for f in &r.found {
                let Found::Object { entry, dov, .. } = f else {
                    unreachable!()
                };
                let k = pvs.ids.binary_search(&entry.id).unwrap();
                assert_eq!(*dov, pvs.dov[k]);
            }
        }
    }
}

#[test]
fn a_larger_eta_stops_at_internal_lods_and_reads_less() {
    let db = open();
    let cells = db.hdov().unwrap().unwrap().cells.clone();
    let (mut stopped, mut total) = (0, [0u64; 2]);
    for &cell in &cells {
        let results: Vec<_> = Scheme::ALL
            .iter()
            .map(|&s| db.hdov_search_with(cell, 0.05, s).unwrap())
            .collect();
        // The schemes store the same VDs: the same answer, node by node.
        assert!(
            results.windows(2).all(|w| w[0].found == w[1].found),
            "cell {cell}"
        );
        let fine = db.hdov_search(cell, 0.0).unwrap();
        let coarse = &results[0];
        assert!(coarse.nodes_read <= fine.nodes_read);
        stopped += coarse.internal();
        total[0] += fine.nodes_read + fine.vpages_read;
        total[1] += coarse.nodes_read + coarse.vpages_read;
        // What a node found at an internal LOD stands for is not found again.
        let seen: u32 = coarse
            .found
            .iter()
            .map(|f| match f {
                Found::Node { nvo, .. } => *nvo,
                Found::Object { .. } => 1,
            })
            .sum();
        assert_eq!(seen as usize, fine.found.len(), "cell {cell}");
    }
    assert!(stopped > 0, "no search stopped at an internal LOD");
    assert!(
        total[1] < total[0],
        "η 0.05 read {} nodes and V-pages, η 0 {}",
        total[1],
        total[0]
    );
}

#[test]
fn each_scheme_takes_what_its_equation_says() {
    let report = city().1.hdov.as_ref().unwrap();
    let of = |s: Scheme| report.schemes.iter().find(|r| r.scheme == s).unwrap();
    let (n, c, nv) = (
        report.nodes as u64,
        report.cells as u64,
        report.visible_nodes,
    );
    assert!(nv >= c && nv < n * c, "{report:?}");
    // Eqs. 5.7–5.9 exactly, with each extent's 44-byte head and the indexed scheme's
    // directory of 12 bytes a cell beside them.
    assert_eq!(
        of(Scheme::Horizontal).bytes,
        of(Scheme::Horizontal).estimate_bytes + 44
    );
    assert_eq!(
        of(Scheme::Vertical).bytes,
        of(Scheme::Vertical).estimate_bytes + 44
    );
    assert_eq!(
        of(Scheme::Indexed).bytes,
        of(Scheme::Indexed).estimate_bytes + 44 + 12 * c
    );
    assert_eq!(of(Scheme::Horizontal).vpages, n * c);
    assert_eq!(of(Scheme::Vertical).vpages, nv);
    assert_eq!(of(Scheme::Indexed).vpages, nv);
    // The vertical schemes save the hidden nodes' V-pages; the indexed one's pairs
    // (8 bytes a visible node) beat the vertical's full segments (4 bytes a node) only
    // where fewer than half the nodes are visible from a cell, which a city this small
    // does not show (its cells see most of it): the bench's larger cities do.
    assert!(of(Scheme::Vertical).bytes < of(Scheme::Horizontal).bytes);
    assert_eq!(
        of(Scheme::Indexed).bytes < of(Scheme::Vertical).bytes,
        8 * nv + 12 * c < 4 * n * c
    );
}

#[test]
fn a_damaged_vpage_is_named_by_its_page() {
    let (dir, _) = city();
    let copy = dir.path().join("damaged.flaneur");
    std::fs::copy(dir.path().join("c.flaneur"), &copy).unwrap();
    let db = Database::open(&copy).unwrap();
    let tree = db.hdov_tree().unwrap();
    let indexed = tree.scheme(db.store(), Scheme::Indexed).unwrap().extent;
    let cell = db.hdov().unwrap().unwrap().cells[0];
    let page_size = db.store().page_size() as u64;
    drop(db);
    // The last page of the scheme's extent holds V-pages.
    let page = indexed.first_page + indexed.page_count as u64 - 1;
    let mut bytes = std::fs::read(&copy).unwrap();
    bytes[(page * page_size + 40) as usize] ^= 0x5a;
    std::fs::write(&copy, &bytes).unwrap();
    let db = Database::open(&copy).unwrap();
    let mut named = false;
    for &cell in &db.hdov().unwrap().unwrap().cells.clone() {
        match db.hdov_search_with(cell, 0.0, Scheme::Indexed) {
            Ok(_) => {}
            Err(Error::CorruptPage { page: p, .. }) => {
                assert_eq!(p, page);
                named = true;
            }
            Err(e) => panic!("{e}"),
        }
    }
    assert!(named, "no search read the damaged page");
    // The other schemes are untouched.
    db.hdov_search_with(cell, 0.0, Scheme::Vertical).unwrap();
}

#[test]
fn a_database_without_the_tree_or_a_bad_eta_says_so() {
    let db = open();
    let cell = db.hdov().unwrap().unwrap().cells[0];
    let e = db.hdov_search(cell, f32::NAN).unwrap_err();
    assert!(e.to_string().contains("threshold"), "{e}");
    let e = db.hdov_search(u32::MAX, 0.0).unwrap_err();
    assert!(e.to_string().contains("not a walkable cell"), "{e}");
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.scene");
    citygen::write_city(
        &citygen::CityConfig {
            objects: 10,
            ..Default::default()
        },
        &scene,
    )
    .unwrap();
    let opts = BuildOptions {
        hdov: Some(HdovOptions::default()),
        ..Default::default()
    };
    let e = crate::build_from_scene(&scene, &dir.path().join("s.flaneur"), &opts).unwrap_err();
    assert!(e.to_string().contains("--visibility"), "{e}");
    crate::build_from_scene(
        &scene,
        &dir.path().join("t.flaneur"),
        &BuildOptions::default(),
    )
    .unwrap();
    let plain = Database::open(&dir.path().join("t.flaneur")).unwrap();
    assert!(plain.hdov().unwrap().is_none());
    let e = plain.hdov_search(0, 0.0).unwrap_err();
    assert!(e.to_string().contains("no HDoV-tree"), "{e}");
}

#[test]
fn what_a_search_finds_loads_at_its_detail() {
    let db = open();
    let cells = db.hdov().unwrap().unwrap().cells.clone();
    let (mut nodes, mut objects) = (0, 0);
    for &cell in cells.iter().step_by(7) {
        for f in db.hdov_search(cell, 0.05).unwrap().found {
            let rep = db.hdov_load(&f).unwrap();
            assert!(rep.mesh.triangle_count() > 0);
            match f {
                Found::Node { .. } => {
                    // An internal LOD: levels count from 1.
                    assert!(rep.level >= 1);
                    nodes += 1;
                }
                Found::Object { entry, detail, .. } => {
                    assert!(rep.mesh.triangle_count() <= entry.triangles as usize);
                    // The level eq. 5.6 picks: barely visible objects come coarse.
                    let levels = db.lod_levels(entry.id).unwrap().unwrap();
                    let t: Vec<u32> = levels.iter().map(|l| l.triangles).collect();
                    assert_eq!(
                        rep.level,
                        level_for_detail(&t, detail),
                        "object {}",
                        entry.id
                    );
                    assert_eq!(rep.mesh.triangle_count(), t[rep.level] as usize);
                    if detail < 0.05 {
                        assert!(rep.level > 0, "object {} at detail {detail}", entry.id);
                    }
                    objects += 1;
                }
            }
        }
    }
    assert!(nodes > 0 && objects > 0, "{nodes} nodes, {objects} objects");
}

#[test]
fn a_node_cache_serves_the_same_answers_and_saves_node_reads() {
    use crate::cache::{policy_by_name, BufferPool};
    use crate::store::PageKind;
    let db = open();
    let head = db.hdov().unwrap().unwrap().clone();
    let cache = BufferPool::new(
        db.store(),
        head.nodes as usize * db.store().page_size(),
        policy_by_name("dovtime").unwrap(),
    )
    .unwrap();
    let cells: Vec<u32> = head.cells.iter().copied().step_by(5).collect();
    for round in 0..2 {
        let before = db.io();
        for &cell in &cells {
            let plain = db.hdov_search_with(cell, 0.0005, Scheme::Indexed).unwrap();
            let cached = db
                .hdov_search_cached(cell, 0.0005, Scheme::Indexed, Some(&cache))
                .unwrap();
            assert_eq!(plain, cached, "cell {cell}");
        }
        let io = db.io().since(&before);
        let stats = cache.stats();
        if round == 1 {
            // The whole tree fits: the second round reads no node through the cache,
            // so its node pages are the plain searches' alone.
            let plain_nodes: u64 = cells
                .iter()
                .map(|&c| {
                    db.hdov_search_with(c, 0.0005, Scheme::Indexed)
                        .unwrap()
                        .nodes_read
                })
                .sum();
            assert_eq!(io.reads_of(PageKind::HdovNode), plain_nodes);
            assert!(stats.hit_rate() > 0.5, "{stats:?}");
        }
    }
}

#[test]
fn a_batch_of_finds_reads_the_same_meshes_and_pages_as_one_at_a_time() {
    let db = open();
    let cells = db.hdov().unwrap().unwrap().cells.clone();
    for &cell in cells.iter().step_by(11) {
        let found = db.hdov_search(cell, 0.05).unwrap().found;
        // What the database keeps once read (the LOD table's head, a version-2 file's
        // zstd dictionaries) read before either.
        db.store().dictionaries().unwrap();
        let mut warm = db.hdov_loader();
        for f in &found {
            warm.level(f).unwrap();
        }
        // One find at a time, as the waiting walk reads them.
        db.reset_io();
        let mut one = db.hdov_loader();
        let mut alone = Vec::new();
        for f in &found {
            let (fine, coarse) = (one.level(f).unwrap(), one.coarsest(f).unwrap());
            assert!(coarse >= fine, "the coarsest level is the largest number");
            alone.push((one.mesh(f, fine).unwrap(), one.mesh(f, coarse).unwrap()));
        }
        let pages_alone = db.io().page_reads;
        // As a batch: levels learnt together, then each level's meshes together.
        db.reset_io();
        let mut batch = db.hdov_loader();
        batch.learn(&found);
        let levels: Vec<(usize, usize)> = found
            .iter()
            .map(|f| (batch.level(f).unwrap(), batch.coarsest(f).unwrap()))
            .collect();
        let fine: Vec<_> = found.iter().zip(&levels).map(|(f, l)| (f, l.0)).collect();
        let coarse: Vec<_> = found.iter().zip(&levels).map(|(f, l)| (f, l.1)).collect();
        let together: Vec<_> = batch
            .meshes(&fine)
            .into_iter()
            .zip(batch.meshes(&coarse))
            .map(|(a, b)| (a.unwrap(), b.unwrap()))
            .collect();
        assert_eq!(together, alone, "cell {cell}");
        assert_eq!(db.io().page_reads, pages_alone, "cell {cell}");
    }
}
