//! The scene pass, shared by the offscreen targets and the window: one pipeline that
//! draws the resident meshes and a ground plane into a colour target and, in the same
//! pass, each pixel's object slot into an id target, over a depth buffer. Flat shading
//! by a fixed sun, each object its own tint (from its id, the same in whatever slot).

use glam::{Mat4, Vec3};
use wgpu::util::DeviceExt;

use crate::meshes::{GpuMeshes, MeshKey, Vertex};
use crate::Gpu;
use flaneur::error::{Error, Result};
use flaneur::geom::Aabb;

pub(crate) const ID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The sky's colour (linear), a pale blue.
pub(crate) const SKY: wgpu::Color = wgpu::Color {
    r: 0.52,
    g: 0.66,
    b: 0.85,
    a: 1.0,
};
/// The ground's slot: the id target shows it as the sky, nothing the database holds.
pub(crate) const GROUND_SLOT: u32 = u32::MAX;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    sun: [f32; 4],
}

/// How a frame looks at the scene: the camera's transform, the part of the targets it
/// fills (x, y, width, height in pixels; `None`: all of them), and whether as lines.
#[derive(Clone, Copy, Debug)]
pub struct SceneView {
    pub view_proj: Mat4,
    pub viewport: Option<[f32; 4]>,
    pub wireframe: bool,
}

/// The scene's pipeline for one colour format, and the ground.
pub struct ScenePass {
    pipeline: wgpu::RenderPipeline,
    /// The same drawing as lines, where the device can (`POLYGON_MODE_LINE`).
    wireframe: Option<wgpu::RenderPipeline>,
    globals: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    ground: Option<wgpu::Buffer>,
}

impl ScenePass {
    /// A pass drawing into colour targets of `colour_format`.
    pub fn new(gpu: &Gpu, colour_format: wgpu::TextureFormat) -> ScenePass {
        let device = &gpu.device;
        let shader = device.create_shader_module(wgpu::include_wgsl!("shader.wgsl"));
        let (globals, layout, bind_group) = uniform(
            device,
            "globals",
            std::mem::size_of::<Globals>() as u64,
            wgpu::ShaderStages::VERTEX_FRAGMENT,
        );
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("objects"),
            bind_group_layouts: &[Some(&layout)],
            ..Default::default()
        });
        let pipeline = |polygon_mode| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
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
                    targets: &[Some(colour_format.into()), Some(ID_FORMAT.into())],
                }),
                primitive: wgpu::PrimitiveState {
                    // Both sides: a ray meets a triangle from either, and so does the id pass.
                    cull_mode: None,
                    polygon_mode,
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
            })
        };
        let wireframe = device
            .features()
            .contains(wgpu::Features::POLYGON_MODE_LINE)
            .then(|| pipeline(wgpu::PolygonMode::Line));
        ScenePass {
            pipeline: pipeline(wgpu::PolygonMode::Fill),
            wireframe,
            globals,
            bind_group,
            ground: None,
        }
    }

    /// Whether the pass can draw wireframe.
    pub fn has_wireframe(&self) -> bool {
        self.wireframe.is_some()
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

    /// Encodes drawing `draw` (objects at a level, each resident in `meshes`) with
    /// `view_proj` into `targets` (colour, ids, depth), cleared first; as lines when
    /// the view says so and the device can.
    pub fn encode(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        targets: [&wgpu::TextureView; 3],
        meshes: &GpuMeshes,
        draw: &[MeshKey],
        view: &SceneView,
    ) -> Result<()> {
        let SceneView {
            view_proj,
            viewport,
            wireframe,
        } = *view;
        let sun = Vec3::new(0.4, 0.8, 0.3).normalize();
        gpu.queue.write_buffer(
            &self.globals,
            0,
            bytemuck::bytes_of(&Globals {
                view_proj: view_proj.to_cols_array_2d(),
                sun: [sun.x, sun.y, sun.z, 0.0],
            }),
        );
        let [colour, ids, depth] = targets;
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
            if let Some([x, y, w, h]) = viewport {
                pass.set_viewport(x, y, w, h, 0.0, 1.0);
            }
            pass.set_pipeline(match (&self.wireframe, wireframe) {
                (Some(lines), true) => lines,
                _ => &self.pipeline,
            });
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
        Ok(())
    }
}

/// A 2D texture of `size` pixels to render into.
pub(crate) fn target(
    device: &wgpu::Device,
    label: &str,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
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
}

/// A uniform buffer of `size` bytes bound at group 0, binding 0, for `visibility`: the
/// buffer, and the layout and bind group a pipeline takes it by.
pub(crate) fn uniform(
    device: &wgpu::Device,
    label: &str,
    size: u64,
    visibility: wgpu::ShaderStages,
) -> (wgpu::Buffer, wgpu::BindGroupLayout, wgpu::BindGroup) {
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        }],
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: buffer.as_entire_binding(),
        }],
    });
    (buffer, layout, bind_group)
}

/// A pass drawing over what `target` already shows (no depth): overlays.
pub(crate) fn overlay_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    target: &wgpu::TextureView,
    label: &str,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            },
        })],
        ..Default::default()
    })
}
