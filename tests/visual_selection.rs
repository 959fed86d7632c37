//! Our screen-space selection beside the thesis's (VISUAL, VSC and PB) on a small city
//! built with LODs, visibility and the HDoV-tree: a node's internal LOD is used only
//! where its stored error projects under τ from the viewcell (VISUAL) or the eye (VSC),
//! where the thesis's rule stops at it whatever the screen says; each object is drawn at
//! the finer of eq. 5.6's level and the screen-space one, where the thesis's draws it
//! at the coarser, under τ stretched for an object whose DoV is at most η (ours); PB's
//! budget still bounds every frame; and a bad rule's name or τ is an error that says
//! what to give.

mod common;

use std::collections::HashSet;

use flaneur::geom::{Camera, DEFAULT_FOV};
use flaneur::hdov::{Found, HdovOptions, NodeErrors, ScreenRule, Selection};
use flaneur::path::cell_walk;
use flaneur::walk::scene::{traverse_screened, SceneErrors, SceneTree, ScreenView, Traversal};
use flaneur::walk::visual::{screen_test, VisualConfig, FAINT_TAU_STRETCH};
use flaneur::walk::{self, FrameSink, Frames, ObjectBuffer, Playback, GROUP_ID};
use flaneur::{BuildOptions, Database};

/// The thesis's τ, 0.1 % of the viewport.
const TAU: f32 = 0.001;

fn city() -> &'static common::City {
    static CITY: std::sync::OnceLock<common::City> = std::sync::OnceLock::new();
    CITY.get_or_init(|| {
        common::city(
            160,
            5,
            &BuildOptions {
                lod: BuildOptions::default().lod,
                hdov: Some(HdovOptions::default()),
                ..common::with_visibility()
            },
        )
    })
}

fn cells(db: &Database) -> Vec<u32> {
    db.hdov().unwrap().expect("built with --hdov").cells.clone()
}

fn nodes(found: &[Found]) -> HashSet<u32> {
    found
        .iter()
        .filter_map(|f| match f {
            Found::Node { node, .. } => Some(*node),
            Found::Object { .. } => None,
        })
        .collect()
}

fn objects(found: &[Found]) -> HashSet<u64> {
    found
        .iter()
        .filter_map(|f| match f {
            Found::Object { entry, .. } => Some(entry.id),
            Found::Node { .. } => None,
        })
        .collect()
}

#[test]
fn the_screen_rule_refuses_a_proxy_whose_error_projects_over_tau_where_the_thesis_stops() {
    let db = Database::open(&city().db).unwrap();
    // A large η, so that the thesis's search stops at many nodes.
    let eta = 0.05;
    let (mut thesis_stops, mut refused, mut kept) = (0, 0, 0);
    for cell in cells(&db) {
        let thesis = db
            .hdov_search_screened(cell, eta, None, None, None)
            .unwrap();
        let errors = NodeErrors::default();
        let rule = ScreenRule {
            test: screen_test(&db, cell, TAU, DEFAULT_FOV).unwrap(),
            errors: &errors,
            tolerant: false,
        };
        let screen = db
            .hdov_search_screened(cell, eta, None, None, Some(&rule))
            .unwrap();
        let ours = nodes(&screen.found);
        // Every internal LOD ours draws passes the test from anywhere in the cell.
        for f in &screen.found {
            if let Found::Node { node, mbr, .. } = f {
                let e = errors
                    .known(*node)
                    .expect("its errors were read to stop there");
                assert!(
                    rule.test.coarsest_fit(&e, mbr).is_some(),
                    "cell {cell}: node {node} drawn with errors {e:?} over τ at {} m",
                    flaneur::hdov::box_distance(&rule.test.from, mbr)
                );
            }
        }
        // Where the thesis stops, ours stops too exactly when the proxy passes.
        for f in &thesis.found {
            let Found::Node { node, mbr, .. } = f else {
                continue;
            };
            thesis_stops += 1;
            let e = errors
                .known(*node)
                .expect("ours tested every node the thesis stops at");
            match rule.test.coarsest_fit(&e, mbr) {
                Some(_) => {
                    kept += 1;
                    assert!(ours.contains(node), "cell {cell}: node {node} passes");
                }
                None => {
                    refused += 1;
                    assert!(!ours.contains(node), "cell {cell}: node {node} over τ");
                }
            }
        }
        // Ours descends where it refuses: every object the thesis finds, ours finds.
        let (t, s) = (objects(&thesis.found), objects(&screen.found));
        assert!(t.is_subset(&s), "cell {cell}: {:?}", t.difference(&s));
        // τ = 0 (full detail) lets no internal LOD pass.
        let strict = ScreenRule {
            test: screen_test(&db, cell, 0.0, DEFAULT_FOV).unwrap(),
            errors: &errors,
            tolerant: false,
        };
        let none = db
            .hdov_search_screened(cell, eta, None, None, Some(&strict))
            .unwrap();
        assert!(nodes(&none.found).is_empty(), "cell {cell}");
    }
    assert!(
        thesis_stops > 0,
        "the thesis's search never stopped at a node"
    );
    assert!(
        refused > 0,
        "no node whose proxy's error projects over τ ({kept} kept of {thesis_stops})"
    );
}

