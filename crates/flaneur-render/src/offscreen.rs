//! Drawing into textures instead of a window, and reading the pixels back: the colour
//! image and, in the same pass, the id of the object each pixel shows.

use glam::Mat4;

use crate::meshes::{GpuMeshes, MeshKey};
use crate::scene::{target, ScenePass, SceneView, DEPTH_FORMAT, GROUND_SLOT, ID_FORMAT};
use crate::Gpu;
use flaneur::error::{Error, Result};
use flaneur::geom::{Aabb, Camera};

const COLOUR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// A rendered image: RGBA8 (sRGB) pixels and each pixel's object, rows top first.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    /// The object each pixel shows; `None` for the sky.
    pub objects: Vec<Option<u64>>,
}

/// The scene pass and the render targets of one image size.
pub struct Offscreen {
    scene: ScenePass,
    colour: wgpu::Texture,
    ids: wgpu::Texture,
    // Made once with the targets, so that a frame allocates nothing but its commands.
    views: [wgpu::TextureView; 3],
    readback: [wgpu::Buffer; 2],
    width: u32,
    height: u32,
    /// Draw as lines (where the device can).
    pub wireframe: bool,
}

impl Offscreen {
    /// Targets of `width` × `height` pixels.
    pub fn new(gpu: &Gpu, width: u32, height: u32) -> Result<Offscreen> {
        let max = gpu.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(Error::Invalid(format!(
                "an image of {width} × {height} pixels: each side must be 1 to {max}"
            )));
        }
        let device = &gpu.device;
        let size = (width, height);
        let readable = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let colour = target(device, "colour", size, COLOUR_FORMAT, readable);
        let ids = target(device, "ids", size, ID_FORMAT, readable);
        let depth = target(
            device,
            "depth",
            size,
            DEPTH_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        let views = [&colour, &ids, &depth].map(|t| t.create_view(&Default::default()));
        let readback = ["colour readback", "id readback"].map(|label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: padded_row(width) as u64 * height as u64,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            })
        });
        Ok(Offscreen {
            scene: ScenePass::new(gpu, COLOUR_FORMAT),
            colour,
            ids,
            views,
            readback,
            width,
            height,
            wireframe: false,
        })
    }

    /// The colour target's format (what an overlay's pipeline must draw into).
    pub fn colour_format(&self) -> wgpu::TextureFormat {
        COLOUR_FORMAT
    }

    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Draws a ground under `city`: a plane at its lowest point reaching `margin`
    /// metres past it on every side. The id target shows the ground as the sky. The
    /// city's heights also set where a camera's picture fades
    /// ([`Offscreen::render_camera`]).
    pub fn set_ground(&mut self, gpu: &Gpu, city: &Aabb, margin: f32) {
        self.scene.set_ground(gpu, city, margin);
    }

    /// Draws `draw` as `camera` sees it, its vertical field of view kept and its
    /// horizontal one fitted to the image: whole, with no far plane, fading into the
    /// sky before the camera's far plane ([`ScenePass::camera_view`]).
    pub fn render_camera(
        &self,
        gpu: &Gpu,
        camera: &Camera,
        meshes: &GpuMeshes,
        draw: &[MeshKey],
    ) -> Result<Frame> {
        let (camera, aspect) = self.fitted(camera)?;
        let view = self.scene.camera_view(&camera, aspect)?;
        self.render_view(gpu, view, meshes, draw, |_, _| Ok(()))
    }

    /// `camera` with its vertical field of view kept and its horizontal one fitted to
    /// the image, and the image's aspect (width / height).
    pub fn fitted(&self, camera: &Camera) -> Result<(Camera, f32)> {
        let aspect = self.width as f32 / self.height as f32;
        Ok((camera.fitted_to(aspect)?, aspect))
    }

    /// Draws `draw` (objects at a level, each resident in `meshes`) with `view_proj`
    /// and reads the image back.
    pub fn render(
        &self,
        gpu: &Gpu,
        view_proj: Mat4,
        meshes: &GpuMeshes,
        draw: &[MeshKey],
    ) -> Result<Frame> {
        self.render_then(gpu, view_proj, meshes, draw, |_, _| Ok(()))
    }

    /// [`render`](Offscreen::render), with `overlay` encoding more drawing onto the
    /// colour target (its view given) before the image is read back: a heads-up
    /// display, bounding boxes.
    pub fn render_then(
        &self,
        gpu: &Gpu,
        view_proj: Mat4,
        meshes: &GpuMeshes,
        draw: &[MeshKey],
        overlay: impl FnOnce(&mut wgpu::CommandEncoder, &wgpu::TextureView) -> Result<()>,
    ) -> Result<Frame> {
        let view = SceneView {
            view_proj,
            viewport: None,
            wireframe: false,
            fade: None,
        };
        self.render_view(gpu, view, meshes, draw, overlay)
    }

    /// Draws `draw` as `view` says (as lines where [`Offscreen::wireframe`] asks),
    /// then `overlay`, and reads the image back.
    fn render_view(
        &self,
        gpu: &Gpu,
        view: SceneView,
        meshes: &GpuMeshes,
        draw: &[MeshKey],
        overlay: impl FnOnce(&mut wgpu::CommandEncoder, &wgpu::TextureView) -> Result<()>,
    ) -> Result<Frame> {
        let [colour, ids, depth] = &self.views;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        self.scene.encode(
            gpu,
            &mut encoder,
            [colour, ids, depth],
            meshes,
            draw,
            &SceneView {
                wireframe: self.wireframe,
                ..view
            },
        )?;
        overlay(&mut encoder, colour)?;
        let [colour_buf, id_buf] = &self.readback;
        self.copy_out(&mut encoder, &self.colour, colour_buf);
        self.copy_out(&mut encoder, &self.ids, id_buf);
        gpu.queue.submit([encoder.finish()]);
        let rgba = self.read(gpu, colour_buf)?;
        let raw = self.read(gpu, id_buf)?;
        let objects = raw
            .chunks_exact(4)
            .map(|b| {
                let v = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                v.checked_sub(1)
                    .filter(|&slot| slot != GROUND_SLOT)
                    .and_then(|slot| meshes.object_in(slot))
            })
            .collect();
        Ok(Frame {
            width: self.width,
            height: self.height,
            rgba,
            objects,
        })
    }

    /// Copies `texture` into `buffer`, rows padded as wgpu requires.
    fn copy_out(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        texture: &wgpu::Texture,
        buffer: &wgpu::Buffer,
    ) {
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded_row(self.width)),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
    }

    /// The buffer's rows without their padding.
    fn read(&self, gpu: &Gpu, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
        let (row, padded) = (4 * self.width as usize, padded_row(self.width) as usize);
        gpu.read_mapped(buffer, "the frame", |data| {
            let mut out = Vec::with_capacity(row * self.height as usize);
            for r in 0..self.height as usize {
                out.extend_from_slice(&data[r * padded..r * padded + row]);
            }
            out
        })
    }
}

/// Bytes per row of a `width`-pixel image (4 bytes a pixel) in a copy, padded as wgpu
/// requires.
fn padded_row(width: u32) -> u32 {
    (4 * width).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
}
