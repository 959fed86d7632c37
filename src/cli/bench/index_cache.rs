//! `flaneur bench index-cache` (Shou 2002, Fig. 4.18).

use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use super::walk_setup::WalkSetupArgs;
use flaneur_bench::index_cache::{self, IndexCacheConfig};

/// `flaneur bench index-cache`'s arguments.
#[derive(clap::Args)]
pub struct IndexCacheArgs {
    /// The database: a file, or a URL (http://… or https://…) on any HTTP server.
    db: PathBuf,
    #[command(flatten)]
    walk: WalkSetupArgs,
    /// Cache sizes in pages, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = IndexCacheConfig::default().sizes)]
    sizes: Vec<usize>,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl IndexCacheArgs {
    /// Replays each walk's index pages through the caches and writes the report.
    pub fn run(self) -> Result<()> {
        let IndexCacheArgs {
            db,
            walk,
            sizes,
            out,
        } = self;
        let cfg = IndexCacheConfig {
            walk: walk.setup(IndexCacheConfig::default().walk),
            sizes,
        };
        let db = crate::cli::source::open(&db)?;
        let r = index_cache::run(&db, &cfg)?;
        write_report(&out, &r)
    }
}
