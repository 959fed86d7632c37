//! Stored LODs end to end: `flaneur build` keeps each object's chain of coarse levels
//! (and, above a threshold, its progressive mesh and DAG), and the database reads them
//! back by object id — every level valid, a coarse level cheap, damage named.

mod common;

use common::flaneur;

use std::os::unix::fs::FileExt;
use std::path::Path;

use flaneur::lod::{LodOptions, ProgressiveMesh};
use flaneur::scene::MeshCodec;
use flaneur::store::{IoStats, PageKind, PAGE_HEADER_LEN};
use flaneur::{BuildOptions, Database, Error, ObjectEntry};

const PAGE: usize = 4096;

fn with_lods(lod: LodOptions) -> BuildOptions {
    BuildOptions {
        lod: Some(lod),
        ..Default::default()
    }
}

/// Every object of the database, from a range query over its bounds.
/// The default build but with format version 1's raw meshes, whole pages each.
fn raw_codec() -> BuildOptions {
    BuildOptions {
        codec: MeshCodec::Raw,
        ..Default::default()
    }
}

fn all_objects(db: &Database) -> Vec<ObjectEntry> {
    let mut all = db.range(&db.bounds()).unwrap().objects;
    all.sort_by_key(|o| o.id);
    all
}

#[test]
fn every_stored_level_is_a_valid_mesh_of_its_stated_size() {
    let city = common::city(120, 3, &BuildOptions::default());
    let db = Database::open(&city.db).unwrap();
    assert!(db.has_lods());
    let stats = db.lod_stats().unwrap().unwrap();
    assert_eq!(stats.objects + stats.refused, 120);
    assert_eq!(stats.refused, 0);
    assert!(stats.with_levels > 100, "{stats:?}");
    assert_eq!(db.pages_by_kind().lod, stats.pages);
    let info = db.info().unwrap();
    assert_eq!(info.lod, Some(stats));
    let k = info.pages_by_kind;
    assert_eq!(1 + k.rtree + k.mesh + k.meta + k.lod, info.pages);

    let objects = all_objects(&db);
    let mut levels_seen = 0;
    for o in objects.iter().step_by(7) {
        let levels = db.lod_levels(o.id).unwrap().expect("every object has LODs");
        assert_eq!(levels[0].level, 0);
        assert_eq!(levels[0].triangles, o.triangles);
        assert_eq!(levels[0].error, 0.0);
        for w in levels.windows(2) {
            assert!(w[1].triangles < w[0].triangles, "{levels:?}");
            assert!(
                w[1].error >= w[0].error,
                "error grows coarse-ward: {levels:?}"
            );
        }
        for l in &levels {
            let m = db.lod_mesh(o.id, l.level).unwrap();
            assert_eq!(m.triangle_count(), l.triangles as usize, "object {}", o.id);
            m.validate().unwrap();
            // A level lies where its object does.
            let (lo, hi) = m.bounds();
            assert!(o.bounds.contains_point(lo.into()) && o.bounds.contains_point(hi.into()));
        }
        assert_eq!(db.lod_mesh(o.id, 0).unwrap(), db.mesh(o).unwrap());
        let e = db.lod_mesh(o.id, levels.len()).unwrap_err();
        assert!(matches!(e, Error::Invalid(_)), "{e}");
        levels_seen += levels.len() - 1;
    }
    assert!(levels_seen > 20);
    assert!(db.lod_levels(1 << 40).unwrap().is_none());
    assert!(
        db.progressive(objects[0].id).unwrap().is_none(),
        "below the threshold"
    );
}

