//! The window survives a damaged database and losing its GPU device: a small city
//! walked in a window on an X display (as in `window.rs`, a binary of its own: one
//! window event loop a process).

mod common;
#[path = "common/window.rs"]
mod window;

use flaneur::path::motion::{self, Motion};
use flaneur::walk::review::{self, Preset, ReviewConfig};
use flaneur::walk::{self, Frames, WalkConfig};
use flaneur::{BuildOptions, Database};
use flaneur_render::{WalkMode, WalkWindow};
use window::{display, options, Player};

/// A mesh page damaged where the walk starts, and the GPU device lost a third of the
/// way along: the walk goes on without the object, and undrawn until a new device
/// answers; each is said once, and drawing starts again.
#[test]
fn the_walk_goes_on_past_a_damaged_page_and_a_lost_device() {
    let Some(_display) = display() else {
        eprintln!("skipped: no display, and no Xvfb to start one");
        return;
    };
    // One mesh to a page (format version 1's raw floats), so that damage to a page is
    // damage to one object: version 2 packs meshes several to a page, and each would be
    // left out.
    let city = common::city(
        60,
        3,
        &BuildOptions {
            codec: flaneur::scene::MeshCodec::Raw,
            ..Default::default()
        },
    );
    let db = Database::open(&city.db).unwrap();
    // Played at 30 frames a second: long enough after the loss for a new device (sought
    // once a second).
    let poses = motion::generate(&db.bounds(), Motion::Normal, 120, 30.0, 2).unwrap();
    // An object in the first frame's view: BOX loads it with its first cell.
    let frustum = poses.poses[0].camera().unwrap().frustum();
    let victim = db
        .range(&frustum.aabb())
        .unwrap()
        .objects
        .into_iter()
        .find(|o| frustum.overlaps_aabb(&o.bounds))
        .expect("an object in view");
    let page_size = db.store().page_size() as u64;
    drop(db);
    let mut bytes = std::fs::read(&city.db).unwrap();
    bytes[(victim.mesh.first_page * page_size + 30) as usize] ^= 0x5a;
    std::fs::write(&city.db, bytes).unwrap();
    let db = Database::open(&city.db).unwrap();
    let mut window = WalkWindow::open(options(&db, &poses), WalkMode::Box).unwrap();
    let cfg = ReviewConfig {
        pace: Some(1.0),
        ..ReviewConfig::preset(Preset::Box)
    };
    let mut player = Player {
        window: &mut window,
        resize_at: None,
        lose_at: Some(20),
        frames: 0,
    };
    let report: review::WalkReport =
        walk::run(&db, &WalkConfig::Review(cfg), &mut player, Frames::Keep)
            .unwrap()
            .try_into()
            .unwrap();
    assert_eq!(report.frames.len(), 120, "the walk went on");
    let s = &window.summary;
    let said = |what: &str| s.problems.iter().any(|p| p.contains(what));
    assert!(said("GPU device was lost"), "{:?}", s.problems);
    assert!(said("drawing again on a new device"), "{:?}", s.problems);
    assert!(
        said(&format!("object {} left out", victim.id)),
        "{:?}",
        s.problems
    );
    // Each said once: nothing else went wrong, and nothing is said frame after frame.
    assert_eq!(s.problems.len(), 3, "{:?}", s.problems);
    assert!(
        s.frames > 30 && s.frames < 120,
        "{} of 120 frames drawn",
        s.frames
    );
    assert!(window.drawn_size().is_some(), "drawing at the end");
}
