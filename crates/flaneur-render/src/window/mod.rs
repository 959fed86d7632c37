//! The walkthrough window (`flaneur view`): a person steers, the walk engine selects,
//! and the window draws exactly that selection at the levels LOD selection chose, with
//! a heads-up display beside it.
//!
//! The window is a [`Viewer`]: the walk asks it for each frame's pose (it pumps the
//! window's events, then steers) and hands it each frame to draw. The walk's view is
//! 45° × 45°, so the picture is the largest centred square of the window; the HUD uses
//! the whole of it. Things that go wrong while walking do not end the walk: a window
//! minimised or hidden skips drawing, a lost or outdated surface is configured again,
//! a lost device is reported and a new one sought every second (the walk goes on,
//! undrawn, meanwhile); drawing errors go to stderr and the HUD.
//!
//! Keys: W A S D move, Shift runs, Space and C climb and sink when flying, F flies or
//! walks, 1, 2 and 3 choose REVIEW, BOX or PVS, the brackets halve or double the LOD threshold
//! τ, minus and equals halve or double the walk's memory budget, H hides the HUD, G
//! draws lines, B draws bounding boxes coloured as the thesis's Fig. 6.3 (red drawn at
//! full detail, yellow drawn coarse, green held but culled, white the frustum), T looks
//! from 400 m above, a click captures the mouse to look around, Esc frees it (or quits), Q
//! quits.

use std::collections::VecDeque;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use winit::application::ApplicationHandler;
use winit::event::{DeviceEvent, ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::platform::pump_events::EventLoopExtPumpEvents;
use winit::window::{CursorGrabMode, Window, WindowId};

use crate::boxes::{lines, Boxes};
use crate::hud::{Hud, HudContent};
use crate::meshes::GpuMeshes;
use crate::scene::{target, ScenePass, SceneView, DEPTH_FORMAT, ID_FORMAT};
use crate::Gpu;
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::geom::{Aabb, Camera};
use flaneur::walk::buffer::{Loaded, ObjectBuffer};
use flaneur::walk::lod_select::{Drawn, LodSelector, REFINED};
use flaneur::walk::steer::{Move, Steer};
use flaneur::walk::{CameraPath, FrameFigures, FrameSink, Pose, Viewer};

/// Frame times the HUD's graph shows.
const GRAPH_FRAMES: usize = 120;
/// How long an error stays on the HUD.
const MESSAGE_FOR: Duration = Duration::from_secs(6);

/// What the window asks the walk to change, when a key asks for it: the walk ends
/// its run and starts again from where the viewer stands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Change {
    /// REVIEW (CSearch with index cache and prefetching), plain BOX queries, or PVS.
    Mode(ViewMode),
    /// The object buffer's budget, times this factor.
    Budget(f32),
}

/// The walk modes the window can show so far.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewMode {
    Review,
    Box,
    /// The current viewcell's PVS, neighbours prefetched (a database built with
    /// visibility).
    Pvs,
}

impl ViewMode {
    pub fn name(self) -> &'static str {
        match self {
            ViewMode::Review => "review",
            ViewMode::Box => "box",
            ViewMode::Pvs => "pvs",
        }
    }
}

/// How the window opens.
#[derive(Clone, Debug)]
pub struct ViewOptions {
    pub size: (u32, u32),
    /// LOD selection's threshold, a fraction of the viewport; `None`: full detail.
    pub lod_tau: Option<f32>,
    /// Where the viewer starts, over a ground at `ground` metres.
    pub start: Pose,
    pub ground: f32,
    /// The city's bounds, and how far past them the ground reaches.
    pub city: Aabb,
    pub margin: f32,
    /// A recorded path to play instead of steering.
    pub play: Option<CameraPath>,
    /// GPU memory the meshes may take, bytes; `None`: what the walk's buffer holds.
    pub gpu_budget: Option<u64>,
    /// Walking speed, m/s (running is four times it, flying the same).
    pub speed: f32,
}

