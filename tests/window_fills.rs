//! The window fills itself: on a window three times wider than tall, the walk's view
//! reaches both side edges, not a centred square between bars of sky. Its pixels are
//! read from the screen of an Xvfb server the test starts (`-fbdir`); on a display of
//! the session's own there is no screen file to read, and the test says so and skips.

mod common;
#[path = "common/window.rs"]
mod window;

use flaneur::path::motion::{self, Motion};
use flaneur::walk::review::{self, Preset, ReviewConfig};
use flaneur::walk::{self, Frames, WalkConfig};
use flaneur::{BuildOptions, Database};
use flaneur_render::{WalkMode, WalkWindow};
use window::{display_in, options, Player, Screen, Ticking};

const SIZE: (usize, usize) = (480, 160);

/// The share of the lower half of columns `xs` of the window (at the screen's corner)
/// that is not the sky.
fn not_sky(screen: &Screen, xs: std::ops::Range<usize>, sky: [u8; 3]) -> f64 {
    let (mut other, mut all) = (0, 0);
    for y in SIZE.1 / 2 + 4..SIZE.1 - 4 {
        for x in xs.clone() {
            let p = screen.at(x, y);
            let near = (0..3).all(|c| p[c].abs_diff(sky[c]) <= 6);
            other += usize::from(!near);
            all += 1;
        }
    }
    other as f64 / all as f64
}

#[test]
fn a_wide_window_is_drawn_edge_to_edge() {
    if std::env::var_os("DISPLAY").is_some() {
        eprintln!("skipped: a display of the session's own, whose pixels are not a file");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let Some(_display) = display_in(dir.path()) else {
        eprintln!("skipped: no Xvfb to start");
        return;
    };
    let city = common::city(60, 3, &BuildOptions::default());
    let db = Database::open(&city.db).unwrap();
    let poses = motion::generate(&db.bounds(), Motion::Normal, 30, 30.0, 2).unwrap();
    let mut opts = options(&db, &poses);
    opts.size = (SIZE.0 as u32, SIZE.1 as u32);
    let mut window = WalkWindow::open(opts, WalkMode::Box).unwrap();
    window.show_hud = false;
    let cfg = ReviewConfig {
        pace: None,
        ..ReviewConfig::preset(Preset::Box)
    };
    let screen = dir.path().join("Xvfb_screen0");
    let mut shot = None;
    let mut player = Player {
        window: &mut window,
        resize_at: None,
        lose_at: None,
        frames: 0,
    };
    // The screen as the window shows it at the walk's last frames, before it closes.
    let mut viewer = Ticking::new(&mut player, |frame| {
        if frame == 25 {
            shot = Some(Screen::read(&screen));
        }
    });
    let report: review::WalkReport =
        walk::run(&db, &WalkConfig::Review(cfg), &mut viewer, Frames::Keep)
            .unwrap()
            .try_into()
            .unwrap();
    assert_eq!(report.frames.len(), 30);
    assert_eq!(window.drawn_size(), Some((SIZE.0 as u32, SIZE.1 as u32)));
    let shot = shot.expect("a frame 25");
    assert!(shot.width >= SIZE.0 && shot.height >= SIZE.1);
    // The window's top row is sky, whatever the view: the eye is at street level.
    let sky = shot.at(SIZE.0 / 2, 1);
    assert!(sky[2] > sky[0], "the top of the window is not sky: {sky:?}");
    let middle = not_sky(&shot, SIZE.0 / 2 - 40..SIZE.0 / 2 + 40, sky);
    let left = not_sky(&shot, 0..SIZE.0 / 8, sky);
    let right = not_sky(&shot, SIZE.0 - SIZE.0 / 8..SIZE.0, sky);
    assert!(
        middle > 0.9,
        "the middle's lower half is {middle:.2} ground and buildings"
    );
    // A square view in the middle leaves the sides' lower halves all sky (0.0).
    assert!(
        left > 0.9 && right > 0.9,
        "the sides' lower halves are {left:.2} and {right:.2} ground and buildings, the middle {middle:.2}"
    );
}