/// What reading the largest object of a 60-object city built in `codec` costs: at full
/// detail, at its coarsest level and at level 1. Also its entry and levels.
fn level_reads(codec: MeshCodec) -> (ObjectEntry, Vec<flaneur::lod::LevelInfo>, [IoStats; 3]) {
    let opts = BuildOptions {
        codec,
        ..Default::default()
    };
    let city = common::city(60, 5, &opts);
    let db = Database::open(&city.db).unwrap();
    let big = *all_objects(&db).iter().max_by_key(|o| o.triangles).unwrap();
    let levels = db.lod_levels(big.id).unwrap().unwrap();
    db.lod_stats().unwrap(); // the table's head is read once per open database
    db.store().dictionaries().unwrap(); // as are the zstd dictionaries (version 2)
    let reads = |f: &dyn Fn()| {
        db.reset_io();
        f();
        db.io()
    };
    let full = reads(&|| {
        db.mesh(&big).unwrap();
    });
    let coarsest = reads(&|| {
        db.lod_mesh(big.id, levels.len() - 1).unwrap();
    });
    let finest = reads(&|| {
        db.lod_mesh(big.id, 1).unwrap();
    });
    (big, levels, [full, coarsest, finest])
}

#[test]
fn a_coarse_level_reads_fewer_pages_than_the_full_mesh() {
    // Format version 1: each level a mesh of its own in the chain, whole pages.
    let (big, levels, [full, coarsest, finest]) = level_reads(MeshCodec::Raw);
    eprintln!(
        "object {} ({} triangles, {} levels): full mesh {} pages; coarsest level ({} triangles) {} pages ({} LOD); level 1 ({} triangles) {} pages",
        big.id,
        big.triangles,
        levels.len(),
        full.page_reads,
        levels.last().unwrap().triangles,
        coarsest.page_reads,
        coarsest.reads_of(PageKind::Lod),
        levels[1].triangles,
        finest.page_reads
    );
    assert!(full.page_reads >= 4, "{full:?}");
    // The table's entry page and the chain's first pages (its directory and the
    // coarsest level), nothing of the full mesh and nothing of the finer levels.
    assert_eq!(coarsest.reads_of(PageKind::Lod), coarsest.page_reads);
    assert!(coarsest.page_reads < full.page_reads, "{coarsest:?}");
    assert!(coarsest.page_reads < finest.page_reads, "{coarsest:?}");
    assert!(finest.page_reads < full.page_reads + 2);
}

#[test]
fn a_coarse_level_of_a_packed_file_reads_its_chain_alone() {
    // Format version 2: chains packed several to a page, the levels sharing one vertex
    // buffer, coarsest first, so that a coarse level reads the chain's first bytes.
    let (_, _, [full, coarsest, finest]) = level_reads(MeshCodec::meshopt());
    assert_eq!(
        coarsest.reads_of(PageKind::Lod),
        coarsest.page_reads,
        "{coarsest:?}"
    );
    assert!(
        coarsest.page_reads <= finest.page_reads,
        "{coarsest:?} {finest:?}"
    );
    assert_eq!(full.reads_of(PageKind::Mesh), full.page_reads, "{full:?}");
}

/// Object `id`'s mesh as the scene file holds it (what the build simplified).
fn scene_mesh(city: &common::City, id: u64) -> flaneur::scene::Mesh {
    citygen::SceneReader::open(&city.scene)
        .unwrap()
        .map(|o| o.unwrap())
        .find(|o| o.id == id)
        .unwrap()
        .mesh
}