impl ViewOptions {
    /// Walking `db` from `start`: a 1024 × 768 window, LODs under the thesis's τ, a
    /// 256 MiB GPU budget, a walker's pace, and the ground reaching the default
    /// frustum's depth past the city.
    pub fn new(db: &Database, start: Pose) -> ViewOptions {
        ViewOptions {
            size: (1024, 768),
            lod_tau: Some(flaneur::walk::lod_select::DEFAULT_TAU),
            start,
            ground: db.bounds().min.y,
            city: db.bounds(),
            margin: flaneur::geom::DEFAULT_FAR,
            play: None,
            gpu_budget: Some(256 << 20),
            speed: flaneur::walk::steer::WALK_SPEED,
        }
    }
}

/// What a session at the window drew.
#[derive(Clone, Debug, Default)]
pub struct ViewSummary {
    pub frames: usize,
    /// Per frame drawn: LOD selection and uploads (CPU), and drawing until the GPU is
    /// done (GPU), milliseconds.
    pub cpu_ms: Vec<f64>,
    pub gpu_ms: Vec<f64>,
    /// The most GPU memory the meshes took, bytes, and the frames whose own meshes
    /// did not fit the GPU budget.
    pub peak_gpu_bytes: u64,
    pub over_budget: usize,
    /// Problems met and got over (lost surfaces, a lost device, drawing errors).
    pub problems: Vec<String>,
}

/// The winit side: the window and what its events asked for since the last pump.
#[derive(Default)]
struct Events {
    window: Option<Arc<Window>>,
    error: Option<String>,
    size: (u32, u32),
    title: String,
    closed: bool,
    resized: bool,
    focus_lost: bool,
    keys: Vec<(KeyCode, bool)>,
    mouse: (f64, f64),
    clicked: bool,
}

impl ApplicationHandler for Events {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let attributes = Window::default_attributes()
            .with_title(self.title.clone())
            .with_inner_size(winit::dpi::PhysicalSize::new(self.size.0, self.size.1));
        match event_loop.create_window(attributes) {
            Ok(w) => self.window = Some(Arc::new(w)),
            Err(e) => self.error = Some(format!("opening a window: {e}")),
        }
    }

    fn window_event(&mut self, _: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested | WindowEvent::Destroyed => self.closed = true,
            WindowEvent::Resized(size) => {
                self.size = (size.width, size.height);
                self.resized = true;
            }
            WindowEvent::Focused(false) => self.focus_lost = true,
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    if !event.repeat {
                        self.keys.push((code, event.state == ElementState::Pressed));
                    }
                }
            }
            WindowEvent::MouseInput {
                state: ElementState::Pressed,
                button: MouseButton::Left,
                ..
            } => self.clicked = true,
            _ => {}
        }
    }

    fn device_event(&mut self, _: &ActiveEventLoop, _: winit::event::DeviceId, e: DeviceEvent) {
        if let DeviceEvent::MouseMotion { delta } = e {
            self.mouse.0 += delta.0;
            self.mouse.1 += delta.1;
        }
    }
}

/// What draws into the window: its surface and device, and what lives on them. Dropped
/// when the device is lost, made again when a new one answers.
struct Surfaced {
    gpu: Gpu,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    scene: ScenePass,
    hud: Hud,
    boxes: Boxes,
    meshes: GpuMeshes,
    /// The id and depth targets, the window's size.
    targets: [wgpu::TextureView; 2],
    lost: Arc<AtomicBool>,
    /// Errors the device met outside any error scope (wgpu panics on them unless told
    /// where to put them): reported, not fatal.
    errors: Arc<std::sync::Mutex<Vec<String>>>,
}

