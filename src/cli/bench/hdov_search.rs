//! `flaneur bench hdov-search` (Shou 2002, Figs. 5.21–5.22).

use crate::cli::args::eta;
use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use crate::cli::bars::with_bar;
use flaneur_bench::hdov_search::{self, HdovSearchConfig};

/// `flaneur bench hdov-search`'s arguments.
#[derive(clap::Args)]
pub struct HdovSearchArgs {
    /// A database built with --visibility --hdov.
    db: PathBuf,
    /// Queries per method and threshold.
    #[arg(long, default_value_t = HdovSearchConfig::default().queries)]
    queries: usize,
    /// Of those, how many also read what they found (the total I/O).
    #[arg(long, default_value_t = HdovSearchConfig::default().load_queries)]
    load_queries: usize,
    /// DoV thresholds η, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = HdovSearchConfig::default().etas, value_parser = eta)]
    etas: Vec<f32>,
    /// Seed of the viewcells queried.
    #[arg(long, default_value_t = HdovSearchConfig::default().seed)]
    seed: u64,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl HdovSearchArgs {
    /// Runs the queries under every scheme and η, and writes the report.
    pub fn run(self) -> Result<()> {
        let HdovSearchArgs {
            db,
            queries,
            load_queries,
            etas,
            seed,
            out,
        } = self;
        let cfg = HdovSearchConfig {
            queries,
            load_queries,
            etas,
            seed,
        };
        let db = crate::cli::source::open(&db)?;
        let r = with_bar("hdov-search", |tick| hdov_search::run(&db, &cfg, tick))?;
        write_report(&out, &r)
    }
}
