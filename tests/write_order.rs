//! The order a build writes objects in (`--order`): along a Hilbert curve by default,
//! as the input gives them on request. The two files of one city answer every question
//! alike, page for page; only where each object's extents lie differs, and along the
//! curve a query's objects lie in fewer byte runs.

mod common;

use flaneur::geom::Aabb;
use flaneur::path::motion::{self, Motion};
use flaneur::scene::MeshCodec;
use flaneur::walk::review::{self, Preset, ReviewConfig};
use flaneur::walk::{self, Frames, Playback};
use flaneur::{BuildOptions, Database, ObjectEntry, WriteOrder};

/// Format version 1's raw floats, whole pages an extent, so that the two orders give
/// the same pages and the same reads: version 2 packs extents several to a page, and
/// which share one follows the order they are written in.
fn raw() -> BuildOptions {
    BuildOptions {
        codec: MeshCodec::Raw,
        ..Default::default()
    }
}

/// Runs of neighbouring mesh pages (gaps of up to `bridge` pages joined) that the
/// meshes of `objects` lie in.
fn runs(objects: &[ObjectEntry], bridge: u64) -> usize {
    let mut extents: Vec<(u64, u64)> = objects
        .iter()
        .map(|o| {
            (
                o.mesh.first_page,
                o.mesh.first_page + o.mesh.page_count as u64,
            )
        })
        .collect();
    extents.sort_unstable();
    let mut count = 0;
    let mut end = None;
    for (first, last) in extents {
        if end.is_none_or(|e: u64| first > e + bridge) {
            count += 1;
        }
        end = Some(end.map_or(last, |e: u64| e.max(last)));
    }
    count
}

#[test]
fn both_orders_answer_alike_and_the_curve_keeps_a_cell_in_fewer_runs() {
    let hilbert = common::city(900, 5, &raw());
    let input = hilbert.dir.path().join("input.flaneur");
    let opts = BuildOptions {
        order: WriteOrder::Input,
        ..raw()
    };
    flaneur::build_from_scene(&hilbert.scene, &input, &opts).unwrap();
    let (h, i) = (
        Database::open(&hilbert.db).unwrap(),
        Database::open(&input).unwrap(),
    );
    assert_eq!(
        h.info().unwrap().pages_by_kind,
        i.info().unwrap().pages_by_kind
    );
    assert_eq!(h.info().unwrap().pages, i.info().unwrap().pages);
    assert_eq!(h.lod_stats().unwrap(), i.lod_stats().unwrap());

    // Every object's mesh and levels read back the same from both files.
    let all = |db: &Database| {
        let mut a = db.range(&db.bounds()).unwrap().objects;
        a.sort_by_key(|o| o.id);
        a
    };
    let (ha, ia) = (all(&h), all(&i));
    assert_eq!(ha.len(), 900);
    for (a, b) in ha.iter().zip(&ia).step_by(37) {
        assert_eq!(a.id, b.id);
        assert_eq!(h.mesh(a).unwrap(), i.mesh(b).unwrap());
        assert_eq!(h.lod_levels(a.id).unwrap(), i.lod_levels(b.id).unwrap());
    }
    // Objects were written in another order: the extents moved.
    assert!(ha.iter().zip(&ia).any(|(a, b)| a.mesh != b.mesh));

    // Walks read the same pages, kind by kind.
    let path = motion::generate(&h.bounds(), Motion::Normal, 200, 30.0, 4).unwrap();
    let cfg = ReviewConfig {
        far: 150.0,
        ..ReviewConfig::preset(Preset::Np)
    };
    let summary = |db: &Database| {
        let r: review::WalkReport = walk::run(
            db,
            &cfg.clone().into(),
            &mut Playback::path(&path),
            Frames::Keep,
        )
        .unwrap()
        .try_into()
        .unwrap();
        r.summary
    };
    let (hw, iw) = (summary(&h), summary(&i));
    assert_eq!(
        (
            hw.index_pages,
            hw.mesh_pages,
            hw.lod_pages,
            hw.visual_misses
        ),
        (
            iw.index_pages,
            iw.mesh_pages,
            iw.lod_pages,
            iw.visual_misses
        )
    );

    // Square queries of a third of the city: the same objects, in fewer runs.
    let b = h.bounds();
    let side = (b.max.x - b.min.x) / 3.0;
    let (mut h_runs, mut i_runs) = (0, 0);
    for (fx, fz) in [(0.2, 0.3), (0.5, 0.5), (0.7, 0.6), (0.35, 0.8)] {
        let x = b.min.x + fx * (b.max.x - b.min.x);
        let z = b.min.z + fz * (b.max.z - b.min.z);
        let q = Aabb::new(
            [x - side / 2.0, b.min.y, z - side / 2.0],
            [x + side / 2.0, b.max.y, z + side / 2.0],
        )
        .unwrap();
        let (hq, iq) = (h.range(&q).unwrap(), i.range(&q).unwrap());
        assert_eq!(hq.ids(), iq.ids());
        h_runs += runs(&hq.objects, 4);
        i_runs += runs(&iq.objects, 4);
    }
    assert!(
        h_runs < i_runs,
        "along the curve {h_runs} runs, in input order {i_runs}"
    );
}