impl Surfaced {
    fn new(
        instance: &wgpu::Instance,
        window: &Arc<Window>,
        opts: &ViewOptions,
    ) -> Result<Surfaced> {
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| Error::Render(format!("a surface for the window: {e}")))?;
        let (gpu, adapter) = Gpu::for_surface(instance, &surface)?;
        let caps = surface.get_capabilities(&adapter);
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| f.is_srgb())
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| {
                Error::Render(format!("{} cannot draw to this window", gpu.adapter.name))
            })?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&adapter, size.width.max(1), size.height.max(1))
            .ok_or_else(|| {
                Error::Render(format!("{} cannot draw to this window", gpu.adapter.name))
            })?;
        config.format = format;
        config.present_mode = wgpu::PresentMode::AutoVsync;
        let lost = Arc::new(AtomicBool::new(false));
        let flag = lost.clone();
        gpu.device
            .set_device_lost_callback(move |_, _| flag.store(true, Ordering::SeqCst));
        let errors = Arc::new(std::sync::Mutex::new(Vec::new()));
        let to = errors.clone();
        gpu.device
            .on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
                if let Ok(mut v) = to.lock() {
                    v.push(e.to_string());
                }
            }));
        let mut scene = ScenePass::new(&gpu, format);
        scene.set_ground(&gpu, &opts.city, opts.margin);
        let hud = Hud::new(&gpu, format)?;
        let boxes = Boxes::new(&gpu, format);
        let targets = window_targets(&gpu, (config.width, config.height));
        let mut s = Surfaced {
            gpu,
            surface,
            config,
            scene,
            hud,
            boxes,
            meshes: GpuMeshes::default(),
            targets,
            lost,
            errors,
        };
        s.configure();
        Ok(s)
    }

    fn configure(&mut self) {
        self.surface.configure(&self.gpu.device, &self.config);
    }

    fn resize(&mut self, (width, height): (u32, u32)) {
        if width == 0 || height == 0 || (width, height) == (self.config.width, self.config.height) {
            return;
        }
        self.config.width = width;
        self.config.height = height;
        self.configure();
        self.targets = window_targets(&self.gpu, (width, height));
    }
}

fn window_targets(gpu: &Gpu, size: (u32, u32)) -> [wgpu::TextureView; 2] {
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
    [
        target(&gpu.device, "window ids", size, ID_FORMAT, usage),
        target(&gpu.device, "window depth", size, DEPTH_FORMAT, usage),
    ]
    .map(|t| t.create_view(&Default::default()))
}

/// The window, steered by a person or playing a path.
pub struct WalkWindow<'a> {
    db: &'a Database,
    event_loop: EventLoop<()>,
    events: Events,
    instance: wgpu::Instance,
    surfaced: Option<Surfaced>,
    last_try: Instant,
    opts: ViewOptions,
    steer: Steer,
    lods: Option<LodSelector<'a>>,
    captured: bool,
    pub show_hud: bool,
    pub wireframe: bool,
    /// Bounding boxes coloured as the thesis's Fig. 6.3, and the view from above.
    pub boxes: bool,
    pub top_view: bool,
    /// The mode shown, and a change a key asked for.
    pub mode: ViewMode,
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
    pages: VecDeque<(Instant, u64)>,
    figures: FrameFigures,
    /// Boxes the walker may not enter: the buffered objects near the eye.
    obstacles: Vec<Aabb>,
    message: Option<(String, Instant)>,
    pub summary: ViewSummary,
}

