//! The memory HDoV scene tree (Shou 2002 ch. 6) on a small city: its VDs add up from
//! each cell's PVS, CONV draws every object in the frustum at full detail, VSC(0) the
//! visible ones, VSC(η) no more triangles than CONV and fewer nodes as η grows, PB(n) stays within its budget and
//! names the object whose coarsest level alone is over a tiny one, and a walk counts
//! the frames outside every cell.

mod common;

use std::collections::HashSet;

use glam::Vec3;

use flaneur::path::{cell_walk, CameraPath, Pose};
use flaneur::visibility::VisibilityOptions;
use flaneur::walk::scene::{traverse, SceneTree, Traversal};
use flaneur::walk::scene::{SceneConfig, SceneReport};
use flaneur::walk::{Frames, Playback, WalkState};
use flaneur::{BuildOptions, Database};

fn city() -> &'static common::City {
    static CITY: std::sync::OnceLock<common::City> = std::sync::OnceLock::new();
    CITY.get_or_init(|| {
        common::city(
            300,
            4,
            &BuildOptions {
                visibility: Some(VisibilityOptions {
                    resolution: 16,
                    ..Default::default()
                }),
                ..Default::default()
            },
        )
    })
}

fn tree(db: &Database) -> SceneTree {
    SceneTree::load(db, &flaneur::progress::Silent).unwrap()
}

/// Walks `path` over the scene tree `state` holds (the same tree walk after walk) under
/// `cfg`, drawing nothing, its frames kept.
fn scene_walk(
    state: &mut WalkState<'_>,
    path: &CameraPath,
    cfg: SceneConfig,
) -> flaneur::Result<SceneReport> {
    state
        .run(&cfg.into(), &mut Playback::path(path), Frames::Keep)?
        .try_into()
}

/// The ids of `db`'s walkable viewcells.
fn walkable(db: &Database) -> Vec<u32> {
    let head = db.visibility().unwrap().unwrap();
    head.cells.iter().map(|c| c.id).collect()
}

/// The eye at the centre of viewcell `cell`, looking along `yaw`.
fn eye(db: &Database, cell: u32, yaw: f32) -> Pose {
    let grid = &db.visibility().unwrap().unwrap().grid;
    let (r, c) = grid.place(cell);
    Pose {
        time: 0.0,
        position: grid.cell_bounds(r, c).center(),
        yaw,
        pitch: 0.0,
    }
}

#[test]
fn vds_add_up_from_the_pvs_and_each_node_is_the_sum_of_its_children() {
    let db = Database::open(&city().db).unwrap();
    let mut t = tree(&db);
    assert_eq!(
        t.nodes.len(),
        2 * 300 - 1,
        "a k-D tree down to one object a leaf"
    );
    let cells = walkable(&db);
    for &cell in cells.iter().step_by(7).take(6) {
        t.enter(&db, cell).unwrap();
        let pvs = db.pvs(cell).unwrap().unwrap();
        let visible = pvs.dov.iter().filter(|d| **d > 0.0).count() as u32;
        assert_eq!(t.nodes[0].vd.nvo, visible);
        let total: f32 = pvs.dov.iter().sum();
        assert!((t.nodes[0].vd.dov - total).abs() <= 1e-3 * total.max(1.0));
        for n in &t.nodes {
            if let Some([a, b]) = n.children {
                let (a, b) = (&t.nodes[a as usize].vd, &t.nodes[b as usize].vd);
                assert_eq!(n.vd.nvo, a.nvo + b.nvo);
                assert!((n.vd.dov - a.dov - b.dov).abs() <= 1e-4 * n.vd.dov.max(1e-3));
            }
        }
    }
}

#[test]
fn conv_draws_the_frustum_vsc_zero_the_visible_and_vsc_fewer_as_eta_grows() {
    let db = Database::open(&city().db).unwrap();
    let mut t = tree(&db);
    let cells = walkable(&db);
    let mut internal_seen = false;
    for (i, &cell) in cells.iter().enumerate().step_by(5).take(8) {
        t.enter(&db, cell).unwrap();
        let pose = eye(&db, cell, i as f32);
        let frustum = pose.camera().unwrap().frustum();
        // CONV: every object whose box meets the frustum, at full detail.
        let conv = traverse(&t, Traversal::Conv, &frustum).unwrap();
        let in_view: HashSet<u64> = city()
            .boxes
            .iter()
            .filter(|(_, b)| frustum.overlaps_aabb(b))
            .map(|(id, _)| *id)
            .collect();
        let drawn: HashSet<u64> = conv.active.iter().map(|a| t.key(a.node)).collect();
        assert_eq!(drawn, in_view);
        assert!(conv.active.iter().all(|a| a.level == 0));
        // VSC(0): the visible ones among them, objects only.
        let pvs = db.pvs(cell).unwrap().unwrap();
        let visible: HashSet<u64> = pvs
            .ids
            .iter()
            .zip(&pvs.dov)
            .filter(|(id, d)| **d > 0.0 && in_view.contains(id))
            .map(|(id, _)| *id)
            .collect();
        let v0 = traverse(&t, Traversal::Vsc { eta: 0.0 }, &frustum).unwrap();
        let drawn: HashSet<u64> = v0.active.iter().map(|a| t.key(a.node)).collect();
        assert_eq!(drawn, visible);
        assert!(v0.visited <= conv.visited);
        for eta in [0.001, 0.01, 0.1] {
            let v = traverse(&t, Traversal::Vsc { eta }, &frustum).unwrap();
            assert!(v.triangles <= conv.triangles);
            assert!(v.visited <= v0.visited, "a larger η stops higher up");
            internal_seen |= v
                .active
                .iter()
                .any(|a| t.nodes[a.node as usize].object.is_none());
        }
    }
    assert!(internal_seen, "no VSC traversal stopped at an internal LOD");
}

