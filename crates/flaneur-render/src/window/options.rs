//! What the window is opened with and what it hands back: the options and the
//! session's summary. Apart
//! from the window's workings because they are plain data that the CLI, the demo and
//! the tests make and read without touching winit or wgpu.

use flaneur::geom::Aabb;
use flaneur::path::{CameraPath, Pose};

/// How the window opens.
#[derive(Clone, Debug)]
pub struct ViewOptions {
    /// The window's title, and its size in pixels.
    pub title: String,
    pub size: (u32, u32),
    /// Whether the window opens smaller than `size` where the screen is too small for
    /// it: shrunk, its shape kept, to 90 % of the screen each way at most (the rest left
    /// to its title bar and borders, and the desktop's panels). On for the default
    /// size, off for a size asked for.
    pub fit_screen: bool,
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
    /// The rule that picks the VISUAL, VSC and PB modes' internal LODs and levels, under
    /// `lod_tau`: ours (screen) or the thesis's.
    pub selection: flaneur::hdov::Selection,
    /// Whether the landmarks are refined for the next frame on the thread pool while a
    /// frame draws (Adapt and Display, [`FrameSink::lod_adapt_ahead`]).
    ///
    /// [`FrameSink::lod_adapt_ahead`]: flaneur::walk::FrameSink::lod_adapt_ahead
    pub adapt_ahead: bool,
}

impl ViewOptions {
    /// Walking a city within `city` from `start`: a 1024 × 768 window titled
    /// "flaneur" (smaller on a smaller screen, [`ViewOptions::fit_screen`]), LODs under
    /// the thesis's τ, VISUAL under its η, a 256 MiB GPU budget, a walker's pace, and
    /// the ground, at the city's foot, reaching the default frustum's depth past it.
    pub fn new(city: Aabb, start: Pose) -> ViewOptions {
        ViewOptions {
            title: "flaneur".into(),
            size: (1024, 768),
            fit_screen: true,
            lod_tau: Some(flaneur::walk::lod_select::DEFAULT_TAU),
            start,
            ground: city.min.y,
            city,
            margin: flaneur::geom::DEFAULT_FAR,
            play: None,
            gpu_budget: Some(256 << 20),
            speed: flaneur::walk::WALK_SPEED,
            eta: flaneur::walk::visual::DEFAULT_ETA,
            polygon_budget: flaneur::walk::DEFAULT_BUDGET,
            selection: flaneur::hdov::Selection::Screen,
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

/// How much of the screen the first window may take each way, when it fits itself.
const SCREEN_SHARE: u64 = 90;

/// `size` shrunk to fit within [`SCREEN_SHARE`] % of a screen of `screen` pixels each
/// way, its shape kept (as nearly as whole pixels allow); `size` itself where it fits
/// already, or where the screen's size is unknown (0).
pub(super) fn fit_to_screen((w, h): (u32, u32), (sw, sh): (u32, u32)) -> (u32, u32) {
    if sw == 0 || sh == 0 || w == 0 || h == 0 {
        return (w, h);
    }
    let (room_w, room_h) = (
        sw as u64 * SCREEN_SHARE / 100,
        sh as u64 * SCREEN_SHARE / 100,
    );
    let (w64, h64) = (w as u64, h as u64);
    if w64 <= room_w && h64 <= room_h {
        return (w, h);
    }
    // The tighter side decides: the other is scaled by the same ratio, rounded down.
    if w64 * room_h > h64 * room_w {
        (room_w as u32, ((h64 * room_w / w64) as u32).max(1))
    } else {
        (((w64 * room_h / h64) as u32).max(1), room_h as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::fit_to_screen;

    #[test]
    fn the_first_window_fits_the_screen() {
        // Fits: kept.
        assert_eq!(fit_to_screen((1024, 768), (1920, 1080)), (1024, 768));
        assert_eq!(fit_to_screen((1024, 768), (1280, 1024)), (1024, 768));
        // Too tall for a 720-pixel screen: 90 % of its height, the shape kept.
        assert_eq!(fit_to_screen((1024, 768), (1280, 720)), (864, 648));
        // Too wide: the width decides.
        assert_eq!(fit_to_screen((2000, 500), (1000, 1000)), (900, 225));
        // An unknown screen leaves the size alone.
        assert_eq!(fit_to_screen((1024, 768), (0, 0)), (1024, 768));
        assert_eq!(fit_to_screen((5000, 1), (100, 100)), (90, 1));
    }
}