impl<'a> WalkWindow<'a> {
    /// Opens the window on `db`. An `Error::Render` when there is no display to open it
    /// on, saying what to use instead.
    pub fn open(db: &'a Database, opts: ViewOptions, mode: ViewMode) -> Result<WalkWindow<'a>> {
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
            title: format!("flaneur — {}", db.store().path().display()),
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
        let surfaced = Surfaced::new(&instance, &window, &opts)?;
        let lods = opts
            .lod_tau
            .map(|tau| LodSelector::new(db, tau).map(LodSelector::tolerating_damage))
            .transpose()?;
        Ok(WalkWindow {
            db,
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
            opts,
            lods,
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
            quit: false,
            last_frame: None,
            frame_ms: VecDeque::with_capacity(GRAPH_FRAMES),
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

    /// Destroys the GPU device the window draws with, as a driver reset or a GPU taken
    /// away would: the window then recovers as from any lost device (an embedder's way
    /// to check that its walk survives one).
    pub fn lose_device(&self) {
        if let Some(s) = &self.surfaced {
            s.gpu.device.destroy();
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
        self.lods.as_ref().map(|l| l.tau())
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

    /// Shows `what` on the HUD for a while, and on stderr. The same problem met frame
    /// after frame is said again only once it has been on the HUD its while.
    pub fn report(&mut self, what: String) {
        if self
            .message
            .as_ref()
            .is_some_and(|(m, at)| *m == what && at.elapsed() < MESSAGE_FOR)
        {
            return;
        }
        eprintln!("{what}");
        self.summary.problems.push(what.clone());
        self.message = Some((what, Instant::now()));
    }

    fn handle_keys(&mut self) {
        for (code, pressed) in std::mem::take(&mut self.events.keys) {
            let movement = match code {
                KeyCode::KeyW | KeyCode::ArrowUp => Some(Move::Forward),
                KeyCode::KeyS | KeyCode::ArrowDown => Some(Move::Back),
                KeyCode::KeyA | KeyCode::ArrowLeft => Some(Move::Left),
                KeyCode::KeyD | KeyCode::ArrowRight => Some(Move::Right),
                KeyCode::Space => Some(Move::Up),
                KeyCode::KeyC => Some(Move::Down),
                KeyCode::ShiftLeft | KeyCode::ShiftRight => Some(Move::Run),
                _ => None,
            };
            if let Some(m) = movement {
                self.steer.key(m, pressed);
                continue;
            }
            if !pressed {
                continue;
            }
            match code {
                KeyCode::KeyF => self.steer.fly = !self.steer.fly,
                KeyCode::KeyH => self.show_hud = !self.show_hud,
                KeyCode::KeyG => self.wireframe = !self.wireframe,
                KeyCode::KeyB => self.boxes = !self.boxes,
                KeyCode::KeyT => self.top_view = !self.top_view,
                KeyCode::Digit1 => self.change = Some(Change::Mode(ViewMode::Review)),
                KeyCode::Digit2 => self.change = Some(Change::Mode(ViewMode::Box)),
                KeyCode::Digit3 => self.change = Some(Change::Mode(ViewMode::Pvs)),
                KeyCode::BracketLeft | KeyCode::BracketRight => {
                    let factor = if code == KeyCode::BracketLeft {
                        0.5
                    } else {
                        2.0
                    };
                    if let Some(l) = &self.lods {
                        let tau = (l.tau() * factor).clamp(1e-5, 0.5);
                        self.lods = LodSelector::new(self.db, tau)
                            .map(LodSelector::tolerating_damage)
                            .ok();
                    }
                }
                KeyCode::Minus => self.change = Some(Change::Budget(0.5)),
                KeyCode::Equal => self.change = Some(Change::Budget(2.0)),
                KeyCode::Escape if self.captured => self.capture(false),
                KeyCode::Escape | KeyCode::KeyQ => self.quit = true,
                _ => {}
            }
        }
    }

    fn capture(&mut self, on: bool) {
        let Some(w) = &self.events.window else { return };
        if on {
            let grabbed = w
                .set_cursor_grab(CursorGrabMode::Locked)
                .or_else(|_| w.set_cursor_grab(CursorGrabMode::Confined));
            if grabbed.is_err() {
                return;
            }
        } else {
            let _ = w.set_cursor_grab(CursorGrabMode::None);
        }
        w.set_cursor_visible(!on);
        self.captured = on;
    }

    /// Tries for a new device once a second after the last was lost.
    fn recover(&mut self) {
        if self.surfaced.is_some() || self.last_try.elapsed() < Duration::from_secs(1) {
            return;
        }
        self.last_try = Instant::now();
        let Some(window) = self.events.window.clone() else {
            return;
        };
        match Surfaced::new(&self.instance, &window, &self.opts) {
            Ok(s) => {
                self.surfaced = Some(s);
                self.report("drawing again on a new device".into());
            }
            Err(e) => eprintln!("no new device yet: {e}"),
        }
    }

    /// Polls the device: reports the errors it raised, and lets it go when it is lost
    /// (it tells of that only when polled). Whether there is a device to draw with.
    fn device_answers(&mut self) -> bool {
        let Some(s) = &self.surfaced else {
            return false;
        };
        let _ = s.gpu.device.poll(wgpu::PollType::Poll);
        let errors: Vec<String> = s
            .errors
            .lock()
            .map(|mut v| v.drain(..).collect())
            .unwrap_or_default();
        let lost = s.lost.load(Ordering::SeqCst);
        for e in errors {
            self.report(format!("the GPU device reported an error: {e}"));
        }
        if lost {
            self.surfaced = None;
            self.last_try = Instant::now();
            self.report(
                "the GPU device was lost; the walk goes on undrawn while a new one is sought"
                    .into(),
            );
        }
        !lost
    }

    /// Draws `selected` as `camera` sees it; `Ok(None)` when nothing could be drawn
    /// this frame (minimised, occluded, surface being configured again).
    fn draw(
        &mut self,
        camera: &Camera,
        buffer: &ObjectBuffer,
        selected: &[Drawn],
    ) -> Result<Option<(f64, f64)>> {
        let pages_per_s = self.pages_per_second();
        if !self.device_answers() {
            return Ok(None);
        }
        let Some(s) = &mut self.surfaced else {
            return Ok(None);
        };
        let started = Instant::now();
        s.meshes.set_budget(self.opts.gpu_budget);
        let followed = s.meshes.follow(
            &s.gpu,
            |id| buffer.contains(id),
            selected,
            self.lods.as_mut(),
        )?;
        self.summary.over_budget += followed.over_budget as usize;
        self.summary.peak_gpu_bytes = self.summary.peak_gpu_bytes.max(s.meshes.bytes());
        let cpu = started.elapsed();
        let (w, h) = (s.config.width, s.config.height);
        let texture = match s.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) => t,
            wgpu::CurrentSurfaceTexture::Suboptimal(t) => {
                drop(t);
                s.configure();
                return Ok(None);
            }
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                return Ok(None)
            }
            wgpu::CurrentSurfaceTexture::Outdated => {
                s.configure();
                return Ok(None);
            }
            wgpu::CurrentSurfaceTexture::Lost => {
                // The surface, not the device: make the surface again.
                self.surfaced = None;
                self.last_try = Instant::now() - Duration::from_secs(1);
                self.report("the window's surface was lost; making it again".into());
                return Ok(None);
            }
            wgpu::CurrentSurfaceTexture::Validation => {
                self.report("the window's surface refused a frame".into());
                return Ok(None);
            }
        };
        let started = Instant::now();
        let view = texture.texture.create_view(&Default::default());
        // The walk's square view, centred.
        let side = w.min(h) as f32;
        let viewport = [(w as f32 - side) * 0.5, (h as f32 - side) * 0.5, side, side];
        let keys: Vec<_> = selected.iter().map(|d| (d.id, d.level)).collect();
        let view_proj = if self.top_view {
            top_view(camera)
        } else {
            camera.view_proj(1.0)?
        };
        let mut encoder = s.gpu.device.create_command_encoder(&Default::default());
        s.scene.encode(
            &s.gpu,
            &mut encoder,
            [&view, &s.targets[0], &s.targets[1]],
            &s.meshes,
            &keys,
            &SceneView {
                view_proj,
                viewport: Some(viewport),
                wireframe: self.wireframe,
            },
        )?;
        if self.boxes {
            let drawn: std::collections::HashSet<u64> = selected.iter().map(|d| d.id).collect();
            let culled: Vec<Aabb> = buffer
                .iter()
                .filter(|o| !drawn.contains(&o.entry.id))
                .map(|o| o.entry.bounds)
                .collect();
            let l = lines(&camera.frustum(), selected, &culled);
            s.boxes
                .draw(&s.gpu, &mut encoder, &view, view_proj, Some(viewport), &l)?;
        }
        if self.show_hud {
            let content = hud_content(
                &self.figures,
                self.mode,
                self.lods.as_ref().map(|l| l.tau()),
                (selected, &s.meshes),
                (self.steer.fly, camera.position, pages_per_s),
                self.message
                    .as_ref()
                    .filter(|m| m.1.elapsed() < MESSAGE_FOR)
                    .map(|m| m.0.as_str()),
                &self.frame_ms,
                s.scene.has_wireframe(),
            );
            s.hud.draw(
                &s.gpu,
                &mut encoder,
                &view,
                (w, h),
                &content,
                if h >= 900 { 2 } else { 1 },
            )?;
        }
        s.gpu.queue.submit([encoder.finish()]);
        // Waiting for the GPU here makes the GPU's share of the frame measurable.
        let _ = s.gpu.device.poll(wgpu::PollType::wait_indefinitely());
        s.gpu.queue.present(texture);
        Ok(Some((
            cpu.as_secs_f64() * 1e3,
            started.elapsed().as_secs_f64() * 1e3,
        )))
    }

    fn pages_per_second(&self) -> f64 {
        match (self.pages.front(), self.pages.back()) {
            (Some(a), Some(b)) if b.0 > a.0 => (b.1 - a.1) as f64 / (b.0 - a.0).as_secs_f64(),
            _ => 0.0,
        }
    }
}

impl FrameSink for WalkWindow<'_> {
    fn frame(
        &mut self,
        _: usize,
        camera: &Camera,
        buffer: &ObjectBuffer,
        drawn: &[&Loaded],
    ) -> Result<()> {
        let now = Instant::now();
        if let Some(last) = self.last_frame.replace(now) {
            if self.frame_ms.len() == GRAPH_FRAMES {
                self.frame_ms.pop_front();
            }
            self.frame_ms.push_back((now - last).as_secs_f32() * 1e3);
        }
        let p = camera.position;
        self.obstacles.clear();
        self.obstacles.extend(
            buffer
                .iter()
                .map(|o| o.entry.bounds)
                .filter(|b| (b.center() - p).length() < 0.5 * b.extent().length() + 20.0),
        );
        let started = Instant::now();
        let selected = match &mut self.lods {
            Some(l) => {
                let chosen = l.select(camera, buffer, drawn);
                for what in l.take_damaged() {
                    self.report(format!("LOD selection: {what}"));
                }
                chosen.unwrap_or_else(|e| {
                    self.report(format!("LOD selection: {e}; drawing full detail"));
                    drawn.iter().map(|o| Drawn::full(o)).collect()
                })
            }
            None => drawn.iter().map(|o| Drawn::full(o)).collect(),
        };
        let select = started.elapsed().as_secs_f64() * 1e3;
        match self.draw(camera, buffer, &selected) {
            Ok(Some((cpu, gpu))) => {
                self.summary.frames += 1;
                self.summary.cpu_ms.push(select + cpu);
                self.summary.gpu_ms.push(gpu);
            }
            Ok(None) => {}
            Err(e) => self.report(format!("drawing: {e}")),
        }
        Ok(())
    }
}

impl Viewer for WalkWindow<'_> {
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
                    // Played at the pace it was walked: a frame drawn early waits for
                    // its pose's time; a late one does not catch up.
                    let (t0, started) = *self.play_clock.get_or_insert((p.time, Instant::now()));
                    let due = Duration::from_secs_f64((p.time - t0).max(0.0));
                    if let Some(wait) = due.checked_sub(started.elapsed()) {
                        std::thread::sleep(wait);
                    }
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
        let reads = self.db.io().page_reads;
        self.pages.push_back((Instant::now(), reads));
        while self.pages.len() > 2 && self.pages[0].0.elapsed() > Duration::from_secs(1) {
            self.pages.pop_front();
        }
        Ok(Some(pose))
    }