/// Each drawn object's level against the level VISUAL loaded it at (eq. 5.6's) and the
/// screen-space one from the eye.
struct Levels<'d> {
    db: &'d Database,
    /// Objects drawn finer than eq. 5.6's level, and all checked.
    finer: usize,
    checked: usize,
    /// Levels that break the rule: (id, drawn, eq. 5.6's, τ's).
    wrong: Vec<(u64, usize, usize, usize)>,
    /// Objects drawn under a stretched τ, and of them those drawn coarser than τ's own
    /// level; the ids drawn stretched and those drawn under τ.
    stretched: usize,
    coarser_than_tau: usize,
    faint: HashSet<u64>,
    bright: HashSet<u64>,
    /// Whether the rule is the finer of the two (ours) or the coarser (the thesis's).
    finer_of: bool,
}

impl FrameSink for Levels<'_> {
    fn frame(
        &mut self,
        _: usize,
        camera: &Camera,
        _: &ObjectBuffer,
        s: &mut flaneur::walk::Selection<'_>,
    ) -> flaneur::Result<()> {
        for (d, o) in s.drawn.iter().zip(s.culled) {
            if o.entry.id & GROUP_ID != 0 || d.level == flaneur::walk::lod_select::REFINED {
                continue;
            }
            // The stretch the walk handed on, which `faint_dov_tau…` checks against
            // the objects' DoVs.
            let level_under = |tau: f32| {
                self.db
                    .lod_level_for(&o.entry, camera.position, camera.fov_y, tau)
                    .map(|l| l.level)
            };
            let by_tau = level_under(TAU * o.tau_scale)?;
            if o.tau_scale != 1.0 {
                self.stretched += 1;
                self.faint.insert(o.entry.id);
                if d.level > level_under(TAU)? {
                    self.coarser_than_tau += 1;
                }
            } else {
                self.bright.insert(o.entry.id);
            }
            let want = match self.finer_of {
                true => by_tau.min(o.level),
                false => by_tau.max(o.level),
            };
            self.checked += 1;
            if d.level < o.level {
                self.finer += 1;
            }
            if d.level != want {
                self.wrong.push((o.entry.id, d.level, o.level, by_tau));
            }
        }
        Ok(())
    }

    fn lod_tau(&self) -> Option<f32> {
        Some(TAU)
    }
}

#[test]
fn an_object_near_the_eye_with_a_small_dov_is_drawn_at_its_tau_level_not_eq_5_6s() {
    let db = Database::open(&city().db).unwrap();
    let path = cell_walk(&db, 60, 1.5, 10.0, 2).unwrap();
    let walk = |selection: Selection| {
        let cfg = VisualConfig {
            eta: 0.0,
            pace: None,
            selection,
            ..VisualConfig::default()
        };
        let mut seen = Levels::new(&db, selection == Selection::Screen);
        walk::run(
            &db,
            &cfg.into(),
            &mut Playback::path(&path).drawn_by(&mut seen),
            Frames::Keep,
        )
        .unwrap();
        seen
    };
    let ours = walk(Selection::Screen);
    assert!(ours.checked > 0);
    assert!(
        ours.wrong.is_empty(),
        "{:?}",
        &ours.wrong[..ours.wrong.len().min(5)]
    );
    assert!(
        ours.finer > 0,
        "no object drawn finer than eq. 5.6's level ({} checked)",
        ours.checked
    );
    // The thesis's: eq. 5.6's level, coarser still where τ allows; never finer.
    let thesis = walk(Selection::Thesis);
    assert!(
        thesis.wrong.is_empty(),
        "{:?}",
        &thesis.wrong[..thesis.wrong.len().min(5)]
    );
    assert_eq!(thesis.finer, 0);
    // η 0 finds no object of DoV ≤ η: none is stretched.
    assert_eq!(ours.stretched + thesis.stretched, 0);
}

