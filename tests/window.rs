//! The window, for real: a small city walked in a window on an X display (the one the
//! session has, or an Xvfb server the test starts; `.ci/run` installs Xvfb), a recorded
//! path played through it, resized half way.

mod common;
#[path = "common/window.rs"]
mod window;

use flaneur::path::motion::{self, Motion};
use flaneur::walk::review::{self, Preset, ReviewConfig};
use flaneur::walk::{self, Frames, WalkConfig};
use flaneur::{BuildOptions, Database};
use flaneur_render::{WalkMode, WalkWindow};
use window::{display, options, Player};

#[test]
fn a_recorded_path_plays_in_the_window_and_survives_a_resize() {
    let Some(_display) = display() else {
        eprintln!("skipped: no display, and no Xvfb to start one");
        return;
    };
    let city = common::city(60, 3, &BuildOptions::default());
    let db = Database::open(&city.db).unwrap();
    let poses = motion::generate(&db.bounds(), Motion::Normal, 40, 30.0, 2).unwrap();
    let opts = options(&db, &poses);
    let mut window = WalkWindow::open(opts, WalkMode::Box).unwrap();
    // Boxes over the view from above: their drawing must not fail either.
    window.boxes = true;
    window.top_view = true;
    assert_eq!(window.drawn_size(), Some((256, 192)));
    let cfg = ReviewConfig {
        pace: None,
        ..ReviewConfig::preset(Preset::Box)
    };
    let mut player = Player {
        window: &mut window,
        resize_at: Some(15),
        lose_at: None,
        frames: 0,
    };
    let report: review::WalkReport =
        walk::run(&db, &WalkConfig::Review(cfg), &mut player, Frames::Keep)
            .unwrap()
            .try_into()
            .unwrap();
    assert_eq!(player.frames, 40);
    assert_eq!(report.frames.len(), 40);
    assert!(window.closed(), "the window closes when the path ends");
    assert_eq!(window.recorded, poses.poses, "it walked the path it played");
    let s = &window.summary;
    assert!(s.problems.is_empty(), "{:?}", s.problems);
    assert!(s.frames > 30, "{} of 40 frames drawn", s.frames);
    assert_eq!(s.cpu_ms.len(), s.frames);
    assert!(s.peak_gpu_bytes > 0);
    assert_eq!(
        window.drawn_size(),
        Some((320, 200)),
        "the resize reached the surface"
    );
    // What it recorded reads back as a path.
    let rec = city.dir.path().join("rec.csv");
    flaneur_render::save_recording(&window.recorded, &rec).unwrap();
    let back = flaneur::path::CameraPath::load_csv(&rec).unwrap();
    assert_eq!(back.poses.len(), 40);
}
