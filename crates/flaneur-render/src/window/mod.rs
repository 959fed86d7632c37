//! The walkthrough window (`flaneur view`): a person steers, the walk engine selects,
//! and the window draws exactly that selection at the levels LOD selection chose, with
//! a heads-up display beside it.
//!
//! The window is a [`Viewer`]: the walk asks it for each frame's pose (it pumps the
//! window's events, then steers) and hands it each frame to draw. The walk's view is
//! 45° high and as wide as the window's shape makes it
//! ([`FrameSink::aspect`](flaneur::walk::FrameSink::aspect)), so the picture fills the
//! window, drawn whole past the walk's far plane and fading into the sky before it, as
//! headless frames are; the HUD uses the whole window too. The window opens at the size
//! asked for, or at its default fitted to the screen ([`ViewOptions::fit_screen`]).
//! Things that go wrong while walking do not end the walk: a window minimised or hidden
//! skips drawing, a lost or outdated surface is configured again, a lost device is
//! reported and a new one sought every second (the walk goes on, undrawn, meanwhile);
//! drawing errors go to stderr and the HUD.
//!
//! Keys: W A S D move, Shift runs, Space and C climb and sink when flying, F flies or
//! walks, 1, 2 and 3 choose REVIEW, BOX or PVS, the brackets halve or double the LOD threshold
//! τ, minus and equals halve or double the walk's memory budget, H hides the HUD, G
//! draws lines, B draws bounding boxes coloured as the thesis's Fig. 6.3 (red drawn at
//! full detail, yellow drawn coarse, green held but culled, white the frustum), T looks
//! from 400 m above, a click captures the mouse to look around, Esc frees it (or quits), Q
//! quits.
//!
//! This file holds the window itself: opening it, what it keeps from frame to frame,
//! and each pose's pump of events and steering. Its other parts stand beside it, one
//! idea a file: the options and summary others read, the winit events, the keys and
//! mouse, the device's loss and recovery, a frame's drawing, the HUD's lines,
//! and recorded paths. The session of walks run one after another at the window, as
//! its keys change the mode, is the walk engine's ([`flaneur::walk::live`]); the
//! window is its [`LiveViewer`] and never reads the database.

mod device;
mod events;
mod frame;
mod hud_lines;
mod keys;
mod options;
mod recording;

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use winit::event_loop::EventLoop;
use winit::platform::pump_events::EventLoopExtPumpEvents;

use device::Surfaced;
use events::Events;
use flaneur::error::{Error, Result};
use flaneur::geom::Aabb;
use flaneur::path::Pose;
use flaneur::walk::live::{Change, LiveViewer};
use flaneur::walk::WalkMode;
use flaneur::walk::{FrameFigures, Steer, Viewer};
use hud_lines::GRAPH_FRAMES;
pub use options::{ViewOptions, ViewSummary};
pub use recording::save_recording;

/// How long an error stays on the HUD.
const MESSAGE_FOR: Duration = Duration::from_secs(6);

/// The window, steered by a person or playing a path.
pub struct WalkWindow {
    event_loop: EventLoop<()>,
    events: Events,
    instance: wgpu::Instance,
    surfaced: Option<Surfaced>,
    last_try: Instant,
    opts: ViewOptions,
    steer: Steer,
    /// The τ the walk's LOD selection draws under (`None`: full detail), and whether a
    /// key set it since the last frame, so that selection starts afresh.
    lod_tau: Option<f32>,
    lod_restart: bool,
    captured: bool,
    pub show_hud: bool,
    pub wireframe: bool,
    /// Bounding boxes coloured as the thesis's Fig. 6.3, and the view from above.
    pub boxes: bool,
    pub top_view: bool,
    /// The mode shown, and a change a key asked for.
    pub mode: WalkMode,
    pub change: Option<Change>,
    /// The session's clock, and the time of the last pose given.
    clock: Instant,
    last_pose: Option<f64>,
    /// Poses given so far (what `--record` saves), and the played path's next pose.
    pub recorded: Vec<Pose>,
    played: usize,
    /// A played path's clock: the time of the pose played when it started, and when.
    play_clock: Option<(f64, Instant)>,
    quit: bool,
    last_frame: Option<Instant>,
    frame_ms: VecDeque<f32>,
    /// Pages the walks read so far, and that count over the last second.
    pages_read: u64,
    pages: VecDeque<(Instant, u64)>,
    figures: FrameFigures,
    /// Boxes the walker may not enter: the buffered objects near the eye.
    obstacles: Vec<Aabb>,
    message: Option<(String, Instant)>,
    /// Where problems are told as they happen (the HUD shows them too); the library
    /// never prints, so by default nowhere.
    tell: Box<dyn FnMut(&str)>,
    /// Objects refined elsewhere (a stream server's landmarks), handed to the first walk.
    remote: Option<Box<dyn flaneur::walk::RemoteRefinements>>,
    pub summary: ViewSummary,
}

