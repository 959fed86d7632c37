//! The GPU device a renderer draws with, found without a window: the best adapter
//! there is, or a software one (Mesa's lavapipe or llvmpipe) where there is no GPU.

use flaneur::error::{Error, Result};

/// A device and its queue, and what adapter they came from.
///
/// ```no_run
/// # fn main() -> flaneur::Result<()> {
/// let gpu = flaneur_render::Gpu::headless()?;
/// println!("drawing on {} ({:?})", gpu.adapter.name, gpu.adapter.backend);
/// # Ok(()) }
/// ```
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter: wgpu::AdapterInfo,
}

impl Gpu {
    /// A device for offscreen rendering: a hardware adapter if there is one, else a
    /// software one. `WGPU_BACKEND` (e.g. `vulkan`, `gl`) narrows the search.
    pub fn headless() -> Result<Gpu> {
        // Vulkan (Metal, DX12) first, OpenGL only where none answers: probing GL for a
        // display it does not need makes some drivers complain on stderr.
        let chosen = std::env::var_os("WGPU_BACKEND").is_some();
        let mut tried = Vec::new();
        for backends in [wgpu::Backends::PRIMARY, wgpu::Backends::GL] {
            let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
            if !chosen {
                desc.backends = backends;
            }
            let instance = wgpu::Instance::new(desc);
            for fallback in [false, true] {
                let found =
                    pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
                        power_preference: wgpu::PowerPreference::HighPerformance,
                        force_fallback_adapter: fallback,
                        ..Default::default()
                    }));
                match found {
                    Ok(adapter) => return Gpu::on(adapter),
                    Err(e) => tried.push(e.to_string()),
                }
            }
            if chosen {
                break;
            }
        }
        tried.dedup();
        Err(Error::Render(format!(
            "no GPU adapter ({}); install a Vulkan or OpenGL driver (on Debian or \
             Ubuntu, `apt-get install mesa-vulkan-drivers` gives a software one)",
            tried.join("; ")
        )))
    }

    /// A device that can draw to `surface` (a window's), and its adapter (which the
    /// surface's configuration needs): a hardware adapter if one can, else a software one.
    pub fn for_surface(
        instance: &wgpu::Instance,
        surface: &wgpu::Surface<'_>,
    ) -> Result<(Gpu, wgpu::Adapter)> {
        let mut tried = Vec::new();
        for fallback in [false, true] {
            let found =
                pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
                    power_preference: wgpu::PowerPreference::HighPerformance,
                    force_fallback_adapter: fallback,
                    compatible_surface: Some(surface),
                    ..Default::default()
                }));
            match found {
                Ok(adapter) => return Ok((Gpu::on(adapter.clone())?, adapter)),
                Err(e) => tried.push(e.to_string()),
            }
        }
        tried.dedup();
        Err(Error::Render(format!(
            "no GPU adapter can draw to the window ({})",
            tried.join("; ")
        )))
    }

    /// Maps `buffer` (MAP_READ, its copies submitted) once the GPU is done, and hands
    /// its bytes to `read`; `what` names it in errors.
    pub(crate) fn read_mapped<R>(
        &self,
        buffer: &wgpu::Buffer,
        what: &str,
        read: impl FnOnce(&[u8]) -> R,
    ) -> Result<R> {
        let fail = |e: &dyn std::fmt::Display| Error::Render(format!("reading {what} back: {e}"));
        let slice = buffer.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| fail(&e))?;
        rx.recv().map_err(|e| fail(&e))?.map_err(|e| fail(&e))?;
        let data = slice.get_mapped_range().map_err(|e| fail(&e))?;
        let out = read(&data);
        drop(data);
        buffer.unmap();
        Ok(out)
    }

    fn on(adapter: wgpu::Adapter) -> Result<Gpu> {
        let info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("flaneur"),
            // Wireframe where the adapter has it; nothing else beyond the baseline.
            required_features: adapter.features() & wgpu::Features::POLYGON_MODE_LINE,
            required_limits: wgpu::Limits {
                max_texture_dimension_2d: adapter.limits().max_texture_dimension_2d,
                ..wgpu::Limits::downlevel_defaults()
            },
            ..Default::default()
        }))
        .map_err(|e| Error::Render(format!("{} ({:?}): {e}", info.name, info.backend)))?;
        Ok(Gpu {
            device,
            queue,
            adapter: info,
        })
    }
}
