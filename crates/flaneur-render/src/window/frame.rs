//! A walk frame in the window: the frame's times and the walker's obstacles noted,
//! what LOD selection found told, the meshes followed onto the GPU, then the scene, the boxes and the
//! HUD drawn into the surface's texture and presented. Apart because it is the one
//! thing the window does each frame once the walk has chosen what to draw.

use std::time::{Duration, Instant};

use super::device::Surfaced;
use super::hud_lines::{hud_content, GRAPH_FRAMES};
use super::{WalkWindow, MESSAGE_FOR};
use crate::boxes::lines;
use crate::scene::SceneView;
use flaneur::error::Result;
use flaneur::geom::{Aabb, Camera};
use flaneur::walk::{FrameSink, ObjectBuffer, Selection};

impl WalkWindow {
    /// Draws `selection` as `camera` sees it; `Ok(None)` when nothing could be drawn
    /// this frame (minimised, occluded, surface being configured again).
    fn draw(
        &mut self,
        camera: &Camera,
        buffer: &ObjectBuffer,
        selection: &mut Selection<'_>,
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
        let (selected, refinements) = selection.parts();
        let followed = s
            .meshes
            .follow(&s.gpu, |id| buffer.contains(id), selected, refinements)?;
        let keys: Vec<_> = selected.iter().map(|d| (d.id, d.level)).collect();
        // What adapts ahead refines for the next frame while this one draws.
        selection.uploaded()?;
        let selected = &selection.drawn[..];
        self.summary.over_budget += followed.over_budget as usize;
        self.summary.peak_gpu_bytes = self.summary.peak_gpu_bytes.max(s.meshes.bytes());
        let cpu = started.elapsed();
        let (w, h) = (s.config.width, s.config.height);
        let texture = match acquire(s) {
            Acquired::Texture(t) => t,
            Acquired::NotNow => return Ok(None),
            Acquired::Lost => {
                // The surface, not the device: make the surface again.
                self.surfaced = None;
                self.last_try = Instant::now() - Duration::from_secs(1);
                self.report("the window's surface was lost; making it again".into());
                return Ok(None);
            }
            Acquired::Refused => {
                self.report("the window's surface refused a frame".into());
                return Ok(None);
            }
        };
        let started = Instant::now();
        let view = texture.texture.create_view(&Default::default());
        // The walk's view fills the window: the walk fitted its camera's horizontal
        // field of view to the window's shape (`FrameSink::aspect`). The view from
        // above stays square, centred, unfaded. The walk's view is drawn as headless
        // frames are (`ScenePass::camera_view`): whole, fading before the far plane.
        let (viewport, scene_view) = if self.top_view {
            let side = w.min(h) as f32;
            let square = [(w as f32 - side) * 0.5, (h as f32 - side) * 0.5, side, side];
            let above = SceneView {
                view_proj: top_view(camera),
                viewport: None,
                wireframe: false,
                fade: None,
            };
            (square, above)
        } else {
            let aspect = w as f32 / h.max(1) as f32;
            let whole = [0.0, 0.0, w as f32, h as f32];
            (whole, s.scene.camera_view(camera, aspect)?)
        };
        let view_proj = scene_view.view_proj;
        let mut encoder = s.gpu.device.create_command_encoder(&Default::default());
        s.scene.encode(
            &s.gpu,
            &mut encoder,
            [&view, &s.targets[0], &s.targets[1]],
            &s.meshes,
            &keys,
            &SceneView {
                viewport: Some(viewport),
                wireframe: self.wireframe,
                ..scene_view
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
                self.lod_tau,
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
}

/// What the surface gave for this frame.
enum Acquired {
    Texture(wgpu::SurfaceTexture),
    /// No frame this time (the window hidden, or its surface configured again).
    NotNow,
    /// The surface is gone and must be made again.
    Lost,
    /// The surface refused a frame (a validation error).
    Refused,
}

/// This frame's texture of `s`'s surface; a suboptimal or outdated surface is
/// configured again and draws nothing this time.
fn acquire(s: &mut Surfaced) -> Acquired {
    match s.surface.get_current_texture() {
        wgpu::CurrentSurfaceTexture::Success(t) => Acquired::Texture(t),
        wgpu::CurrentSurfaceTexture::Suboptimal(t) => {
            drop(t);
            s.configure();
            Acquired::NotNow
        }
        wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
            Acquired::NotNow
        }
        wgpu::CurrentSurfaceTexture::Outdated => {
            s.configure();
            Acquired::NotNow
        }
        wgpu::CurrentSurfaceTexture::Lost => Acquired::Lost,
        wgpu::CurrentSurfaceTexture::Validation => Acquired::Refused,
    }
}

impl FrameSink for WalkWindow {
    fn frame(
        &mut self,
        _: usize,
        camera: &Camera,
        buffer: &ObjectBuffer,
        selection: &mut Selection<'_>,
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
        let select = selection.select_ms;
        for what in std::mem::take(&mut selection.damaged) {
            self.report(format!("LOD selection: {what}"));
        }
        if let Some(e) = selection.failed.take() {
            self.report(format!("LOD selection: {e}; drawing full detail"));
        }
        match self.draw(camera, buffer, selection) {
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

    fn lod_tau(&self) -> Option<f32> {
        self.lod_tau
    }

    fn aspect(&self) -> Option<f32> {
        let (w, h) = match &self.surfaced {
            Some(s) => (s.config.width, s.config.height),
            None => self.opts.size,
        };
        (w > 0 && h > 0).then(|| w as f32 / h as f32)
    }

    fn lod_restart(&mut self) -> bool {
        std::mem::take(&mut self.lod_restart)
    }

    fn lod_remote(&mut self) -> Option<Box<dyn flaneur::walk::RemoteRefinements>> {
        self.remote.take()
    }

    fn lod_adapt_ahead(&self) -> bool {
        self.opts.adapt_ahead
    }
}

/// The view from 400 m above the viewer, looking down, the viewer's heading up the
/// picture: where the boxes show what the walk held, drew and culled.
fn top_view(camera: &Camera) -> glam::Mat4 {
    let (sin, cos) = camera.yaw.sin_cos();
    let heading = glam::Vec3::new(cos, 0.0, sin);
    let eye = camera.position + glam::Vec3::Y * 400.0;
    glam::camera::rh::proj::directx::perspective(60f32.to_radians(), 1.0, 1.0, 5000.0)
        * glam::camera::rh::view::look_at_mat4(eye, camera.position, heading)
}