impl WalkWindow {
    /// Opens the window as `opts` say, showing `mode`. An `Error::Render` when there is
    /// no display to open it on, saying what to use instead.
    pub fn open(opts: ViewOptions, mode: WalkMode) -> Result<WalkWindow> {
        let (w, h) = opts.size;
        if w == 0 || h == 0 {
            return Err(Error::Invalid(format!("a window of {w} × {h} pixels")));
        }
        if !(opts.speed.is_finite() && opts.speed > 0.0) {
            return Err(Error::Invalid(format!(
                "a walking speed of {} m/s: give a positive number",
                opts.speed
            )));
        }
        let mut builder = EventLoop::builder();
        #[cfg(target_os = "linux")]
        {
            // The tests open it off the main thread; the CLI opens it on it.
            use winit::platform::x11::EventLoopBuilderExtX11;
            builder.with_any_thread(true);
        }
        let mut event_loop = builder.build().map_err(|e| {
            Error::Render(format!(
                "no display to open a window on ({e}); `flaneur walk --render` draws a walk's \
                 frames headless"
            ))
        })?;
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(event_loop.owned_display_handle()),
            ));
        let mut events = Events {
            size: opts.size,
            title: opts.title.clone(),
            fit_screen: opts.fit_screen,
            ..Default::default()
        };
        let started = Instant::now();
        while events.window.is_none() && events.error.is_none() {
            event_loop.pump_app_events(Some(Duration::from_millis(10)), &mut events);
            if started.elapsed() > Duration::from_secs(10) {
                return Err(Error::Render("the window did not open within 10 s".into()));
            }
        }
        if let Some(e) = events.error.take() {
            return Err(Error::Render(e));
        }
        let window = events
            .window
            .clone()
            .expect("the loop above ends with a window");
        // The size it opened at, fitted to the screen.
        let mut opts = opts;
        opts.size = events.size;
        let surfaced = Surfaced::new(&instance, &window, &opts)?;
        if let Some(tau) = opts.lod_tau {
            flaneur::walk::lod_select::check_tau(tau)?;
        }
        Ok(WalkWindow {
            event_loop,
            events,
            instance,
            surfaced: Some(surfaced),
            last_try: Instant::now(),
            steer: {
                let mut steer = Steer::new(opts.start, opts.ground)?;
                steer.speed = opts.speed;
                steer
            },
            lod_tau: opts.lod_tau,
            lod_restart: false,
            opts,
            captured: false,
            show_hud: true,
            wireframe: false,
            boxes: false,
            top_view: false,
            mode,
            change: None,
            clock: Instant::now(),
            last_pose: None,
            recorded: Vec::new(),
            played: 0,
            play_clock: None,
            tell: Box::new(|_| {}),
            remote: None,
            quit: false,
            last_frame: None,
            frame_ms: VecDeque::with_capacity(GRAPH_FRAMES),
            pages_read: 0,
            pages: VecDeque::new(),
            figures: FrameFigures::default(),
            obstacles: Vec::new(),
            message: None,
            summary: ViewSummary::default(),
        })
    }

    /// Asks the window system for a new inner size (it may refuse, or give another).
    pub fn request_size(&self, (width, height): (u32, u32)) {
        if let Some(w) = &self.events.window {
            let _ = w.request_inner_size(winit::dpi::PhysicalSize::new(width, height));
        }
    }

    /// The size the window's picture is drawn at now, `None` while no device draws it.
    pub fn drawn_size(&self) -> Option<(u32, u32)> {
        self.surfaced
            .as_ref()
            .map(|s| (s.config.width, s.config.height))
    }

    /// The adapter drawing the window.
    pub fn adapter(&self) -> Option<&wgpu::AdapterInfo> {
        self.surfaced.as_ref().map(|s| &s.gpu.adapter)
    }

    /// Whether the person closed the window or quit.
    pub fn closed(&self) -> bool {
        self.quit || self.events.closed
    }

    /// LOD selection's threshold now (`[` and `]` change it), `None` at full detail.
    pub fn lod_tau(&self) -> Option<f32> {
        self.lod_tau
    }

    /// Where the viewer stands now.
    pub fn pose(&self) -> Pose {
        self.steer.pose()
    }

    /// Starts the next walk where this one stopped (after a change, or an error).
    pub fn resume(&mut self) {
        self.change = None;
        self.last_pose = None;
        self.play_clock = None;
        self.clock = Instant::now();
        self.steer.restart_clock();
    }

    /// Tells `tell` each problem as it happens (a lost device, a damaged object, a walk
    /// that failed and restarted): the CLI prints them on stderr.
    pub fn telling(mut self, tell: impl FnMut(&str) + 'static) -> Self {
        self.tell = Box::new(tell);
        self
    }

    /// Draws the objects `remote` refines from there (a stream server's landmarks),
    /// its status on the HUD: the walks at this window hand it on from one to the next.
    pub fn with_remote(mut self, remote: Box<dyn flaneur::walk::RemoteRefinements>) -> Self {
        self.remote = Some(remote);
        self
    }

    /// Shows `what` on the HUD for a while, and tells it (see [`WalkWindow::telling`]).
    /// The same problem met frame after frame is said again only once it has been on
    /// the HUD its while.
    pub fn report(&mut self, what: String) {
        if self
            .message
            .as_ref()
            .is_some_and(|(m, at)| *m == what && at.elapsed() < MESSAGE_FOR)
        {
            return;
        }
        (self.tell)(&what);
        self.summary.problems.push(what.clone());
        self.message = Some((what, Instant::now()));
    }
}

