//! The heads-up display: text and a frame-time graph drawn on the CPU into an image
//! (pure, so tests can check it pixel by pixel), then blended onto a render target as
//! one textured quad.

use image::{Rgba, RgbaImage};

use crate::scene::overlay_pass;
use crate::Gpu;
use flaneur::error::{Error, Result};

/// Room around the text and the graph, and between them, in font pixels.
const PAD: u32 = 4;
/// A line's height in font pixels: the 8-pixel glyph and a gap under it.
const LINE: u32 = 10;
/// The graph's height in font pixels, one a millisecond, and its least width.
const GRAPH_HEIGHT: u32 = 64;
const GRAPH_MIN_WIDTH: u32 = 120;
/// The most the HUD shows: beyond these it would cover any screen, and the caps keep
/// its image small whatever the content.
const MAX_SCALE: u32 = 8;
const MAX_LINES: usize = 48;
const MAX_COLUMNS: usize = 160;
/// How far the HUD sits from the target's top-left corner, in target pixels.
const MARGIN: u32 = 8;

const PANEL: Rgba<u8> = Rgba([12, 14, 20, 176]);
const TEXT: Rgba<u8> = Rgba([235, 235, 235, 255]);
const GREEN: Rgba<u8> = Rgba([70, 200, 90, 255]);
const YELLOW: Rgba<u8> = Rgba([230, 200, 50, 255]);
const RED: Rgba<u8> = Rgba([230, 60, 50, 255]);
const LIMIT_LINE: Rgba<u8> = Rgba([200, 200, 200, 255]);

/// What the heads-up display shows: lines of text (ASCII; anything else drawn as '?'),
/// and a small graph of recent frame times in milliseconds (newest last), with a line
/// at 50 ms.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HudContent {
    pub lines: Vec<String>,
    pub frame_ms: Vec<f32>,
}