#[test]
fn objects_above_the_threshold_keep_a_progressive_mesh_that_refines_back_exactly() {
    // Raw meshes: the stored mesh is the input's, vertex for vertex, as the progressive
    // mesh refines back to it (format version 2 stores it quantised and reordered).
    let threshold = 800;
    let city = common::city(
        40,
        7,
        &BuildOptions {
            codec: MeshCodec::Raw,
            ..with_lods(LodOptions {
                pm_threshold: threshold,
                ..Default::default()
            })
        },
    );
    let db = Database::open(&city.db).unwrap();
    let stats = db.lod_stats().unwrap().unwrap();
    assert_eq!(stats.pm_threshold, threshold as u64);
    let mut checked = 0;
    for o in all_objects(&db) {
        let Some((pm, dag)) = db.progressive(o.id).unwrap() else {
            assert!(o.triangles as usize <= threshold, "object {}", o.id);
            continue;
        };
        assert!(o.triangles as usize > threshold);
        checked += 1;
        let mesh = db.mesh(&o).unwrap();
        let full = pm.cursor_at(pm.splits.len()).unwrap();
        assert_eq!(full.triangle_count(), mesh.triangle_count());
        assert_eq!(full.to_mesh().triangle_count(), o.triangles as usize);
        // Through the renumbering, the refined mesh is the stored one, exactly.
        let sm = full.mesh();
        for (v, p) in mesh.positions.iter().enumerate() {
            assert_eq!(sm.positions()[pm.vertex_map[v] as usize], *p, "vertex {v}");
        }
        for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
            let expect = [tri[0], tri[1], tri[2]].map(|v| pm.vertex_map[v as usize]);
            assert_eq!(
                sm.slots()[pm.triangle_map[t] as usize],
                expect,
                "triangle {t}"
            );
        }
        // The stored progressive mesh is the one the LOD core builds from the scene's
        // mesh, bit for bit, and its DAG the one it builds from that.
        assert_eq!(
            pm,
            ProgressiveMesh::build(&scene_mesh(&city, o.id)).unwrap()
        );
        let again =
            flaneur::lod::Dag::build(&pm, flaneur::lod::DagConstruction::MiniRedundant).unwrap();
        assert_eq!(dag, again);
        assert_eq!(flaneur::lod::Dag::from_bytes(&dag.to_bytes()).unwrap(), dag);
        flaneur::lod::Refiner::new(&pm, &dag).unwrap();
    }
    assert!(
        checked >= 3,
        "{checked} objects above {threshold} triangles"
    );
    assert_eq!(stats.with_pm, checked);
}

