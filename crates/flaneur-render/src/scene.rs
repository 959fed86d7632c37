//! The scene pass, shared by the offscreen targets and the window: one pipeline that
//! draws the resident meshes and a ground plane into a colour target and, in the same
//! pass, each pixel's object slot into an id target, over a depth buffer. Flat shading
//! by a fixed sun, each object its own tint (from its id, the same in whatever slot).
//!
//! A camera's picture is drawn without a far plane: the query's far plane (the
//! camera's `far`, REVIEW's 1 km eyesight) chooses what is drawn, and what it chose is
//! drawn whole, its foot included where that lies past the plane. The picture fades
//! into the sky with the distance across the ground ([`Fade`]), ending where the
//! eyesight could miss something, so that neither the edge of what was loaded nor a
//! building cut off from the ground shows.

use glam::{Mat4, Vec3, Vec4};
use wgpu::util::DeviceExt;

use crate::meshes::{GpuMeshes, MeshKey, Vertex};
use crate::Gpu;
use flaneur::error::{Error, Result};
use flaneur::geom::{Aabb, Camera};

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
/// Where the fade into the sky starts, as a share of the distance where it ends.
const FADE_FROM: f32 = 0.6;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    sun: [f32; 4],
    sky: [f32; 4],
    /// The eye's x and z, and the fade's start and end; an end below 0: no fade.
    fade: [f32; 4],
}

/// How a frame looks at the scene: the camera's transform, the part of the targets it
/// fills (x, y, width, height in pixels; `None`: all of them), whether as lines, and
/// how it fades into the sky (`None`: not at all).
#[derive(Clone, Copy, Debug)]
pub struct SceneView {
    pub view_proj: Mat4,
    pub viewport: Option<[f32; 4]>,
    pub wireframe: bool,
    pub fade: Option<Fade>,
}

/// How a picture fades into the sky with the distance across the ground from the eye
/// (not along the ray, so that a wall fades evenly from its top to its foot, and as
/// the ground it stands on): untouched up to `from` metres, the sky's colour from `to`
/// on, where the id target shows the sky too.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fade {
    /// The eye's x and z, metres.
    pub eye: [f32; 2],
    pub from: f32,
    pub to: f32,
}

impl Fade {
    /// The fade for `camera` over a city whose objects lie between heights
    /// `floor` and `roof` (metres): it ends where a point of the city at that distance
    /// across the ground may be farther from the eye than `camera.far`, the eyesight
    /// the query selected by. Nearer, every point is within the eyesight, so whatever
    /// shows there was selected and drawn whole; farther, nothing shows, so neither a
    /// building the query missed nor the edge of what it read can be seen. From 250 m
    /// above a city of low buildings with a 1 km eyesight it ends at 968 m; at street
    /// level among 100 m towers, at 995 m.
    ///
    /// ```
    /// use flaneur::geom::Camera;
    /// use flaneur_render::Fade;
    /// # fn main() -> flaneur::Result<()> {
    /// let high = Camera::new(glam::Vec3::new(0.0, 250.0, 0.0), 0.0, -0.5)?;
    /// let fade = Fade::for_camera(&high, (0.0, 40.0));
    /// assert!((fade.to - 968.2).abs() < 0.1 && fade.from < fade.to);
    /// # Ok(()) }
    /// ```
    pub fn for_camera(camera: &Camera, (floor, roof): (f32, f32)) -> Fade {
        let y = camera.position.y;
        let rise = (y - floor).abs().max((roof - y).abs());
        let to = (camera.far * camera.far - rise * rise).max(0.0).sqrt();
        Fade {
            eye: [camera.position.x, camera.position.z],
            from: FADE_FROM * to,
            to,
        }
    }
}

/// Projection × view that draws `camera` into an image of `aspect` (width / height):
/// [`Camera::view_proj`]'s, but with no far plane (depth reaches 1 at infinity), so
/// that the query's far plane, which chose what is drawn, cuts none of it. Its depth
/// precision is the same: a perspective depth's is set by the near plane. Errors as
/// [`Camera::view_proj`] does.
pub fn drawing_view_proj(camera: &Camera, aspect: f32) -> Result<Mat4> {
    camera.validate()?;
    if !(aspect.is_finite() && aspect > 0.0) {
        return Err(Error::Invalid(format!(
            "aspect {aspect} must be a positive number"
        )));
    }
    let focal = 1.0 / (camera.fov_y * 0.5).tan();
    let proj = Mat4::from_cols(
        Vec4::new(focal / aspect, 0.0, 0.0, 0.0),
        Vec4::new(0.0, focal, 0.0, 0.0),
        Vec4::new(0.0, 0.0, -1.0, -1.0),
        Vec4::new(0.0, 0.0, -camera.near, 0.0),
    );
    // Right-handed, looking down −z: the camera's own axes.
    let (p, r, u, f) = (
        camera.position,
        camera.right(),
        camera.up(),
        camera.forward(),
    );
    let view = Mat4::from_cols(
        Vec4::new(r.x, u.x, -f.x, 0.0),
        Vec4::new(r.y, u.y, -f.y, 0.0),
        Vec4::new(r.z, u.z, -f.z, 0.0),
        Vec4::new(-r.dot(p), -u.dot(p), f.dot(p), 1.0),
    );
    Ok(proj * view)
}

