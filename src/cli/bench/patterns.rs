//! `flaneur bench patterns` (Shou 2002, Table 4.1).

use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use super::walk_setup::WalkSetupArgs;
use flaneur_bench::patterns::{self, PatternsConfig};

/// `flaneur bench patterns`'s arguments.
#[derive(clap::Args)]
pub struct PatternsArgs {
    /// The database: a file, or a URL (http://… or https://…) on any HTTP server.
    db: PathBuf,
    #[command(flatten)]
    walk: WalkSetupArgs,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl PatternsArgs {
    /// Walks every pattern, Optimal and BOX, and writes the report.
    pub fn run(self) -> Result<()> {
        let PatternsArgs { db, walk, out } = self;
        let d = PatternsConfig::default();
        let cfg = PatternsConfig {
            walk: walk.setup(d.walk),
            ..d
        };
        let db = crate::cli::source::open(&db)?;
        let r = patterns::run(&db, &cfg)?;
        write_report(&out, &r)
    }
}