#[test]
fn the_build_command_takes_the_order_and_says_which() {
    let c = common::city(
        40,
        2,
        &BuildOptions {
            lod: None,
            ..Default::default()
        },
    );
    let out = c.dir.path().join("o.flaneur");
    let scene = c.scene.to_str().unwrap();
    let built = common::flaneur(&[
        "build",
        scene,
        "-o",
        out.to_str().unwrap(),
        "--no-lod",
        "--order",
        "input",
        "-q",
    ]);
    assert!(
        built.status.success(),
        "{}",
        String::from_utf8_lossy(&built.stderr)
    );
    assert!(String::from_utf8_lossy(&built.stdout).contains("written in input order"));
    let bad = common::flaneur(&[
        "build",
        scene,
        "-o",
        out.to_str().unwrap(),
        "--order",
        "zorder",
    ]);
    assert!(!bad.status.success());
    assert!(
        String::from_utf8_lossy(&bad.stderr).contains("hilbert or input"),
        "{}",
        String::from_utf8_lossy(&bad.stderr)
    );
}

#[test]
fn bench_layout_asks_both_files_the_same_queries_over_http() {
    let a = common::city(300, 6, &raw());
    let input = a.dir.path().join("input.flaneur");
    let opts = BuildOptions {
        order: WriteOrder::Input,
        ..raw()
    };
    flaneur::build_from_scene(&a.scene, &input, &opts).unwrap();
    let out = a.dir.path().join("bench");
    let (db, other) = (a.db.to_str().unwrap(), input.to_str().unwrap());
    let ran = common::flaneur(&[
        "bench",
        "layout",
        db,
        other,
        "--queries",
        "6",
        "--sides",
        "100,300",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        ran.status.success(),
        "{}",
        String::from_utf8_lossy(&ran.stderr)
    );
    assert!(out.join("layout.md").exists());
    let csv = std::fs::read_to_string(out.join("layout.csv")).unwrap();
    let head: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |row: &str, name: &str| -> u64 {
        let i = head.iter().position(|h| *h == name).unwrap();
        row.split(',').nth(i).unwrap().parse().unwrap()
    };
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 4, "{csv}");
    for pair in rows.chunks(2) {
        // The same city, the same queries: the same objects and the same pages read.
        for name in ["objects", "query_reads", "coarse_reads", "full_reads"] {
            assert_eq!(col(pair[0], name), col(pair[1], name), "{name}: {csv}");
        }
        for row in pair {
            assert!(
                col(row, "objects") > 0 && col(row, "full_requests") > 0,
                "{row}"
            );
            assert!(col(row, "coarse_requests") < col(row, "objects"), "{row}");
        }
    }
    // Files of two cities are not compared.
    let b = common::city(120, 7, &BuildOptions::default());
    let mixed = common::flaneur(&["bench", "layout", db, b.db.to_str().unwrap()]);
    assert!(!mixed.status.success());
    assert!(
        String::from_utf8_lossy(&mixed.stderr).contains("different cities"),
        "{}",
        String::from_utf8_lossy(&mixed.stderr)
    );
}
