//! The walk settings every walking experiment takes, as arguments.

use crate::cli::args::{finite_f32, frame_rate, pace_factor};
use flaneur::path::motion::Motion;
use flaneur::walk::settings;
use flaneur_bench::walk_setup::{self, WalkSetup};

use crate::cli::args::{or_default, pace};

/// The walk every walking experiment takes (`bench::walk_setup::WalkSetup`).
#[derive(clap::Args)]
pub struct WalkSetupArgs {
    #[arg(long, help = frames_help())]
    frames: Option<usize>,
    /// Frames a second of the walks, within [0.1, 1000].
    #[arg(long, default_value_t = walk_setup::DEFAULT_FPS, value_parser = frame_rate, allow_negative_numbers = true)]
    fps: f32,
    /// Seed of the walks' paths (and of bench csearch's street walk): the same seed,
    /// the same paths.
    #[arg(long, default_value_t = walk_setup::DEFAULT_SEED)]
    pub(super) seed: u64,
    /// Frustum depth, metres.
    #[arg(long, default_value_t = settings::DEFAULT_FAR, value_parser = finite_f32, allow_negative_numbers = true)]
    far: f32,
    /// Scale factor SF of the disk cell (not used where SF is swept).
    #[arg(long, default_value_t = settings::DEFAULT_SF, value_parser = finite_f32, allow_negative_numbers = true)]
    sf: f32,
    /// Object buffer budget, MiB.
    #[arg(long, default_value_t = settings::DEFAULT_MEMORY_BUDGET >> 20)]
    budget_mb: usize,
    /// Motion patterns, comma-separated (default: the thesis's five; normal where one
    /// path is walked).
    #[arg(long, value_delimiter = ',')]
    patterns: Vec<Motion>,
    /// Playback speed of walks that prefetch, times real time, within [0.01, 1000] (0:
    /// unpaced, frames back to back; the prefetch thread then rarely finishes in time).
    #[arg(long, default_value_t = settings::DEFAULT_PACE, value_parser = pace_factor, allow_negative_numbers = true)]
    speed: f32,
}

/// `--frames`'s help, with the defaults as the library has them.
fn frames_help() -> String {
    format!(
        "Frames of each walk [default: {}; {} for bench patterns; {} for bench csearch's figures, which walk once per configuration and cell size or city]",
        walk_setup::DEFAULT_FRAMES,
        walk_setup::PATTERN_FRAMES,
        walk_setup::SHORT_FRAMES
    )
}

impl WalkSetupArgs {
    /// The experiment's walk: these settings over `base`, the experiment's default,
    /// which gives the frames and the patterns when they are not given.
    pub fn setup(self, base: WalkSetup) -> WalkSetup {
        WalkSetup {
            frames: self.frames.unwrap_or(base.frames),
            fps: self.fps,
            seed: self.seed,
            far: self.far,
            sf: self.sf,
            memory_budget: self.budget_mb.saturating_mul(1 << 20),
            patterns: or_default(self.patterns, base.patterns),
            pace: pace(self.speed),
        }
    }
}