impl Viewer for WalkWindow {
    fn next_pose(&mut self, _: usize) -> Result<Option<Pose>> {
        self.events.mouse = (0.0, 0.0);
        self.event_loop
            .pump_app_events(Some(Duration::ZERO), &mut self.events);
        if self.events.focus_lost {
            self.events.focus_lost = false;
            self.steer.release_all();
            self.capture(false);
        }
        if std::mem::take(&mut self.events.clicked) && !self.captured {
            self.capture(true);
        }
        if std::mem::take(&mut self.events.resized) {
            let size = self.events.size;
            if let Some(s) = &mut self.surfaced {
                s.resize(size);
            }
        }
        self.handle_keys();
        self.recover();
        if self.closed() || self.change.is_some() {
            return Ok(None);
        }
        if self.captured {
            self.steer.mouse(self.events.mouse.0, self.events.mouse.1);
        }
        let pose = match &self.opts.play {
            Some(path) => match path.poses.get(self.played) {
                Some(&p) => {
                    self.played += 1;
                    self.wait_for(&p);
                    p
                }
                None => {
                    self.quit = true;
                    return Ok(None);
                }
            },
            None => {
                let now = self.clock.elapsed().as_secs_f64();
                // Poses must move forward in time, even between two quick pumps.
                let dt = (now - self.last_pose.unwrap_or(now - 1.0 / 60.0)).max(1e-4);
                self.steer.step(dt as f32, &self.obstacles)?
            }
        };
        self.last_pose = Some(pose.time);
        self.recorded.push(pose);
        self.pages.push_back((Instant::now(), self.pages_read));
        while self.pages.len() > 2 && self.pages[0].0.elapsed() > Duration::from_secs(1) {
            self.pages.pop_front();
        }
        Ok(Some(pose))
    }

    fn figures(&mut self, figures: &FrameFigures) {
        self.pages_read += figures.pages + figures.lod_pages;
        for what in &figures.damaged {
            self.report(what.clone());
        }
        self.figures = figures.clone();
    }

    fn skips_damaged(&self) -> bool {
        true
    }
}

impl LiveViewer for WalkWindow {
    fn closed(&self) -> bool {
        WalkWindow::closed(self)
    }

    fn change(&self) -> Option<Change> {
        self.change
    }

    fn show_mode(&mut self, mode: WalkMode) {
        self.mode = mode;
    }

    fn report(&mut self, what: String) {
        WalkWindow::report(self, what)
    }

    fn resume(&mut self) {
        WalkWindow::resume(self)
    }

    fn eta(&self) -> f32 {
        self.opts.eta
    }

    fn polygon_budget(&self) -> u64 {
        self.opts.polygon_budget
    }

    fn selection(&self) -> flaneur::hdov::Selection {
        self.opts.selection
    }
}
