//! Bounding boxes and the view frustum drawn as lines over a frame, coloured as the
//! thesis's Fig. 6.3 (Shou 2002): red for objects drawn at full detail (its leaf nodes),
//! yellow for objects drawn at a coarser level (where its traversal stopped at an
//! internal LOD), green for objects the walk holds but culled, white for the frustum.
//! Seen from above (the window's top view), they show what the walk selected and why.

use glam::{Mat4, Vec3};

use crate::scene::{overlay_pass, uniform};
use crate::Gpu;
use flaneur::error::Result;
use flaneur::geom::{box_corners, Aabb, Frustum, EDGES};
use flaneur::walk::lod_select::Drawn;

/// Line colours (linear RGBA).
pub const FULL: [f32; 4] = [0.9, 0.1, 0.1, 1.0];
pub const COARSE: [f32; 4] = [0.95, 0.85, 0.1, 1.0];
pub const CULLED: [f32; 4] = [0.1, 0.8, 0.2, 1.0];
pub const FRUSTUM: [f32; 4] = [1.0, 1.0, 1.0, 1.0];

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LineVertex {
    pub position: [f32; 3],
    pub colour: [f32; 4],
}

/// The lines of one frame: each box's 12 edges, and the frustum's.
///
/// ```
/// use flaneur::geom::{Aabb, Camera};
/// use flaneur_render::boxes::{lines, CULLED};
/// let camera = Camera::new(glam::Vec3::ZERO, 0.0, 0.0)?;
/// let held = [Aabb::new([-20.0, 0.0, -1.0], [-19.0, 1.0, 1.0])?]; // behind the eye
/// let v = lines(&camera.frustum(), &[], &held);
/// assert_eq!(v.len(), 2 * 12 * 2); // the frustum and one box, 12 edges of 2 ends
/// assert!(v[24..].iter().all(|l| l.colour == CULLED));
/// # Ok::<(), flaneur::Error>(())
/// ```
pub fn lines(frustum: &Frustum, drawn: &[Drawn], culled: &[Aabb]) -> Vec<LineVertex> {
    let mut out = Vec::with_capacity(24 * (1 + drawn.len() + culled.len()));
    let mut edges = |corners: &[Vec3; 8], colour: [f32; 4]| {
        for &(a, b) in &EDGES {
            for c in [corners[a], corners[b]] {
                out.push(LineVertex {
                    position: c.to_array(),
                    colour,
                });
            }
        }
    };
    edges(frustum.corners(), FRUSTUM);
    for d in drawn {
        let colour = if d.level == 0 { FULL } else { COARSE };
        edges(&box_corners(&d.bounds), colour);
    }
    for b in culled {
        edges(&box_corners(b), CULLED);
    }
    out
}

/// The line pipeline and a vertex buffer it reuses while the lines fit.
pub struct Boxes {
    pipeline: wgpu::RenderPipeline,
    globals: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    vertices: Option<wgpu::Buffer>,
}

impl Boxes {
    /// Lines for colour targets of `format`.
    pub fn new(gpu: &Gpu, format: wgpu::TextureFormat) -> Boxes {
        let device = &gpu.device;
        let shader = device.create_shader_module(wgpu::include_wgsl!("boxes.wgsl"));
        let (globals, layout, bind_group) =
            uniform(device, "boxes", 64, wgpu::ShaderStages::VERTEX);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("boxes"),
            bind_group_layouts: &[Some(&layout)],
            ..Default::default()
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("boxes"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &shader,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<LineVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4],
                })],
            },
            fragment: Some(wgpu::FragmentState {
                module: &shader,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::LineList,
                ..Default::default()
            },
            // Over the picture, not hidden by it: what the walk held is the point.
            depth_stencil: None,
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        Boxes {
            pipeline,
            globals,
            bind_group,
            vertices: None,
        }
    }

    /// Encodes drawing `lines` with `view_proj` over `target`, within `viewport` (x,
    /// y, width, height in pixels; `None`: all of it).
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        view_proj: Mat4,
        viewport: Option<[f32; 4]>,
        lines: &[LineVertex],
    ) -> Result<()> {
        if lines.is_empty() {
            return Ok(());
        }
        let bytes: &[u8] = bytemuck::cast_slice(lines);
        if self
            .vertices
            .as_ref()
            .is_none_or(|b| b.size() < bytes.len() as u64)
        {
            self.vertices = Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("box lines"),
                size: (bytes.len() as u64).next_power_of_two(),
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }));
        }
        let vertices = self.vertices.as_ref().expect("made above");
        gpu.queue.write_buffer(vertices, 0, bytes);
        gpu.queue.write_buffer(
            &self.globals,
            0,
            bytemuck::cast_slice(&view_proj.to_cols_array()),
        );
        let mut pass = overlay_pass(encoder, target, "boxes");
        if let Some([x, y, w, h]) = viewport {
            pass.set_viewport(x, y, w, h, 0.0, 1.0);
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.set_vertex_buffer(0, vertices.slice(..bytes.len() as u64));
        pass.draw(0..lines.len() as u32, 0..1);
        Ok(())
    }
}
