//! The window, for real: a small city walked in a window on an X display (the one the
//! session has, or an Xvfb server the test starts; `.ci/run` installs Xvfb), a recorded
//! path played through it, resized half way.

use std::process::{Child, Command};

use flaneur::render::{ViewMode, ViewOptions, WalkWindow};
use flaneur::walk::review::{self, Preset, ReviewConfig};
use flaneur::walk::{motion, FrameSink, Motion, Pose, Viewer};
use flaneur::{BuildOptions, Database};

/// An X server to draw on: `None` when the session has a display already.
struct Display(Option<Child>);

impl Drop for Display {
    fn drop(&mut self) {
        if let Some(c) = &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

fn display() -> Option<Display> {
    if std::env::var_os("DISPLAY").is_some() {
        return Some(Display(None));
    }
    // Xvfb picks a free display and writes its number on stdout once it takes clients.
    let child = Command::new("Xvfb")
        .args([
            "-displayfd",
            "1",
            "-screen",
            "0",
            "800x600x24",
            "-nolisten",
            "tcp",
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .ok()?;
    // Killed when dropped, on the way out below too.
    let mut server = Display(Some(child));
    let mut line = String::new();
    let out = server.0.as_mut()?.stdout.take()?;
    std::io::BufRead::read_line(&mut std::io::BufReader::new(out), &mut line).ok()?;
    let n: u32 = line.trim().parse().ok()?;
    std::env::set_var("DISPLAY", format!(":{n}"));
    std::env::remove_var("WAYLAND_DISPLAY");
    Some(server)
}

/// Plays `poses` through the window, asking for a new size at frame `resize_at`.
struct Resizing<'w, 'a> {
    window: &'w mut WalkWindow<'a>,
    resize_at: usize,
    frames: usize,
}

impl FrameSink for Resizing<'_, '_> {
    fn frame(
        &mut self,
        index: usize,
        camera: &flaneur::geom::Camera,
        buffer: &flaneur::walk::buffer::ObjectBuffer,
        drawn: &[&flaneur::walk::buffer::Loaded],
    ) -> flaneur::Result<()> {
        self.frames += 1;
        if index == self.resize_at {
            self.window.request_size((320, 200));
        }
        self.window.frame(index, camera, buffer, drawn)
    }
}

impl Viewer for Resizing<'_, '_> {
    fn next_pose(&mut self, frame: usize) -> flaneur::Result<Option<Pose>> {
        self.window.next_pose(frame)
    }
}

#[test]
fn a_recorded_path_plays_in_the_window_and_survives_a_resize() {
    let Some(_display) = display() else {
        eprintln!("skipped: no display, and no Xvfb to start one");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("c.scene");
    let city = citygen::CityConfig {
        objects: 60,
        seed: 3,
        landmarks: 0.0,
        ..Default::default()
    };
    citygen::write_city(&city, &scene, false).unwrap();
    let path = dir.path().join("c.flaneur");
    flaneur::build_from_scene(&scene, &path, &BuildOptions::default()).unwrap();
    let db = Database::open(&path).unwrap();
    let poses = motion::generate(&db.bounds(), Motion::Normal, 40, 30.0, 2).unwrap();
    let start = flaneur::walk::start::busiest_street(&db).unwrap();
    let opts = ViewOptions {
        size: (256, 192),
        lod_tau: Some(0.001),
        start,
        ground: db.bounds().min.y,
        city: db.bounds(),
        margin: 1000.0,
        play: Some(poses.clone()),
        gpu_budget: Some(4 << 20),
        speed: 1.4,
    };
    let mut window = WalkWindow::open(&db, opts, ViewMode::Box).unwrap();
    // Boxes over the view from above: their drawing must not fail either.
    window.boxes = true;
    window.top_view = true;
    assert_eq!(window.drawn_size(), Some((256, 192)));
    let cfg = ReviewConfig {
        pace: None,
        ..ReviewConfig::preset(Preset::Box)
    };
    let mut player = Resizing {
        window: &mut window,
        resize_at: 15,
        frames: 0,
    };
    let report = review::walk_live(&db, &cfg, |_| {}, &mut player).unwrap();
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
    let rec = dir.path().join("rec.csv");
    flaneur::render::save_recording(&window.recorded, &rec).unwrap();
    let back = flaneur::walk::CameraPath::load_csv(&rec).unwrap();
    assert_eq!(back.poses.len(), 40);
}
