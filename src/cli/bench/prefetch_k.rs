//! `flaneur bench prefetch-k` (Shou 2002, Fig. 4.17).

use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use super::walk_setup::WalkSetupArgs;
use crate::cli::args::or_default;
use crate::cli::args::seconds_ahead;
use flaneur_bench::prefetch_k::{self, PrefetchKConfig};

/// `flaneur bench prefetch-k`'s arguments.
#[derive(clap::Args)]
pub struct PrefetchKArgs {
    /// The database: a file, or a URL (http://… or https://…) on any HTTP server.
    db: PathBuf,
    #[command(flatten)]
    walk: WalkSetupArgs,
    /// The k values in seconds, at most 60, comma-separated (default 0, 0.4, 0.8, 1.2,
    /// 1.6, 2, 3, 4, 6, 8).
    #[arg(long, value_delimiter = ',', value_parser = seconds_ahead, allow_negative_numbers = true)]
    ks: Vec<f32>,
    /// Walks per pattern and k (the median is reported, with the spread).
    #[arg(long, default_value_t = 1)]
    repeats: usize,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl PrefetchKArgs {
    /// Sweeps k over every pattern and writes the report.
    pub fn run(self) -> Result<()> {
        let PrefetchKArgs {
            db,
            walk,
            ks,
            repeats,
            out,
        } = self;
        let d = PrefetchKConfig::default();
        let cfg = PrefetchKConfig {
            walk: walk.setup(d.walk),
            ks: or_default(ks, d.ks),
            repeats,
        };
        let db = crate::cli::source::open(&db)?;
        let r = prefetch_k::run(&db, &cfg)?;
        write_report(&out, &r)
    }
}