/// The scene's pipeline for one colour format, and the ground.
pub struct ScenePass {
    pipeline: wgpu::RenderPipeline,
    /// The same drawing as lines, where the device can (`POLYGON_MODE_LINE`).
    wireframe: Option<wgpu::RenderPipeline>,
    globals: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    ground: Option<wgpu::Buffer>,
    /// The heights the city's objects lie between (from the ground's city), what the
    /// fade of a camera's picture is worked out from.
    heights: Option<(f32, f32)>,
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
            heights: None,
        }
    }

    /// Whether the pass can draw wireframe.
    pub fn has_wireframe(&self) -> bool {
        self.wireframe.is_some()
    }

    /// Draws a ground under `city`: a plane at its lowest point reaching `margin`
    /// metres past it on every side (the database holds buildings, not the ground
    /// between them). The id target shows the ground as the sky. The city's heights
    /// also set where a camera's picture fades ([`ScenePass::camera_view`]).
    pub fn set_ground(&mut self, gpu: &Gpu, city: &Aabb, margin: f32) {
        self.heights = Some((city.min.y, city.max.y));
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

    /// How `camera` is drawn over the whole of a target of `aspect` (width / height):
    /// without a far plane ([`drawing_view_proj`]), fading into the sky as
    /// [`Fade::for_camera`] says for the ground's city (a city at the eye's height
    /// before [`ScenePass::set_ground`]).
    pub fn camera_view(&self, camera: &Camera, aspect: f32) -> Result<SceneView> {
        let y = camera.position.y;
        Ok(SceneView {
            view_proj: drawing_view_proj(camera, aspect)?,
            viewport: None,
            wireframe: false,
            fade: Some(Fade::for_camera(camera, self.heights.unwrap_or((y, y)))),
        })
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
            fade,
        } = *view;
        let sun = Vec3::new(0.4, 0.8, 0.3).normalize();
        let fade = fade.map_or([0.0, 0.0, 0.0, -1.0], |f| {
            [f.eye[0], f.eye[1], f.from, f.to]
        });
        gpu.queue.write_buffer(
            &self.globals,
            0,
            bytemuck::bytes_of(&Globals {
                view_proj: view_proj.to_cols_array_2d(),
                sun: [sun.x, sun.y, sun.z, 0.0],
                sky: [SKY.r as f32, SKY.g as f32, SKY.b as f32, 1.0],
                fade,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_drawing_projection_is_the_cameras_without_its_far_plane() {
        let camera = Camera::new(Vec3::new(30.0, 250.0, -40.0), 0.7, -0.5)
            .unwrap()
            .with_fov(1.1, 0.8)
            .unwrap();
        let aspect = camera.aspect();
        let (query, drawing) = (
            camera.view_proj(aspect).unwrap(),
            drawing_view_proj(&camera, aspect).unwrap(),
        );
        let (f, r, u) = (camera.forward(), camera.right(), camera.up());
        for (along, side, up) in [
            (1.0, 0.0, 0.0),
            (400.0, 90.0, -60.0),
            (999.0, -300.0, 200.0),
        ] {
            let p = camera.position + f * along + r * side + u * up;
            let (a, b) = (query.project_point3(p), drawing.project_point3(p));
            // The same place in the picture, and depth in the same order.
            assert!((a.truncate() - b.truncate()).length() < 1e-4, "{a} {b}");
            assert!((0.0..1.0).contains(&b.z), "{b}");
        }
        // Past the far plane: out of the camera's clip volume, within the drawing's.
        let past = camera.position + f * 1500.0;
        assert!(query.project_point3(past).z > 1.0);
        let z = drawing.project_point3(past).z;
        assert!(z > drawing.project_point3(camera.position + f * 999.0).z && z < 1.0);
        assert!(drawing_view_proj(&camera, 0.0).is_err());
    }

    #[test]
    fn the_fade_ends_where_the_eyesight_could_miss_something() {
        // At street level among 100 m towers, and high over low roofs.
        let street = Camera::new(Vec3::new(0.0, 1.7, 0.0), 0.0, 0.0).unwrap();
        let fade = Fade::for_camera(&street, (0.0, 100.0));
        assert!((fade.to - 995.2).abs() < 0.1, "{fade:?}");
        assert!((fade.from - 0.6 * fade.to).abs() < 1e-3);
        let high = Camera::new(Vec3::new(5.0, 1200.0, 7.0), 0.0, -1.0).unwrap();
        let fade = Fade::for_camera(&high, (0.0, 40.0));
        assert_eq!((fade.eye, fade.to), ([5.0, 7.0], 0.0));
    }
}
