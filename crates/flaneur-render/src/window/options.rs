//! What the window is opened with and what it hands back: the options and the
//! session's summary. Apart
//! from the window's workings because they are plain data that the CLI, the demo and
//! the tests make and read without touching winit or wgpu.

use flaneur::geom::Aabb;
use flaneur::walk::path::{CameraPath, Pose};

/// How the window opens.
#[derive(Clone, Debug)]
pub struct ViewOptions {
    /// The window's title, and its size in pixels.
    pub title: String,
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
    /// The DoV threshold η of the VISUAL and VSC modes.
    pub eta: f32,
    /// The PB mode's polygon budget, triangles a frame.
    pub polygon_budget: u64,
    /// Whether the landmarks are refined for the next frame on the thread pool while a
    /// frame draws (Adapt and Display, [`FrameSink::lod_adapt_ahead`]).
    ///
    /// [`FrameSink::lod_adapt_ahead`]: flaneur::walk::FrameSink::lod_adapt_ahead
    pub adapt_ahead: bool,
}

impl ViewOptions {
    /// Walking a city within `city` from `start`: a 1024 × 768 window titled
    /// "flaneur", LODs under the thesis's τ, VISUAL under its η, a 256 MiB GPU budget, a
    /// walker's pace, and
    /// the ground, at the city's foot, reaching the default frustum's depth past it.
    pub fn new(city: Aabb, start: Pose) -> ViewOptions {
        ViewOptions {
            title: "flaneur".into(),
            size: (1024, 768),
            lod_tau: Some(flaneur::walk::lod_select::DEFAULT_TAU),
            start,
            ground: city.min.y,
            city,
            margin: flaneur::geom::DEFAULT_FAR,
            play: None,
            gpu_budget: Some(256 << 20),
            speed: flaneur::walk::WALK_SPEED,
            eta: flaneur::walk::visual::DEFAULT_ETA,
            polygon_budget: flaneur::walk::live::DEFAULT_BUDGET,
            adapt_ahead: false,
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