impl<'d> Levels<'d> {
    fn new(db: &'d Database, finer_of: bool) -> Levels<'d> {
        Levels {
            db,
            finer: 0,
            checked: 0,
            wrong: Vec::new(),
            finer_of,
            stretched: 0,
            coarser_than_tau: 0,
            faint: HashSet::new(),
            bright: HashSet::new(),
        }
    }
}

#[test]
fn faint_dov_tau_an_object_of_dov_at_most_eta_is_drawn_under_a_stretched_tau() {
    let db = Database::open(&city().db).unwrap();
    let path = cell_walk(&db, 60, 1.5, 10.0, 2).unwrap();
    let eta = 0.01;
    let walk = |faint_tau: f32| {
        let cfg = VisualConfig {
            eta,
            pace: None,
            faint_tau,
            ..VisualConfig::default()
        };
        let mut seen = Levels::new(&db, true);
        walk::run(
            &db,
            &cfg.into(),
            &mut Playback::path(&path).drawn_by(&mut seen),
            Frames::Keep,
        )
        .unwrap();
        seen
    };
    let ours = walk(FAINT_TAU_STRETCH);
    // Every object at the finer of eq. 5.6's level and the screen-space one under the τ
    // its DoV gives it.
    assert!(
        ours.wrong.is_empty(),
        "{:?}",
        &ours.wrong[..ours.wrong.len().min(5)]
    );
    assert!(ours.stretched > 0, "no object drawn under a stretched τ");
    assert!(
        ours.coarser_than_tau > 0,
        "no faint object drawn coarser than τ's level ({} stretched)",
        ours.stretched
    );
    // Stretched exactly where a cell found the object at a DoV of at most η.
    let (mut faint, mut bright) = (HashSet::new(), HashSet::new());
    for cell in cells(&db) {
        let errors = NodeErrors::default();
        let rule = ScreenRule {
            test: screen_test(&db, cell, TAU, DEFAULT_FOV).unwrap(),
            errors: &errors,
            tolerant: false,
        };
        for f in db
            .hdov_search_screened(cell, eta, None, None, Some(&rule))
            .unwrap()
            .found
        {
            if let Found::Object { entry, dov, .. } = f {
                match dov <= eta {
                    true => faint.insert(entry.id),
                    false => bright.insert(entry.id),
                };
            }
        }
    }
    assert!(
        ours.faint.is_subset(&faint),
        "{:?}",
        ours.faint.difference(&faint)
    );
    assert!(
        ours.bright.is_subset(&bright),
        "{:?}",
        ours.bright.difference(&bright)
    );
    // A stretch of 1 draws every object under τ itself.
    let plain = walk(1.0);
    assert!(plain.wrong.is_empty());
    assert_eq!(plain.stretched, 0);
    // A stretch under 1, or not a number, is refused with what to give.
    for bad in [0.5, f32::NAN] {
        let cfg = VisualConfig {
            faint_tau: bad,
            ..VisualConfig::default()
        };
        let e = walk::run(&db, &cfg.into(), &mut Playback::path(&path), Frames::Keep).unwrap_err();
        assert!(e.to_string().contains("≥ 1"), "{e}");
    }
    // `flaneur walk` takes the stretch too, and hands it to the walk's checks.
    let db = city().db.to_str().unwrap();
    let out = common::flaneur(&["walk", db, "--mode", "visual", "--faint-tau", "0.5", "-q"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("stretch of 0.5"),
        "{err}"
    );
    let out = common::flaneur(&["walk", db, "--mode", "visual", "--faint-tau", "1", "-q"]);
    common::succeeded(&out);
}

/// The screen rule from `eye` at the walks' field of view under τ.
fn view(eye: glam::Vec3, errors: &SceneErrors) -> ScreenView<'_> {
    ScreenView {
        eye,
        fov_y: DEFAULT_FOV,
        tau: TAU,
        errors,
    }
}

/// The centre of viewcell `cell` of `db`'s grid.
fn cell_centre(db: &Database, cell: u32) -> glam::Vec3 {
    let grid = &db.visibility().unwrap().unwrap().grid;
    let (r, c) = grid.place(cell);
    grid.cell_bounds(r, c).center()
}

#[test]
fn vsc_and_pb_hold_internal_lods_and_levels_to_the_screen_rule() {
    let db = Database::open(&city().db).unwrap();
    let mut tree = SceneTree::load(&db, &flaneur::progress::Silent).unwrap();
    let mut errors = SceneErrors::load(&db, &tree).unwrap();
    let internal: Vec<u32> = (0..tree.nodes.len() as u32)
        .filter(|&k| tree.nodes[k as usize].object.is_none())
        .collect();
    let (mut thesis_internal, mut compared) = (0, 0);
    for cell in cells(&db).into_iter().step_by(3) {
        tree.enter(&db, cell).unwrap();
        let eye = cell_centre(&db, cell);
        for yaw in [0.0f32, 1.6, 3.2, 4.8] {
            let camera = Camera::new(eye, yaw, 0.0).unwrap();
            let frustum = camera.frustum();
            let how = Traversal::Vsc { eta: 0.05 };
            let thesis = traverse_screened(&tree, how, &frustum, None).unwrap();
            let drawn_internal = |t: &flaneur::walk::scene::Traversed| -> HashSet<u32> {
                t.active
                    .iter()
                    .filter(|a| tree.nodes[a.node as usize].object.is_none())
                    .map(|a| a.node)
                    .collect()
            };
            thesis_internal += drawn_internal(&thesis).len();
            // Internal LODs with no bound on their error are never drawn under ours.
            for &k in &internal {
                errors.set(k, vec![f32::INFINITY; tree.nodes[k as usize].levels.len()]);
            }
            let ours = traverse_screened(&tree, how, &frustum, Some(&view(eye, &errors))).unwrap();
            assert!(drawn_internal(&ours).is_empty(), "cell {cell}");
            // Leaves at the finer of eq. 5.6's level and τ's: never coarser than the
            // thesis's, and exactly τ's where that is finer.
            let thesis_level: std::collections::HashMap<u32, usize> =
                thesis.active.iter().map(|a| (a.node, a.level)).collect();
            for a in &ours.active {
                if let Some(&l) = thesis_level.get(&a.node) {
                    assert!(
                        a.level <= l,
                        "cell {cell}: node {} at {} > {l}",
                        a.node,
                        a.level
                    );
                    compared += 1;
                }
            }
            // With errors of 0, ours draws an internal LOD only where the thesis's rule
            // allows it and the eye is outside the node's box (where the eye is inside,
            // it descends, and may stop at a child the thesis never reached).
            for &k in &internal {
                errors.set(k, vec![0.0; tree.nodes[k as usize].levels.len()]);
            }
            let ours = traverse_screened(&tree, how, &frustum, Some(&view(eye, &errors))).unwrap();
            for k in drawn_internal(&ours) {
                let n = &tree.nodes[k as usize];
                assert!(flaneur::hdov::stops(n.vd, 0.05, n.h, n.s, 2.0), "node {k}");
                assert!(flaneur::lod::distance_to(&n.bounds, eye) > 0.0, "node {k}");
            }
            // PB's budget bounds the frame under ours too.
            let budget = 3_000;
            let pb = Traversal::Pb { budget };
            let ours = traverse_screened(&tree, pb, &frustum, Some(&view(eye, &errors))).unwrap();
            assert!(ours.triangles <= budget, "cell {cell}: {}", ours.triangles);
        }
    }
    assert!(thesis_internal > 0, "VSC(0.05) never drew an internal LOD");
    assert!(compared > 0);
}

#[test]
fn pb_under_ours_spends_its_budget_by_one_screen_error_for_every_visible_object() {
    let db = Database::open(&city().db).unwrap();
    let mut tree = SceneTree::load(&db, &flaneur::progress::Silent).unwrap();
    let errors = SceneErrors::load(&db, &tree).unwrap();
    // Each active leaf's level against the coarsest that passes τ′ from `eye`.
    let at = |tree: &SceneTree, eye: glam::Vec3, tau: f32, k: u32| {
        let test = flaneur::hdov::ScreenTest {
            from: flaneur::geom::Aabb { min: eye, max: eye },
            fov_y: DEFAULT_FOV,
            tau,
        };
        let n = &tree.nodes[k as usize];
        test.coarsest_fit(errors.of(k), &n.bounds).unwrap_or(0)
    };
    let (mut whole, mut spent) = (0, 0);
    for cell in cells(&db).into_iter().step_by(3) {
        tree.enter(&db, cell).unwrap();
        let eye = cell_centre(&db, cell);
        for yaw in [0.0f32, 1.6, 3.2, 4.8] {
            let frustum = Camera::new(eye, yaw, 0.0).unwrap().frustum();
            // Every visible leaf under τ itself: what a budget that holds it draws.
            let all =
                traverse_screened(&tree, Traversal::Vsc { eta: 0.0 }, &frustum, None).unwrap();
            let under_tau: u64 = all
                .active
                .iter()
                .map(|a| tree.nodes[a.node as usize].triangles[at(&tree, eye, TAU, a.node)] as u64)
                .sum();
            let coarsest_total: u64 = all
                .active
                .iter()
                .map(|a| *tree.nodes[a.node as usize].triangles.last().unwrap() as u64)
                .sum();
            if under_tau < 2 {
                // Nothing visible in this view: no budget to spend.
                continue;
            }
            for budget in [under_tau, under_tau / 2, 3_000] {
                let pb = Traversal::Pb { budget };
                let ours =
                    traverse_screened(&tree, pb, &frustum, Some(&view(eye, &errors))).unwrap();
                assert!(ours.triangles <= budget, "cell {cell}: {}", ours.triangles);
                if coarsest_total > budget {
                    // Even the coarsest levels overdraw: the thesis's traversal.
                    continue;
                }
                // The visible leaves, each at the level one τ′ of the ladder gives it.
                assert_eq!(ours.active.len(), all.active.len(), "cell {cell}");
                let mut tau = TAU;
                let fits = loop {
                    if ours
                        .active
                        .iter()
                        .all(|a| a.level == at(&tree, eye, tau, a.node))
                    {
                        break true;
                    }
                    if tau >= 1.0 {
                        break false;
                    }
                    tau *= flaneur::walk::scene::PB_TAU_STEP;
                };
                let coarsest = ours
                    .active
                    .iter()
                    .all(|a| a.level + 1 == tree.nodes[a.node as usize].triangles.len());
                assert!(fits || coarsest, "cell {cell}, budget {budget}");
                if budget == under_tau {
                    whole += 1;
                    assert!(
                        ours.active
                            .iter()
                            .all(|a| a.level == at(&tree, eye, TAU, a.node)),
                        "cell {cell}: a budget that holds τ's levels draws them"
                    );
                }
                spent += 1;
            }
        }
    }
    assert!(whole > 0 && spent > 0);
}

#[test]
fn a_bad_rule_or_tau_is_an_error_that_says_what_to_give() {
    let db = city().db.to_str().unwrap().to_string();
    let out = common::flaneur(&["walk", &db, "--mode", "visual", "--selection", "eyeball"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("screen") && err.contains("thesis"), "{err}");
    let opened = Database::open(&city().db).unwrap();
    let cell = cells(&opened)[0];
    let e = screen_test(&opened, cell, 1.5, DEFAULT_FOV).unwrap_err();
    assert!(e.to_string().contains("[0, 1)"), "{e}");
    let cfg = VisualConfig {
        tau: f32::NAN,
        ..VisualConfig::default()
    };
    let path = cell_walk(&opened, 2, 1.0, 10.0, 1).unwrap();
    let e = walk::run(
        &opened,
        &cfg.into(),
        &mut Playback::path(&path),
        Frames::Keep,
    )
    .unwrap_err();
    assert!(e.to_string().contains("τ"), "{e}");
    // Both rules walk.
    let thesis = common::flaneur(&[
        "walk",
        &db,
        "--mode",
        "vsc",
        "--selection",
        "thesis",
        "--frames",
        "5",
        "-q",
    ]);
    common::succeeded(&thesis);
}