    fn figures(&mut self, figures: &FrameFigures) {
        for what in &figures.damaged {
            self.report(what.clone());
        }
        self.figures = figures.clone();
    }

    fn skips_damaged(&self) -> bool {
        true
    }
}

/// The view from 400 m above the viewer, looking down, the viewer's heading up the
/// picture: where the boxes show what the walk held, drew and culled.
fn top_view(camera: &Camera) -> glam::Mat4 {
    let (sin, cos) = camera.yaw.sin_cos();
    let heading = glam::Vec3::new(cos, 0.0, sin);
    let eye = camera.position + glam::Vec3::Y * 400.0;
    glam::Mat4::perspective_rh(60f32.to_radians(), 1.0, 1.0, 5000.0)
        * glam::Mat4::look_at_rh(eye, camera.position, heading)
}

/// The HUD's lines.
#[allow(clippy::too_many_arguments)]
fn hud_content(
    f: &FrameFigures,
    mode: ViewMode,
    tau: Option<f32>,
    (selected, gpu): (&[Drawn], &GpuMeshes),
    (flying, p, pages_per_s): (bool, glam::Vec3, f64),
    message: Option<&str>,
    frame_ms: &VecDeque<f32>,
    wireframe: bool,
) -> HudContent {
    let last = frame_ms.back().copied().unwrap_or(0.0);
    let worst = frame_ms.iter().copied().fold(0.0, f32::max);
    let triangles: usize = selected.iter().map(|d| d.triangles).sum();
    let coarse = selected.iter().filter(|d| d.is_coarse()).count();
    let refined = selected.iter().filter(|d| d.level == REFINED).count();
    let mut lines = vec![
        format!(
            "frame {last:5.1} ms (worst {worst:.1} of the last {})",
            frame_ms.len()
        ),
        format!(
            "mode {} ({}), LOD tau {}",
            mode.name(),
            if flying { "flying" } else { "walking" },
            tau.map_or("off (full detail)".into(), |t| format!("{t}"))
        ),
        format!(
            "triangles {triangles}, objects drawn {} ({coarse} coarse, {refined} refined)",
            selected.len()
        ),
        format!(
            "objects resident {} (GPU {}, {:.1} MiB{}), misses {}",
            f.objects_buffered,
            gpu.len(),
            gpu.bytes() as f64 / 1048576.0,
            gpu.budget().map_or(String::new(), |b| format!(
                " of {:.0}",
                b as f64 / 1048576.0
            )),
            f.visual_misses
        ),
        format!(
            "pages {:.0}/s, index cache hits {}, prefetch queue {}",
            pages_per_s,
            f.cache_hit_rate
                .map_or("-".into(), |h| format!("{:.0}%", 100.0 * h)),
            f.prefetch_queue
        ),
        format!("{} at {:.0}, {:.1}, {:.0}", f.cell, p.x, p.y, p.z),
        format!(
            "WASD shift F fly  1 review 2 box 3 pvs  [ ] tau  - = budget  H hud  B boxes  T top{}  Q quit",
            if wireframe { "  G lines" } else { "" }
        ),
    ];
    if let Some(m) = message {
        lines.push(m.to_string());
    }
    HudContent {
        lines,
        frame_ms: frame_ms.iter().copied().collect(),
    }
}

/// Where `--record` writes a session's poses: a path CSV that `--play` (and `flaneur
/// walk --path`) read back.
pub fn save_recording(poses: &[Pose], path: &Path) -> Result<()> {
    // Restarts after a change begin a new clock: renumber times so they increase.
    let mut out = Vec::with_capacity(poses.len());
    let mut t = 0.0;
    for (i, p) in poses.iter().enumerate() {
        if i > 0 {
            let dt = p.time - poses[i - 1].time;
            t += if dt > 0.0 { dt } else { 1.0 / 60.0 };
        }
        out.push(Pose { time: t, ..*p });
    }
    CameraPath::new(out)?.save_csv(path)
}