#[test]
fn a_database_built_without_lods_opens_and_says_so() {
    let city = common::city(
        50,
        2,
        &BuildOptions {
            lod: None,
            ..Default::default()
        },
    );
    let db = Database::open(&city.db).unwrap();
    assert!(!db.has_lods());
    assert_eq!(db.lod_stats().unwrap(), None);
    assert_eq!(db.pages_by_kind().lod, 0);
    assert_eq!(db.info().unwrap().lod, None);
    let o = all_objects(&db)[0];
    assert!(db.lod_levels(o.id).unwrap().is_none());
    assert!(db.progressive(o.id).unwrap().is_none());
    let e = db.lod_mesh(o.id, 0).unwrap_err().to_string();
    assert!(e.contains("no LOD data"), "{e}");
    // Nor does the file hold a single LOD page.
    let bytes = std::fs::read(&city.db).unwrap();
    assert!(bytes
        .chunks(PAGE)
        .skip(1)
        .all(|p| p[0] != PageKind::Lod as u8));

    let out = flaneur(&["info", city.db.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("lods        none"),
        "{text}"
    );
}

/// Damages the first page of object `id`'s chain, past its header; that page.
fn damage_chain(db: &Path, id: u64) -> u64 {
    let page = common::lod_chain_page(db, id);
    let file = std::fs::OpenOptions::new().write(true).open(db).unwrap();
    file.write_all_at(&[0x77], page * PAGE as u64 + PAGE_HEADER_LEN as u64 + 200)
        .unwrap();
    page
}

#[test]
fn a_damaged_lod_page_is_an_error_naming_the_page_and_the_object() {
    // One chain to a page (format version 1), so that the damage is one object's: a
    // damaged page of packed meshes costs each of its objects (tests/bad_input.rs).
    let city = common::city(30, 4, &raw_codec());
    let db = Database::open(&city.db).unwrap();
    let objects = all_objects(&db);
    let victim = objects[5];
    let coarsest = db.lod_levels(victim.id).unwrap().unwrap().len() - 1;
    drop(db);
    let page = damage_chain(&city.db, victim.id);

    let db = Database::open(&city.db).unwrap();
    for e in [
        db.lod_mesh(victim.id, coarsest).unwrap_err(),
        db.lod_levels(victim.id).unwrap_err(),
    ] {
        match &e {
            Error::CorruptPage { page: p, what, .. } => {
                assert_eq!(*p, page, "{e}");
                assert!(what.contains(&format!("object {}", victim.id)), "{e}");
                assert!(what.contains("checksum"), "{e}");
            }
            other => panic!("expected a corrupt page, got {other}"),
        }
    }
    // Its full mesh and every other object's LODs still read.
    db.lod_mesh(victim.id, 0).unwrap();
    for o in objects.iter().filter(|o| o.id != victim.id) {
        let levels = db.lod_levels(o.id).unwrap().unwrap();
        db.lod_mesh(o.id, levels.len() - 1).unwrap();
    }
}

#[test]
fn a_mesh_the_simplifier_refuses_gets_no_lods_and_is_counted() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("odd.scene");
    let db_path = dir.path().join("odd.flaneur");
    let config = citygen::CityConfig {
        objects: 12,
        landmarks: 0.0,
        ..Default::default()
    };
    let mut w = citygen::SceneWriter::create(&scene).unwrap();
    for id in 0..12 {
        let mut o = citygen::object(&config, id).unwrap();
        if id == 7 {
            // Points without triangles: a valid mesh with nothing to simplify.
            o.mesh.indices.clear();
        }
        w.write(&o).unwrap();
    }
    w.finish().unwrap();
    let summary = flaneur::build_from_scene(&scene, &db_path, &BuildOptions::default()).unwrap();
    let lod = summary.lod.unwrap();
    assert_eq!((lod.stats.objects, lod.stats.refused), (11, 1));
    let why = lod.first_refusal.unwrap();
    assert!(
        why.contains("object 7") && why.contains("no triangles"),
        "{why}"
    );

    let db = Database::open(&db_path).unwrap();
    assert_eq!(db.objects(), 12);
    assert_eq!(db.lod_stats().unwrap().unwrap().refused, 1);
    assert!(db.lod_levels(7).unwrap().is_none());
    assert!(db.lod_levels(6).unwrap().is_some());
    let out = flaneur(&["info", db_path.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("refused   1 objects"), "{text}");
}

#[test]
fn inserted_objects_have_no_lods_and_the_others_keep_theirs() {
    let city = common::city(25, 6, &BuildOptions::default());
    let mut db = Database::open_writable(&city.db, flaneur::Backend::Mmap).unwrap();
    let before = db.lod_stats().unwrap();
    let mesh = db.lod_mesh(3, 0).unwrap();
    db.insert(1_000, &mesh).unwrap();
    drop(db);
    let db = Database::open(&city.db).unwrap();
    assert_eq!(db.objects(), 26);
    assert_eq!(db.lod_stats().unwrap(), before);
    assert!(db.lod_levels(1_000).unwrap().is_none());
    let levels = db.lod_levels(3).unwrap().unwrap();
    db.lod_mesh(3, levels.len() - 1).unwrap();
}

#[test]
fn the_cli_builds_lods_by_default_and_takes_its_options() {
    let city = common::city(
        40,
        8,
        &BuildOptions {
            lod: None,
            ..Default::default()
        },
    );
    let scene = city.scene.to_str().unwrap();
    let with = city.dir.path().join("with.flaneur");
    let out = flaneur(&[
        "build",
        scene,
        "--out",
        with.to_str().unwrap(),
        "-q",
        "--pm-threshold",
        "900",
        "--codec",
        "meshopt",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("LODs: 40 objects simplified"), "{text}");
    let out = flaneur(&["info", with.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("PM + DAG above 900 triangles"), "{text}");
    assert!(text.contains(", lod "), "{text}");
    let out = flaneur(&["info", with.to_str().unwrap(), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["lod"]["objects"], 40);
    assert_eq!(v["lod"]["pm_threshold"], 900);
    // Chains packed several to a page (format version 2, the default), in fewer pages
    // than raw floats take (below).
    let lod_pages = v["pages_by_kind"]["lod"].as_u64().unwrap();
    assert!(lod_pages > 0, "{lod_pages}");
    assert!(v["bytes_per_triangle"]["lod"].as_f64().unwrap() > 0.0);
    assert_eq!(v["format_version"], 2);
    assert!(
        text.contains(
            "codec       meshoptimizer's, zstd level 9, with dictionaries trained on the city ("
        ) && text.contains(" KiB) (format version 2)"),
        "{text}"
    );
    // Format version 1's raw meshes, still written when asked for: a chain or more to a
    // page.
    let raw = city.dir.path().join("raw.flaneur");
    let out = flaneur(&[
        "build",
        scene,
        "--out",
        raw.to_str().unwrap(),
        "-q",
        "--codec",
        "raw",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = flaneur(&["info", raw.to_str().unwrap(), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["pages_by_kind"]["lod"].as_u64().unwrap() > 2 * lod_pages);
    assert_eq!(v["format_version"], 1);
    assert_eq!(v["codec"], "Raw");

    let without = city.dir.path().join("without.flaneur");
    let out = flaneur(&[
        "build",
        scene,
        "--out",
        without.to_str().unwrap(),
        "-q",
        "--no-lod",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("LODs: none"),
        "{text}"
    );
    let (a, b) = (
        std::fs::metadata(&raw).unwrap().len(),
        std::fs::metadata(&without).unwrap().len(),
    );
    assert!(a > b, "{a} vs {b}");
}

#[test]
fn builds_are_deterministic_and_finish_inside_a_one_thread_pool() {
    let city = common::city(
        30,
        9,
        &BuildOptions {
            lod: None,
            ..Default::default()
        },
    );
    let opts = with_lods(LodOptions {
        batch: 4,
        pm_threshold: 1500,
        ..Default::default()
    });
    let (a, b) = (
        city.dir.path().join("a.flaneur"),
        city.dir.path().join("b.flaneur"),
    );
    flaneur::build_from_scene(&city.scene, &a, &opts).unwrap();
    // A build run from a pool thread must not wait on tasks that need that thread.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| flaneur::build_from_scene(&city.scene, &b, &opts))
        .unwrap();
    assert!(std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap());
    let db = Database::open(&b).unwrap();
    assert_eq!(db.lod_stats().unwrap().unwrap().objects, 30);
}

/// A large object is drawn at its discrete levels in the frames its progressive mesh and
/// DAG spend decoding on the thread pool, and refined from the frame after they are
/// done; the frame that first sees it reads them, and never waits for them.
/// Every object of `db` loaded into an object buffer, as a walk would hold them.
fn all_loaded(db: &Database) -> flaneur::walk::ObjectBuffer {
    use flaneur::walk::{Loaded, ObjectBuffer};
    let mut buffer = ObjectBuffer::new(usize::MAX);
    for o in all_objects(db) {
        let mesh = db.mesh(&o).unwrap();
        buffer.insert(Loaded::new(o, mesh));
    }
    buffer
}

/// A camera far above `db`'s city looking down at it: every object small on screen,
/// drawn as coarse as it can be.
fn far_above(db: &Database) -> flaneur::geom::Camera {
    let b = db.bounds();
    flaneur::geom::Camera::new(
        b.center() + glam::Vec3::new(0.0, 3.0 * b.extent().max_element(), 0.0),
        0.0,
        -1.5,
    )
    .unwrap()
}

#[test]
fn large_objects_are_drawn_at_their_levels_until_their_refiner_is_decoded() {
    use flaneur::walk::lod_select::{LodSelector, REFINED};
    use flaneur::walk::Loaded;
    let city = common::city(30, 5, &common::with_landmarks());
    let db = Database::open(&city.db).unwrap();
    let mut buffer = all_loaded(&db);
    let large: Vec<u64> = all_objects(&db)
        .iter()
        .filter(|o| db.progressive(o.id).unwrap().is_some())
        .map(|o| o.id)
        .collect();
    assert!(!large.is_empty(), "no object above 1,000 triangles");
    let drawn: Vec<&Loaded> = buffer.iter().collect();
    let camera = far_above(&db);
    let mut lods = LodSelector::new(&db, 0.001).unwrap();
    let pages = db.io().reads_of(PageKind::Lod);
    let first = lods.select(&camera, &buffer, &drawn).unwrap();
    assert!(
        db.io().reads_of(PageKind::Lod) > pages,
        "the first frame reads the LODs"
    );
    for d in first.iter().filter(|d| large.contains(&d.id)) {
        assert_ne!(
            d.level, REFINED,
            "object {} refined before it was decoded",
            d.id
        );
    }
    assert_eq!(lods.counts.drawn_while_decoding, large.len() as u64);
    lods.settle().unwrap();
    assert_eq!(lods.counts.decoded, large.len() as u64);
    let pages = db.io().reads_of(PageKind::Lod);
    let second = lods.select(&camera, &buffer, &drawn).unwrap();
    for d in &second {
        assert_eq!(d.level == REFINED, large.contains(&d.id), "object {}", d.id);
        if d.level == REFINED {
            let mesh = lods.refined_mesh(d.id).unwrap();
            assert_eq!(d.triangles, mesh.triangle_count());
            assert!(d.triangles < buffer.get(d.id).unwrap().mesh.triangle_count());
        }
    }
    assert_eq!(
        db.io().reads_of(PageKind::Lod),
        pages,
        "nothing read again once decoded"
    );
    assert_eq!(lods.counts.drawn_while_decoding, large.len() as u64);
    // An object evicted while its decoding runs is forgotten, not refined.
    let mut lods = LodSelector::new(&db, 0.001).unwrap();
    lods.select(&camera, &buffer, &drawn).unwrap();
    buffer.remove(large[0]);
    let drawn: Vec<&Loaded> = buffer.iter().collect();
    lods.select(&camera, &buffer, &drawn).unwrap();
    lods.settle().unwrap();
    assert_eq!(lods.counts.decoded, large.len() as u64 - 1);
    assert!(lods.refined_mesh(large[0]).is_none());
    // A settling selector refines them from the first frame, the frame waiting.
    let drawn: Vec<&Loaded> = buffer.iter().collect();
    let mut lods = LodSelector::new(&db, 0.001).unwrap().settling();
    let first = lods.select(&camera, &buffer, &drawn).unwrap();
    for d in &first {
        assert_eq!(
            d.level == REFINED,
            large[1..].contains(&d.id),
            "object {}",
            d.id
        );
    }
    assert_eq!(lods.counts.drawn_while_decoding, 0);
    assert_eq!(lods.counts.decoded, large.len() as u64 - 1);
}

/// LOD selection meeting a damaged chain page: the frame's error, naming the page; or,
/// tolerating damage, the object drawn at full detail from then on, told of once.
#[test]
fn lod_selection_meets_a_damaged_lod_page() {
    // One chain to a page, as above.
    use flaneur::walk::lod_select::LodSelector;
    use flaneur::walk::Loaded;
    let city = common::city(30, 4, &raw_codec());
    let db = Database::open(&city.db).unwrap();
    let victim = all_objects(&db)[5];
    drop(db);
    let page = damage_chain(&city.db, victim.id);
    let db = Database::open(&city.db).unwrap();
    let buffer = all_loaded(&db);
    let drawn: Vec<&Loaded> = buffer.iter().collect();
    let camera = far_above(&db);
    let err = LodSelector::new(&db, 0.001)
        .unwrap()
        .select(&camera, &buffer, &drawn)
        .unwrap_err();
    assert!(
        matches!(err, Error::CorruptPage { page: p, .. } if p == page),
        "{err}"
    );
    let mut lods = LodSelector::new(&db, 0.001).unwrap().tolerating_damage();
    for frame in 0..2 {
        let chosen = lods.select(&camera, &buffer, &drawn).unwrap();
        assert_eq!(chosen.len(), drawn.len());
        for d in &chosen {
            assert_eq!(
                d.level == 0,
                d.id == victim.id,
                "frame {frame}: object {}",
                d.id
            );
        }
        let told = lods.take_damaged();
        if frame == 0 {
            assert_eq!(told.len(), 1, "{told:?}");
            assert!(
                told[0].contains(&format!("object {}", victim.id))
                    && told[0].contains(&format!("page {page}")),
                "{told:?}"
            );
        } else {
            assert!(told.is_empty(), "told again: {told:?}");
        }
    }
}

/// Adapting ahead, each frame draws its refined objects as refined for the view
/// predicted from the two frames before, by a traversal run on the thread pool once
/// the frame before was uploaded: over three frames whose cameras move in a straight
/// line, exactly the meshes a selector refining on the frame's thread makes for the
/// views c0, c0, c2 (the first prediction has one camera to go on).
#[test]
fn adapting_ahead_refines_for_the_predicted_view_off_the_frames_thread() {
    use flaneur::walk::lod_select::{LodSelector, REFINED};
    use flaneur::walk::Loaded;
    let city = common::city(30, 5, &common::with_landmarks());
    let db = Database::open(&city.db).unwrap();
    let buffer = all_loaded(&db);
    let drawn: Vec<&Loaded> = buffer.iter().collect();
    let b = db.bounds();
    let at = |k: f32| {
        let step = glam::Vec3::new(0.05 * b.extent().x, 0.0, 0.0);
        flaneur::geom::Camera::new(
            b.center() + glam::Vec3::new(0.0, b.extent().max_element(), 0.0) + k * step,
            0.0,
            -1.4,
        )
        .unwrap()
    };
    let mut ahead = LodSelector::new(&db, 0.001)
        .unwrap()
        .settling()
        .adapting_ahead();
    let mut here = LodSelector::new(&db, 0.001).unwrap().settling();
    for (k, view_here) in [(0.0, 0.0), (1.0, 0.0), (2.0, 2.0)] {
        let frame = ahead.select(&at(k), &buffer, &drawn).unwrap();
        here.select(&at(view_here), &buffer, &drawn).unwrap();
        let refined: Vec<u64> = frame
            .iter()
            .filter(|d| d.level == REFINED)
            .map(|d| d.id)
            .collect();
        assert!(!refined.is_empty(), "frame {k}: nothing refined");
        for id in refined {
            let (a, h) = (
                ahead.refined_mesh(id).unwrap(),
                here.refined_mesh(id).unwrap(),
            );
            assert_eq!(
                a.triangle_count(),
                h.triangle_count(),
                "frame {k}, object {id}"
            );
            assert_eq!(a.shared_with(h), 1.0, "frame {k}, object {id}");
        }
        // Uploaded: the traversals for the next frame start, and the refined objects
        // are away until the next selection takes them back.
        ahead.launch_ahead().unwrap();
        assert!(frame
            .iter()
            .filter(|d| d.level == REFINED)
            .all(|d| ahead.refined_mesh(d.id).is_none()));
        // A second call in the same frame does nothing.
        ahead.launch_ahead().unwrap();
    }
    assert_eq!(ahead.counts.refined_draws, here.counts.refined_draws);
    assert_eq!(ahead.counts.refine_ops, here.counts.refine_ops);
    assert!(here.counts.refine_ops > 0);
}
