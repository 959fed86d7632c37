//! `flaneur bench hdov-cache` (Shou 2002, Figs. 5.15–5.20).

use crate::cli::args::eta;
use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use crate::cli::bars::with_bar;
use flaneur_bench::hdov_cache::{self, HdovCacheConfig};

/// `flaneur bench hdov-cache`'s arguments.
#[derive(clap::Args)]
pub struct HdovCacheArgs {
    /// A database built with --visibility --hdov.
    db: PathBuf,
    /// Queries of each set, continuous and random.
    #[arg(long, default_value_t = HdovCacheConfig::default().queries)]
    queries: usize,
    /// DoV thresholds η, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = HdovCacheConfig::default().etas, value_parser = eta)]
    etas: Vec<f32>,
    /// Cache sizes in node pages, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = HdovCacheConfig::default().sizes)]
    sizes: Vec<usize>,
    /// Replacement policies, comma-separated (lru, dov, dovtime, dplru); Belady is
    /// always beside them.
    #[arg(long, value_delimiter = ',', default_values_t = HdovCacheConfig::default().policies)]
    policies: Vec<String>,
    /// Seed of the viewcells queried.
    #[arg(long, default_value_t = HdovCacheConfig::default().seed)]
    seed: u64,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl HdovCacheArgs {
    /// Traces each query set's node accesses, replays them through every policy and
    /// size, and writes the report.
    pub fn run(self) -> Result<()> {
        let HdovCacheArgs {
            db,
            queries,
            etas,
            sizes,
            policies,
            seed,
            out,
        } = self;
        let cfg = HdovCacheConfig {
            queries,
            etas,
            sizes,
            policies,
            seed,
        };
        let db = crate::cli::source::open(&db)?;
        let r = with_bar("hdov-cache", |tick| hdov_cache::run(&db, &cfg, tick))?;
        write_report(&out, &r)
    }
}
