//! `flaneur bench scene-tree` (Shou 2002, Table 6.1, Fig. 6.7).

use crate::cli::args::finite_f32;
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
    #[arg(long, default_value_t = SceneTreeConfig::default().frames)]
    frames: usize,
    #[arg(long, default_value_t = SceneTreeConfig::default().fps, value_parser = finite_f32, allow_negative_numbers = true)]
    fps: f32,
    /// The walker's speed, m/s.
    #[arg(long, default_value_t = SceneTreeConfig::default().speed, value_parser = finite_f32, allow_negative_numbers = true)]
    speed: f32,
    /// VSC's DoV thresholds η, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = SceneTreeConfig::default().etas)]
    etas: Vec<f32>,
    /// PB's polygon budgets, triangles, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = SceneTreeConfig::default().budgets)]
    budgets: Vec<u64>,
    #[arg(long, default_value_t = SceneTreeConfig::default().seed)]
    seed: u64,
    #[arg(long, default_value = "bench-out")]
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
            out,
        } = self;
        let cfg = SceneTreeConfig {
            frames,
            fps,
            speed,
            etas,
            budgets,
            seed,
        };
        let db = crate::cli::source::open(&db)?;
        let r = with_bar("scene-tree", |tick| scene_tree::run(&db, &cfg, tick))?;
        write_report(&out, &r)
    }
}