#[test]
fn pb_keeps_its_budget_and_names_what_is_too_big_for_a_tiny_one() {
    let db = Database::open(&city().db).unwrap();
    let mut state = WalkState::new(&db).with_scene_tree(tree(&db));
    let path = cell_walk(&db, 120, 1.5, 10.0, 3).unwrap();
    let conv = scene_walk(&mut state, &path, SceneConfig::new(Traversal::Conv)).unwrap();
    let budget = (conv.summary.mean_triangles / 4.0) as u64;
    let pb = scene_walk(
        &mut state,
        &path,
        SceneConfig::new(Traversal::Pb { budget }),
    )
    .unwrap();
    assert!(pb.within_budget() >= 0.99, "{:?}", pb.summary);
    assert!(pb.summary.mean_triangles > 0.0);
    assert!(pb.summary.mean_triangles < conv.summary.mean_triangles);
    // A budget below every object's coarsest level: said so, naming one.
    let tiny = scene_walk(
        &mut state,
        &path,
        SceneConfig::new(Traversal::Pb { budget: 4 }),
    )
    .unwrap();
    let said = tiny
        .too_big()
        .expect("a tiny budget names an object too big for it");
    assert!(said.contains("over the budget of 4"), "{said}");
}

#[test]
fn a_walk_counts_conv_frames_before_any_cell_and_frames_outside() {
    let db = Database::open(&city().db).unwrap();
    let mut state = WalkState::new(&db).with_scene_tree(tree(&db));
    let b = db.bounds();
    let inside = cell_walk(&db, 10, 1.0, 10.0, 2).unwrap();
    let above = |i: usize, p: &Pose| Pose {
        time: i as f64 * 0.1,
        position: Vec3::new(p.position.x, b.max.y + 30.0, p.position.z),
        // Looking down at the city.
        pitch: -0.6,
        ..*p
    };
    // Five frames above the roofs, ten in cells, five above again.
    let mut poses: Vec<Pose> = (0..5).map(|i| above(i, &inside.poses[0])).collect();
    poses.extend(inside.poses.iter().enumerate().map(|(i, p)| Pose {
        time: 0.5 + i as f64 * 0.1,
        ..*p
    }));
    poses.extend((0..5).map(|i| above(16 + i, inside.poses.last().unwrap())));
    let path = CameraPath::new(poses).unwrap();
    let r = scene_walk(
        &mut state,
        &path,
        SceneConfig::new(Traversal::Vsc { eta: 0.001 }),
    )
    .unwrap();
    assert_eq!(r.summary.frames_outside, 10);
    assert_eq!(r.summary.frames_conv, 5);
    assert!(
        r.frames[..5].iter().all(|f| f.conv && f.drawn > 0),
        "{:?}",
        &r.frames[..5]
    );
    assert!(r.frames[15..].iter().all(|f| !f.conv && f.cell.is_none()));
}

#[test]
fn the_scene_tree_bench_sets_vsc_and_pb_beside_conv_and_writes_its_report() {
    use flaneur_bench::scene_tree::{self, SceneTreeConfig};
    let db = Database::open(&city().db).unwrap();
    let cfg = SceneTreeConfig {
        frames: 90,
        etas: vec![0.0, 0.001],
        budgets: vec![2_000],
        ..Default::default()
    };
    let r = scene_tree::run(&db, &cfg, |_, _| {}).unwrap();
    assert_eq!(r.rows.len(), 4);
    let conv = r.row("CONV").unwrap();
    let vsc = r.row("VSC(0.001)").unwrap();
    assert!(vsc.mean_triangles <= conv.mean_triangles);
    assert!(vsc.mean_visited <= conv.mean_visited);
    let pb = r.row("PB(2000)").unwrap();
    assert!(pb.within_budget >= 0.99, "{pb:?}");
    assert!(r.series.iter().all(|(_, f)| f.len() == cfg.frames));

    let out = city().dir.path().join("scene-bench");
    let o = common::flaneur(&[
        "bench",
        "scene-tree",
        city().db.to_str().unwrap(),
        "--frames",
        "30",
        "--etas",
        "0.001",
        "--budgets",
        "5000",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "scene-tree.csv",
        "scene-tree.md",
        "scene-tree-frames.csv",
        "scene-tree-triangles.png",
        "scene-tree-frames.png",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    // And a walk in the mode from the command line.
    let o = common::flaneur(&[
        "walk",
        city().db.to_str().unwrap(),
        "--mode",
        "pb",
        "--budget",
        "3000",
        "--frames",
        "30",
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(
        said.contains("PB(3000)") && said.contains("within the budget"),
        "{said}"
    );
}

#[test]
fn bad_settings_and_missing_parts_are_clear_errors() {
    let e = Traversal::Pb { budget: 0 }.validate().unwrap_err();
    assert!(e.to_string().contains("polygon budget of 0"), "{e}");
    let e = Traversal::Vsc { eta: f32::NAN }.validate().unwrap_err();
    assert!(e.to_string().contains("η"), "{e}");
    let db = city().db.to_str().unwrap();
    // A scheme that is not one, and a scene walk on a database without visibility.
    let o = common::flaneur(&["walk", db, "--mode", "visual", "--scheme", "diagonal", "-q"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("diagonal") && !err.contains("panicked"),
        "{err}"
    );
    let plain = common::city(30, 2, &BuildOptions::default());
    let o = common::flaneur(&["walk", plain.db.to_str().unwrap(), "--mode", "vsc", "-q"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--visibility") && !err.contains("panicked"),
        "{err}"
    );
}
