//! The window tests' shared parts: an X display to draw on, a player that plays a path
//! through the window and disturbs it on cue, and the window's options. A process can
//! open one window event loop only, so each window test is a test binary of its own.
#![allow(dead_code)]

use std::process::{Child, Command};

use flaneur::path::Pose;
use flaneur::walk::{FrameSink, Viewer};
use flaneur::Database;
use flaneur_render::{ViewOptions, WalkWindow};

/// An X server to draw on: `None` when the session has a display already.
pub struct Display(Option<Child>);

impl Drop for Display {
    fn drop(&mut self) {
        if let Some(c) = &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

pub fn display() -> Option<Display> {
    if std::env::var_os("DISPLAY").is_some() {
        return Some(Display(None));
    }
    xvfb((800, 600), &[])
}

/// An Xvfb server of our own whose screen is also a file in `dir` (XWD, `Xvfb_screen0`),
/// so that a test can see the window's pixels, on a black root. `None` without Xvfb.
pub fn display_in(dir: &std::path::Path) -> Option<Display> {
    display_sized_in(dir, (800, 600))
}

/// [`display_in`] with a screen of `(width, height)` pixels.
pub fn display_sized_in(dir: &std::path::Path, screen: (u32, u32)) -> Option<Display> {
    xvfb(screen, &["-fbdir", dir.to_str()?, "-br"])
}

fn xvfb((width, height): (u32, u32), extra: &[&str]) -> Option<Display> {
    let screen = format!("{width}x{height}x24");
    // Xvfb picks a free display and writes its number on stdout once it takes clients.
    let child = Command::new("Xvfb")
        .args([
            "-displayfd",
            "1",
            "-screen",
            "0",
            screen.as_str(),
            "-nolisten",
            "tcp",
        ])
        .args(extra)
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

/// Plays the window's path through it, asking for a new size at frame `resize_at`, and
/// destroying its GPU device at frame `lose_at`.
pub struct Player<'w> {
    pub window: &'w mut WalkWindow,
    pub resize_at: Option<usize>,
    pub lose_at: Option<usize>,
    pub frames: usize,
}

impl FrameSink for Player<'_> {
    fn frame(
        &mut self,
        index: usize,
        camera: &flaneur::geom::Camera,
        buffer: &flaneur::walk::ObjectBuffer,
        selection: &mut flaneur::walk::Selection<'_>,
    ) -> flaneur::Result<()> {
        self.frames += 1;
        if Some(index) == self.resize_at {
            self.window.request_size((320, 200));
        }
        if Some(index) == self.lose_at {
            self.window.lose_device();
        }
        self.window.frame(index, camera, buffer, selection)
    }

    fn lod_tau(&self) -> Option<f32> {
        self.window.lod_tau()
    }

    fn lod_restart(&mut self) -> bool {
        self.window.lod_restart()
    }
}

impl Viewer for Player<'_> {
    fn next_pose(&mut self, frame: usize) -> flaneur::Result<Option<Pose>> {
        self.window.next_pose(frame)
    }

    fn figures(&mut self, figures: &flaneur::walk::FrameFigures) {
        self.window.figures(figures)
    }

    fn skips_damaged(&self) -> bool {
        self.window.skips_damaged()
    }
}

/// `viewer`, telling `tick` the index of each frame once the frame is drawn and its
/// figures are taken (a walk's progress): everything else is `viewer`'s own.
pub struct Ticking<'v, V: Viewer + ?Sized, F: FnMut(usize)> {
    pub viewer: &'v mut V,
    pub tick: F,
    at: usize,
}

impl<'v, V: Viewer + ?Sized, F: FnMut(usize)> Ticking<'v, V, F> {
    pub fn new(viewer: &'v mut V, tick: F) -> Self {
        Ticking {
            viewer,
            tick,
            at: 0,
        }
    }
}

impl<V: Viewer + ?Sized, F: FnMut(usize)> FrameSink for Ticking<'_, V, F> {
    fn frame(
        &mut self,
        index: usize,
        camera: &flaneur::geom::Camera,
        buffer: &flaneur::walk::ObjectBuffer,
        selection: &mut flaneur::walk::Selection<'_>,
    ) -> flaneur::Result<()> {
        self.viewer.frame(index, camera, buffer, selection)
    }

    fn draws(&self) -> bool {
        self.viewer.draws()
    }

    fn aspect(&self) -> Option<f32> {
        self.viewer.aspect()
    }

    fn lod_tau(&self) -> Option<f32> {
        self.viewer.lod_tau()
    }

    fn lod_restart(&mut self) -> bool {
        self.viewer.lod_restart()
    }

    fn lod_settled(&self) -> bool {
        self.viewer.lod_settled()
    }

    fn lod_adapt_ahead(&self) -> bool {
        self.viewer.lod_adapt_ahead()
    }

    fn lod_remote(&mut self) -> Option<Box<dyn flaneur::walk::RemoteRefinements>> {
        self.viewer.lod_remote()
    }
}

impl<V: Viewer + ?Sized, F: FnMut(usize)> Viewer for Ticking<'_, V, F> {
    fn next_pose(&mut self, frame: usize) -> flaneur::Result<Option<Pose>> {
        self.at = frame;
        self.viewer.next_pose(frame)
    }

    fn figures(&mut self, figures: &flaneur::walk::FrameFigures) {
        self.viewer.figures(figures);
        (self.tick)(self.at);
    }

    fn skips_damaged(&self) -> bool {
        self.viewer.skips_damaged()
    }
}

/// A small window over `db` playing `poses` from its busiest street, with LODs and a
/// GPU budget of 4 MiB.
pub fn options(db: &Database, poses: &flaneur::path::CameraPath) -> ViewOptions {
    ViewOptions {
        size: (256, 192),
        lod_tau: Some(0.001),
        play: Some(poses.clone()),
        gpu_budget: Some(4 << 20),
        ..ViewOptions::new(db.bounds(), flaneur::walk::busiest_street(db).unwrap())
    }
}

/// An X screen's pixels, read from the XWD file Xvfb keeps it in (`-fbdir`): 8-bit RGB.
pub struct Screen {
    pub width: usize,
    pub height: usize,
    rgb: Vec<[u8; 3]>,
}

impl Screen {
    /// Reads the XWD dump at `path` (32 bits a pixel, as Xvfb writes a 24-bit screen).
    pub fn read(path: &std::path::Path) -> Screen {
        let bytes = std::fs::read(path).unwrap();
        let field = |i: usize| u32::from_be_bytes(bytes[i * 4..i * 4 + 4].try_into().unwrap());
        let (header, width, height) = (field(0) as usize, field(4) as usize, field(5) as usize);
        let (lsb_first, bits, line) = (field(7) == 0, field(11), field(12) as usize);
        let masks = [field(14), field(15), field(16)];
        let colours = field(19) as usize;
        assert_eq!(bits, 32, "{bits} bits a pixel");
        let start = header + colours * 12;
        let mut rgb = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                let at = start + y * line + x * 4;
                let b: [u8; 4] = bytes[at..at + 4].try_into().unwrap();
                let v = if lsb_first {
                    u32::from_le_bytes(b)
                } else {
                    u32::from_be_bytes(b)
                };
                rgb.push(masks.map(|m| ((v & m) >> m.trailing_zeros()) as u8));
            }
        }
        Screen { width, height, rgb }
    }

    pub fn at(&self, x: usize, y: usize) -> [u8; 3] {
        self.rgb[y * self.width + x]
    }
}
