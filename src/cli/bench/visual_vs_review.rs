//! `flaneur bench visual-vs-review` (Shou 2002, Table 5.3, Figs. 5.24–5.27).

use crate::cli::args::{eta, finite_f32, frame_rate, pace_factor, selection};
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
    /// Frames a second of the sessions, within [0.1, 1000].
    #[arg(long, default_value_t = VisualVsReviewConfig::default().fps, value_parser = frame_rate, allow_negative_numbers = true)]
    fps: f32,
    /// The walker's speed, m/s.
    #[arg(long, default_value_t = VisualVsReviewConfig::default().speed, value_parser = finite_f32, allow_negative_numbers = true)]
    speed: f32,
    /// VISUAL's DoV thresholds η, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = VisualVsReviewConfig::default().etas, value_parser = eta)]
    etas: Vec<f32>,
    /// REVIEW's query boxes, metres, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = VisualVsReviewConfig::default().boxes)]
    boxes: Vec<f32>,
    /// Sessions: normal, turning, back-forth, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = VisualVsReviewConfig::default().sessions)]
    sessions: Vec<String>,
    /// Playback speed, times real time, within [0.01, 1000].
    #[arg(long, default_value_t = VisualVsReviewConfig::default().pace, value_parser = pace_factor, allow_negative_numbers = true)]
    pace: f32,
    /// Seed of the sessions' paths: the same seed, the same paths.
    #[arg(long, default_value_t = VisualVsReviewConfig::default().seed)]
    seed: u64,
    /// VISUAL's rule for internal LODs and levels: `screen` (ours, the default: a
    /// node's internal LOD only where its stored error also projects under the thesis's
    /// τ of 0.1 % from the viewcell) or `thesis` (Table 5.3's own).
    #[arg(long, default_value = "screen", value_parser = selection)]
    selection: flaneur::hdov::Selection,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
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
            selection,
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
            selection,
        };
        let db = crate::cli::source::open(&db)?;
        let r = with_bar("visual-vs-review", |tick| {
            visual_vs_review::run(&db, &cfg, tick)
        })?;
        write_report(&out, &r)
    }
}
