//! `flaneur bench visual-vs-review` (Shou 2002, Table 5.3, Figs. 5.24–5.27).

use crate::cli::args::finite_f32;
use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use crate::cli::bars::with_bar;
use flaneur_bench::visual_vs_review::{self, VisualVsReviewConfig};

/// `flaneur bench visual-vs-review`'s arguments.
#[derive(clap::Args)]
pub struct VisualVsReviewArgs {
    /// A database built with --visibility --hdov.
    db: PathBuf,
    /// Frames per session.
    #[arg(long, default_value_t = VisualVsReviewConfig::default().frames)]
    frames: usize,
    #[arg(long, default_value_t = VisualVsReviewConfig::default().fps, value_parser = finite_f32, allow_negative_numbers = true)]
    fps: f32,
    /// The walker's speed, m/s.
    #[arg(long, default_value_t = VisualVsReviewConfig::default().speed, value_parser = finite_f32, allow_negative_numbers = true)]
    speed: f32,
    /// VISUAL's DoV thresholds η, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = VisualVsReviewConfig::default().etas)]
    etas: Vec<f32>,
    /// REVIEW's query boxes, metres, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = VisualVsReviewConfig::default().boxes)]
    boxes: Vec<f32>,
    /// Sessions: normal, turning, back-forth, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = VisualVsReviewConfig::default().sessions)]
    sessions: Vec<String>,
    /// Playback speed, times real time.
    #[arg(long, default_value_t = VisualVsReviewConfig::default().pace, value_parser = finite_f32, allow_negative_numbers = true)]
    pace: f32,
    #[arg(long, default_value_t = VisualVsReviewConfig::default().seed)]
    seed: u64,
    #[arg(long, default_value = "bench-out")]
    out: PathBuf,
}

impl VisualVsReviewArgs {
    /// Walks every session with VISUAL and REVIEW, and writes the report.
    pub fn run(self) -> Result<()> {
        let VisualVsReviewArgs {
            db,
            frames,
            fps,
            speed,
            etas,
            boxes,
            sessions,
            pace,
            seed,
            out,
        } = self;
        let cfg = VisualVsReviewConfig {
            frames,
            fps,
            speed,
            etas,
            boxes,
            sessions,
            pace,
            seed,
        };
        let db = crate::cli::source::open(&db)?;
        let r = with_bar("visual-vs-review", |tick| {
            visual_vs_review::run(&db, &cfg, tick)
        })?;
        write_report(&out, &r)
    }
}
