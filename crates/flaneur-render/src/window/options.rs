//! What the window is opened with and what it hands back: the options, the walk modes
//! it shows, the changes its keys ask of the walk, and the session's summary. Apart
//! from the window's workings because they are plain data that the CLI, the demo and
//! the tests make and read without touching winit or wgpu.

use flaneur::database::Database;
use flaneur::geom::Aabb;
use flaneur::walk::{CameraPath, Pose};

/// What the window asks the walk to change, when a key asks for it: the walk ends
/// its run and starts again from where the viewer stands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Change {
    /// REVIEW (CSearch with index cache and prefetching), plain BOX queries, or PVS.
    Mode(ViewMode),
    /// The object buffer's budget, times this factor.
    Budget(f32),
}

/// The walk modes the window can show so far.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewMode {
    Review,
    Box,
    /// The current viewcell's PVS, neighbours prefetched (a database built with
    /// visibility).
    Pvs,
}

impl ViewMode {
    pub fn name(self) -> &'static str {
        match self {
            ViewMode::Review => "review",
            ViewMode::Box => "box",
            ViewMode::Pvs => "pvs",
        }
    }
}

/// How the window opens.
#[derive(Clone, Debug)]
pub struct ViewOptions {
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
}

impl ViewOptions {
    /// Walking `db` from `start`: a 1024 × 768 window, LODs under the thesis's τ, a
    /// 256 MiB GPU budget, a walker's pace, and the ground reaching the default
    /// frustum's depth past the city.
    pub fn new(db: &Database, start: Pose) -> ViewOptions {
        ViewOptions {
            size: (1024, 768),
            lod_tau: Some(flaneur::walk::lod_select::DEFAULT_TAU),
            start,
            ground: db.bounds().min.y,
            city: db.bounds(),
            margin: flaneur::geom::DEFAULT_FAR,
            play: None,
            gpu_budget: Some(256 << 20),
            speed: flaneur::walk::steer::WALK_SPEED,
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
