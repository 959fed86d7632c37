//! `flaneur bench soak`: an hour of walking with the resident set sampled.

use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use flaneur_bench::soak::{self, SoakConfig};

/// `flaneur bench soak`'s arguments.
#[derive(clap::Args)]
pub struct SoakArgs {
    /// The database: a file, or a URL (http://… or https://…) on any HTTP server.
    db: PathBuf,
    /// Frames to walk (108,000: an hour at 30 frames a second).
    #[arg(long, default_value_t = SoakConfig::default().frames)]
    frames: usize,
    /// Frames of warm-up before the resident set must be flat.
    #[arg(long, default_value_t = SoakConfig::default().warm_up)]
    warm_up: usize,
    /// Frames between samples of the resident set.
    #[arg(long, default_value_t = SoakConfig::default().sample_every)]
    sample_every: usize,
    /// The motion pattern walked.
    #[arg(long, default_value = "random")]
    path: String,
    #[arg(long, value_name = "MIB", help = format!(
        "The object buffer's budget, MiB [default: {}]",
        SoakConfig::default().review.memory_budget >> 20
    ))]
    budget_mb: Option<usize>,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl SoakArgs {
    /// Walks and writes the report.
    pub fn run(self) -> Result<()> {
        let d = SoakConfig::default();
        let mut cfg = SoakConfig {
            frames: self.frames,
            warm_up: self.warm_up,
            sample_every: self.sample_every,
            motion: self.path.parse()?,
            ..d
        };
        if let Some(mb) = self.budget_mb {
            flaneur::walk::settings::check_budget(mb << 20)?;
            cfg.review.memory_budget = mb << 20;
        }
        let db = crate::cli::source::open(&self.db)?;
        let r = soak::run(&db, &cfg)?;
        write_report(&self.out, &r)
    }
}
