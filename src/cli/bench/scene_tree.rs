//! `flaneur bench scene-tree` (Shou 2002, Table 6.1, Fig. 6.7).

use crate::cli::args::{eta, finite_f32, frame_rate};
use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use crate::cli::bars::with_bar;
use flaneur_bench::scene_tree::{self, SceneTreeConfig};

/// `flaneur bench scene-tree`'s arguments.
#[derive(clap::Args)]
pub struct SceneTreeArgs {
    /// A database built with --visibility.
    db: PathBuf,
    /// Frames of the walk through the walkable viewcells.
    #[arg(long, default_value_t = SceneTreeConfig::default().frames)]
    frames: usize,
    /// Frames a second of the walk, within [0.1, 1000].
    #[arg(long, default_value_t = SceneTreeConfig::default().fps, value_parser = frame_rate, allow_negative_numbers = true)]
    fps: f32,
    /// The walker's speed, m/s.
    #[arg(long, default_value_t = SceneTreeConfig::default().speed, value_parser = finite_f32, allow_negative_numbers = true)]
    speed: f32,
    /// VSC's DoV thresholds η, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = SceneTreeConfig::default().etas, value_parser = eta)]
    etas: Vec<f32>,
    /// PB's polygon budgets, triangles, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = SceneTreeConfig::default().budgets)]
    budgets: Vec<u64>,
    /// Seed of the walk's path: the same seed, the same path.
    #[arg(long, default_value_t = SceneTreeConfig::default().seed)]
    seed: u64,
    /// VSC's and PB's rule for internal LODs and levels: `screen` (ours, the default:
    /// each representation's stored error held under the thesis's τ of 0.1 % from the
    /// eye) or `thesis` (Table 6.1's own).
    #[arg(long, default_value = "screen", value_parser = crate::cli::args::selection)]
    selection: flaneur::hdov::Selection,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl SceneTreeArgs {
    /// Loads the scene tree, walks it under every traversal and writes the report.
    pub fn run(self) -> Result<()> {
        let SceneTreeArgs {
            db,
            frames,
            fps,
            speed,
            etas,
            budgets,
            seed,
            selection,
            out,
        } = self;
        let cfg = SceneTreeConfig {
            frames,
            fps,
            speed,
            etas,
            budgets,
            seed,
            selection,
        };
        let db = crate::cli::source::open(&db)?;
        let r = with_bar("scene-tree", |tick| scene_tree::run(&db, &cfg, tick))?;
        write_report(&out, &r)
    }
}
