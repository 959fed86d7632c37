//! The window's keys and mouse, for real: a small city walked in a window on an X
//! display, with key presses and mouse moves sent through the X server by `xdotool`
//! (`.ci/run` installs it) as a person would make them. A binary of its own: one
//! window event loop a process.

mod common;
#[path = "common/window.rs"]
mod window;

use std::process::Command;

use flaneur::path::Pose;
use flaneur::walk::review::{Preset, ReviewConfig};
use flaneur::walk::{self, FrameSink, Frames, Viewer, WalkConfig};
use flaneur::{BuildOptions, Database};
use flaneur_render::{Change, WalkMode, WalkWindow};
use window::{display, options};

/// Steers the window by sending `script` to `xdotool` at frame 3, and ends the walk
/// after `limit` frames whatever happened.
struct Typist<'w> {
    window: &'w mut WalkWindow,
    script: Vec<&'static str>,
    limit: usize,
    typing: Option<std::process::Child>,
    /// The window's settings after each frame: HUD, boxes, τ.
    seen: Vec<(bool, bool, Option<f32>)>,
}

impl FrameSink for Typist<'_> {
    fn frame(
        &mut self,
        index: usize,
        camera: &flaneur::geom::Camera,
        buffer: &flaneur::walk::ObjectBuffer,
        selection: &mut flaneur::walk::Selection<'_>,
    ) -> flaneur::Result<()> {
        if index == 3 {
            self.typing = Some(Command::new("xdotool").args(&self.script).spawn().unwrap());
        }
        self.window.frame(index, camera, buffer, selection)?;
        let w = &self.window;
        self.seen.push((w.show_hud, w.boxes, w.lod_tau()));
        Ok(())
    }

    fn lod_tau(&self) -> Option<f32> {
        self.window.lod_tau()
    }

    fn lod_restart(&mut self) -> bool {
        self.window.lod_restart()
    }
}

impl Viewer for Typist<'_> {
    fn next_pose(&mut self, frame: usize) -> flaneur::Result<Option<Pose>> {
        if frame >= self.limit {
            return Ok(None);
        }
        // Paced a little, so that the keys held take some frames.
        std::thread::sleep(std::time::Duration::from_millis(10));
        self.window.next_pose(frame)
    }
}

#[test]
fn keys_and_the_mouse_steer_the_window() {
    if Command::new("xdotool").arg("version").output().is_err() {
        eprintln!("skipped: no xdotool to type with");
        return;
    }
    let Some(_display) = display() else {
        eprintln!("skipped: no display, and no Xvfb to start one");
        return;
    };
    let city = common::city(60, 3, &BuildOptions::default());
    let db = Database::open(&city.db).unwrap();
    let opts = flaneur_render::ViewOptions {
        play: None,
        ..options(&db, &flaneur::path::CameraPath { poses: Vec::new() })
    };
    let start = opts.start;
    let mut window = WalkWindow::open(opts, WalkMode::Review).unwrap();
    let tau = window.lod_tau().unwrap();
    assert!(window.show_hud && !window.boxes);
    let cfg = ReviewConfig {
        pace: None,
        ..ReviewConfig::preset(Preset::Optimal)
    };
    // The window found by its title and given the keyboard (there is no window
    // manager to), W held, H, B and ] pressed; a click captures the mouse, whose moves
    // then turn the view; 2 asks for BOX.
    let script = "search --sync --name flaneur windowfocus --sync %1 \
                  mousemove --window %1 100 80 sleep 0.2 \
                  keydown w sleep 0.6 keyup w key h key b key bracketright sleep 0.2 \
                  click 1 sleep 0.2 mousemove_relative -- 60 0 sleep 0.3 key 2";
    let mut typist = Typist {
        window: &mut window,
        script: script.split_whitespace().collect(),
        limit: 1500,
        typing: None,
        seen: Vec::new(),
    };
    walk::run(&db, &WalkConfig::Review(cfg), &mut typist, Frames::Keep).unwrap();
    let typed = typist.typing.take().unwrap().wait().unwrap();
    assert!(typed.success(), "xdotool failed");
    let seen = std::mem::take(&mut typist.seen);
    assert!(
        seen.len() < 1500,
        "the walk ran to its limit: 2 did not switch the mode"
    );
    assert_eq!(
        window.change,
        Some(Change::Mode(WalkMode::Box)),
        "2 asks for BOX"
    );
    let last = *seen.last().unwrap();
    assert_eq!(last, (false, true, Some(2.0 * tau)), "H, B and ]");
    let end = window.pose();
    let moved = (end.position - start.position) * glam::Vec3::new(1.0, 0.0, 1.0);
    assert!(moved.length() > 0.3, "W held walked {} m", moved.length());
    assert!(
        (end.position.y - start.position.y).abs() < 1e-3,
        "walking keeps the eye's height"
    );
    assert!(end.yaw != start.yaw, "the mouse turned the view");
    assert!(
        window.summary.problems.is_empty(),
        "{:?}",
        window.summary.problems
    );
}