/// The HUD drawn on the CPU: the 8×8 font scaled by `scale` (1 to 8; others are
/// clamped), on a translucent dark panel covering the whole image, the text starting
/// 4·`scale` pixels from its top-left corner, one line every 10·`scale` pixels (at most
/// 48 lines of 160 characters; the rest is cut). Under the text, the graph: 64·`scale`
/// pixels high and as wide as the text (at least 120·`scale`), a bar `scale` pixels
/// wide per frame, newest on the right, `scale` pixels high a millisecond (up to 64),
/// green under 33 ms, yellow under 50 ms, red from there; a thin light line across it
/// at 50 ms.
///
/// ```
/// use flaneur_render::{rasterise, HudContent};
///
/// let content = HudContent {
///     lines: vec!["12.5 ms".into()],
///     frame_ms: vec![12.5, 40.0, 70.0],
/// };
/// let image = rasterise(&content, 2);
/// assert!(image.width() >= 2 * 120 && image.height() > 2 * 64);
/// // The first row of '1' lights its fourth pixel: opaque text.
/// assert_eq!(image.get_pixel(8 + 2 * 3, 8).0[3], 255);
/// ```
pub fn rasterise(content: &HudContent, scale: u32) -> RgbaImage {
    let s = scale.clamp(1, MAX_SCALE);
    let lines = &content.lines[..content.lines.len().min(MAX_LINES)];
    let columns = lines.iter().map(|l| l.chars().count()).max().unwrap_or(0);
    let graph_width = (8 * columns.min(MAX_COLUMNS) as u32).max(GRAPH_MIN_WIDTH);
    let graph_top = PAD + LINE * lines.len() as u32;
    let (width, height) = (graph_width + 2 * PAD, graph_top + GRAPH_HEIGHT + PAD);
    let mut image = RgbaImage::from_pixel(s * width, s * height, PANEL);
    // Everything below is laid out in font pixels, each a `s` × `s` square.
    let mut paint = |x: u32, y: u32, w: u32, h: u32, colour| {
        for py in s * y..s * (y + h) {
            for px in s * x..s * (x + w) {
                image.put_pixel(px, py, colour);
            }
        }
    };

    for (row, line) in (0..).zip(lines) {
        for (column, c) in (0..).zip(line.chars().take(MAX_COLUMNS)) {
            let c = if c.is_ascii() { c } else { '?' };
            let (x0, y0) = (PAD + 8 * column, PAD + LINE * row);
            for (y, bits) in (0..).zip(font8x8::legacy::BASIC_LEGACY[c as usize]) {
                for x in (0..8).filter(|x| bits & (1 << x) != 0) {
                    paint(x0 + x, y0 + y, 1, 1, TEXT);
                }
            }
        }
    }

    let bottom = graph_top + GRAPH_HEIGHT;
    let bars = content.frame_ms.len().min(graph_width as usize);
    let shown = &content.frame_ms[content.frame_ms.len() - bars..];
    let first = PAD + graph_width - bars as u32;
    for (x, &ms) in (first..).zip(shown) {
        // NaN and negative times draw no bar; the graph tops out at 64 ms.
        let h = ms.max(0.0).min(GRAPH_HEIGHT as f32).round() as u32;
        let colour = if ms < 33.0 {
            GREEN
        } else if ms < 50.0 {
            YELLOW
        } else {
            RED
        };
        paint(x, bottom - h, 1, h, colour);
    }
    paint(PAD, bottom - 50, graph_width, 1, LIMIT_LINE);
    image
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Quad {
    rect: [f32; 4],
    origin: [f32; 4],
}

/// The texture the HUD image goes to, and the bind group that shows it.
struct Upload {
    texture: wgpu::Texture,
    bind_group: wgpu::BindGroup,
    size: (u32, u32),
}

/// The HUD on the GPU: [`rasterise`]d, uploaded, and drawn as one quad blended
/// (straight alpha) onto whatever a target already shows, 8 pixels from its top-left
/// corner. Its texture is kept while the image does not outgrow it, so a steady HUD
/// allocates nothing per frame.
///
/// Each [`draw`](Hud::draw) writes the texture and the quad through the queue, which
/// applies them before the next submission's commands: draw once per submission.
pub struct Hud {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    quad: wgpu::Buffer,
    texels: wgpu::TextureFormat,
    upload: Option<Upload>,
}

impl Hud {
    /// For targets of `format` (e.g. [`Offscreen::colour_format`](crate::Offscreen::colour_format),
    /// or a window surface's format); an error where `format` cannot be blended onto.
    pub fn new(gpu: &Gpu, format: wgpu::TextureFormat) -> Result<Hud> {
        let features = format.guaranteed_format_features(gpu.device.features());
        if !features
            .allowed_usages
            .contains(wgpu::TextureUsages::RENDER_ATTACHMENT)
            || !features
                .flags
                .contains(wgpu::TextureFormatFeatureFlags::BLENDABLE)
        {
            return Err(Error::Invalid(format!(
                "the HUD cannot be blended onto a {format:?} target"
            )));
        }
        let device = &gpu.device;
        let shader = device.create_shader_module(wgpu::include_wgsl!("hud.wgsl"));
        let quad = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("hud quad"),
            size: std::mem::size_of::<Quad>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("hud"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("hud"),
            bind_group_layouts: &[Some(&layout)],
            ..Default::default()
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("hud"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &shader,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            fragment: Some(wgpu::FragmentState {
                module: &shader,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format,
                    blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            multiview_mask: None,
            cache: None,
        });
        // The image's bytes are sRGB: an sRGB target blends in linear light and encodes
        // back, so the texture decodes them; any other target takes them as they are.
        let texels = if format.is_srgb() {
            wgpu::TextureFormat::Rgba8UnormSrgb
        } else {
            wgpu::TextureFormat::Rgba8Unorm
        };
        Ok(Hud {
            pipeline,
            layout,
            quad,
            texels,
            upload: None,
        })
    }

    /// The size of the texture the HUD is uploaded to; (0, 0) before the first draw.
    pub fn texture_size(&self) -> (u32, u32) {
        self.upload.as_ref().map_or((0, 0), |u| u.size)
    }

    /// Rasterises `content` at `scale` and encodes drawing it onto `target`, a view of a
    /// `target_size` texture, clipped to the target. A target of zero size is an error.
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        target_size: (u32, u32),
        content: &HudContent,
        scale: u32,
    ) -> Result<()> {
        let (tw, th) = target_size;
        if tw == 0 || th == 0 {
            return Err(Error::Invalid(format!(
                "a HUD target of {tw} × {th} pixels: each side must be at least 1"
            )));
        }
        let image = rasterise(content, scale);
        // Clipped here rather than by the GPU, so the texture never exceeds the target.
        let max = gpu.device.limits().max_texture_dimension_2d;
        let w = image.width().min(tw.saturating_sub(MARGIN)).min(max);
        let h = image.height().min(th.saturating_sub(MARGIN)).min(max);
        if w == 0 || h == 0 {
            return Ok(());
        }
        let upload = Upload::fit(
            &mut self.upload,
            gpu,
            &self.layout,
            &self.quad,
            self.texels,
            (w, h),
        );
        gpu.queue.write_texture(
            upload.texture.as_image_copy(),
            &image,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * image.width()),
                rows_per_image: Some(image.height()),
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        let clip_x = |px: u32| 2.0 * px as f32 / tw as f32 - 1.0;
        let clip_y = |px: u32| 1.0 - 2.0 * px as f32 / th as f32;
        let quad = Quad {
            rect: [
                clip_x(MARGIN),
                clip_y(MARGIN),
                clip_x(MARGIN + w),
                clip_y(MARGIN + h),
            ],
            origin: [MARGIN as f32, MARGIN as f32, 0.0, 0.0],
        };
        gpu.queue
            .write_buffer(&self.quad, 0, bytemuck::bytes_of(&quad));
        let mut pass = overlay_pass(encoder, target, "hud");
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &upload.bind_group, &[]);
        pass.draw(0..6, 0..1);
        Ok(())
    }
}

impl Upload {
    /// The texture in `slot` if it holds `w` × `h` texels, else a new one large enough
    /// for both, so that the size settles after a few frames.
    fn fit<'a>(
        slot: &'a mut Option<Upload>,
        gpu: &Gpu,
        layout: &wgpu::BindGroupLayout,
        quad: &wgpu::Buffer,
        format: wgpu::TextureFormat,
        (w, h): (u32, u32),
    ) -> &'a Upload {
        let upload = match slot.take() {
            Some(u) if w <= u.size.0 && h <= u.size.1 => u,
            old => {
                let (old_w, old_h) = old.map_or((0, 0), |u| u.size);
                Upload::new(gpu, layout, quad, format, (w.max(old_w), h.max(old_h)))
            }
        };
        slot.insert(upload)
    }

    fn new(
        gpu: &Gpu,
        layout: &wgpu::BindGroupLayout,
        quad: &wgpu::Buffer,
        format: wgpu::TextureFormat,
        size: (u32, u32),
    ) -> Upload {
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("hud"),
            size: wgpu::Extent3d {
                width: size.0,
                height: size.1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hud"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: quad.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
            ],
        });
        Upload {
            texture,
            bind_group,
            size,
        }
    }
}
