//! The device and surface the window draws with, and their lifecycle: made when the
//! window opens, polled for errors and loss before each frame, let go when lost, and
//! sought again every second after. Apart because a lost device is the one failure the
//! window outlives by starting its GPU side over, and all that is remade lives here.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use winit::window::Window;

use super::{ViewOptions, WalkWindow};
use crate::boxes::Boxes;
use crate::hud::Hud;
use crate::meshes::GpuMeshes;
use crate::scene::{target, ScenePass, DEPTH_FORMAT, ID_FORMAT};
use crate::Gpu;
use flaneur::error::{Error, Result};

/// What draws into the window: its surface and device, and what lives on them. Dropped
/// when the device is lost, made again when a new one answers.
pub(super) struct Surfaced {
    pub(super) gpu: Gpu,
    pub(super) surface: wgpu::Surface<'static>,
    pub(super) config: wgpu::SurfaceConfiguration,
    pub(super) scene: ScenePass,
    pub(super) hud: Hud,
    pub(super) boxes: Boxes,
    pub(super) meshes: GpuMeshes,
    /// The id and depth targets, the window's size.
    pub(super) targets: [wgpu::TextureView; 2],
    lost: Arc<AtomicBool>,
    /// Errors the device met outside any error scope (wgpu panics on them unless told
    /// where to put them): reported, not fatal.
    errors: Arc<std::sync::Mutex<Vec<String>>>,
}

impl Surfaced {
    pub(super) fn new(
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

    pub(super) fn configure(&mut self) {
        self.surface.configure(&self.gpu.device, &self.config);
    }

    pub(super) fn resize(&mut self, (width, height): (u32, u32)) {
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

impl WalkWindow {
    /// Destroys the GPU device the window draws with, as a driver reset or a GPU taken
    /// away would: the window then recovers as from any lost device (an embedder's way
    /// to check that its walk survives one).
    pub fn lose_device(&self) {
        if let Some(s) = &self.surfaced {
            s.gpu.device.destroy();
        }
    }

    /// Tries for a new device once a second after the last was lost.
    pub(super) fn recover(&mut self) {
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
            Err(e) => (self.tell)(&format!("no new device yet: {e}")),
        }
    }

    /// Polls the device: reports the errors it raised, and lets it go when it is lost
    /// (it tells of that only when polled). Whether there is a device to draw with.
    pub(super) fn device_answers(&mut self) -> bool {
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
}
