//! Drawing into textures instead of a window, and reading the pixels back: the colour
//! image and, in the same pass, the id of the object each pixel shows.

use glam::{Mat4, Vec3};

use super::meshes::{GpuMeshes, MeshKey, Vertex};
use super::Gpu;
use crate::error::{Error, Result};
use crate::geom::{Aabb, Camera};
use wgpu::util::DeviceExt;

const COLOUR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
const ID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The sky's colour (linear), a pale blue.
const SKY: wgpu::Color = wgpu::Color {
    r: 0.52,
    g: 0.66,
    b: 0.85,
    a: 1.0,
};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    sun: [f32; 4],
}

/// A rendered image: RGBA8 (sRGB) pixels and each pixel's object, rows top first.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    /// The object each pixel shows; `None` for the sky.
    pub objects: Vec<Option<u64>>,
}

/// The pipeline and the render targets of one image size.
pub struct Offscreen {
    pipeline: wgpu::RenderPipeline,
    globals: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    colour: wgpu::Texture,
    ids: wgpu::Texture,
    // Made once with the targets, so that a frame allocates nothing but its commands.
    views: [wgpu::TextureView; 3],
    readback: [wgpu::Buffer; 2],
    ground: Option<wgpu::Buffer>,
    width: u32,
    height: u32,
}

/// The ground's slot: the id target shows it as the sky, nothing the database holds.
const GROUND_SLOT: u32 = u32::MAX;

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
        let shader = device.create_shader_module(wgpu::include_wgsl!("shader.wgsl"));
        let globals = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("globals"),
            size: std::mem::size_of::<Globals>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("globals"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("globals"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: globals.as_entire_binding(),
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("objects"),
            bind_group_layouts: &[Some(&layout)],
            ..Default::default()
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("objects"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &shader,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[Some(Vertex::LAYOUT)],
            },
            fragment: Some(wgpu::FragmentState {
                module: &shader,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(COLOUR_FORMAT.into()), Some(ID_FORMAT.into())],
            }),
            primitive: wgpu::PrimitiveState {
                // Both sides: a ray meets a triangle from either, and so does the id pass.
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        let target = |label, format, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let readable = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
        let colour = target("colour", COLOUR_FORMAT, readable);
        let ids = target("ids", ID_FORMAT, readable);
        let depth = target(
            "depth",
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
            pipeline,
            globals,
            bind_group,
            colour,
            ids,
            views,
            readback,
            ground: None,
            width,
            height,
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
    /// metres past it on every side (the database holds buildings, not the ground
    /// between them). The id target shows the ground as the sky.
    pub fn set_ground(&mut self, gpu: &Gpu, city: &Aabb, margin: f32) {
        let (lo, hi, y) = (city.min - margin, city.max + margin, city.min.y);
        let corner = |x: f32, z: f32| Vertex {
            position: [x, y, z],
            normal: [0.0, 1.0, 0.0],
            slot: GROUND_SLOT,
            key: 0,
        };
        let quad = [
            corner(lo.x, lo.z),
            corner(hi.x, hi.z),
            corner(hi.x, lo.z),
            corner(lo.x, lo.z),
            corner(lo.x, hi.z),
            corner(hi.x, hi.z),
        ];
        self.ground = Some(
            gpu.device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("ground"),
                    contents: bytemuck::cast_slice(&quad),
                    usage: wgpu::BufferUsages::VERTEX,
                }),
        );
    }

    /// Draws `draw` as `camera` sees it, its vertical field of view kept and its
    /// horizontal one fitted to the image.
    pub fn render_camera(
        &self,
        gpu: &Gpu,
        camera: &Camera,
        meshes: &GpuMeshes,
        draw: &[MeshKey],
    ) -> Result<Frame> {
        let (camera, aspect) = self.fitted(camera)?;
        self.render(gpu, camera.view_proj(aspect)?, meshes, draw)
    }

    /// `camera` with its vertical field of view kept and its horizontal one fitted to
    /// the image, and the image's aspect (width / height).
    pub fn fitted(&self, camera: &Camera) -> Result<(Camera, f32)> {
        let aspect = self.width as f32 / self.height as f32;
        let fitted = camera.with_fov(super::fov_x_for(camera.fov_y, aspect), camera.fov_y)?;
        Ok((fitted, aspect))
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
        let sun = Vec3::new(0.4, 0.8, 0.3).normalize();
        gpu.queue.write_buffer(
            &self.globals,
            0,
            bytemuck::bytes_of(&Globals {
                view_proj: view_proj.to_cols_array_2d(),
                sun: [sun.x, sun.y, sun.z, 0.0],
            }),
        );
        let [colour, ids, depth] = &self.views;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("objects"),
                color_attachments: &[
                    Some(wgpu::RenderPassColorAttachment {
                        view: colour,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(SKY),
                            store: wgpu::StoreOp::Store,
                        },
                    }),
                    Some(wgpu::RenderPassColorAttachment {
                        view: ids,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    }),
                ],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            if let Some(ground) = &self.ground {
                pass.set_vertex_buffer(0, ground.slice(..));
                pass.draw(0..6, 0..1);
            }
            for &(id, level) in draw {
                let m = meshes.get((id, level)).ok_or_else(|| {
                    Error::Invalid(format!("object {id} at level {level} is not on the GPU"))
                })?;
                pass.set_vertex_buffer(0, m.vertices.slice(..));
                pass.set_index_buffer(m.indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..m.index_count, 0, 0..1);
            }
        }
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
        let slice = buffer.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        gpu.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Render(format!("waiting for the frame: {e}")))?;
        rx.recv()
            .map_err(|e| Error::Render(format!("reading the frame back: {e}")))?
            .map_err(|e| Error::Render(format!("reading the frame back: {e}")))?;
        let data = slice
            .get_mapped_range()
            .map_err(|e| Error::Render(format!("reading the frame back: {e}")))?;
        let (row, padded) = (4 * self.width as usize, padded_row(self.width) as usize);
        let mut out = Vec::with_capacity(row * self.height as usize);
        for r in 0..self.height as usize {
            out.extend_from_slice(&data[r * padded..r * padded + row]);
        }
        drop(data);
        buffer.unmap();
        Ok(out)
    }
}

/// Bytes per row of a `width`-pixel image (4 bytes a pixel) in a copy, padded as wgpu
/// requires.
fn padded_row(width: u32) -> u32 {
    (4 * width).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
}
