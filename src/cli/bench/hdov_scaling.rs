//! `flaneur bench hdov-scaling` (Shou 2002, Fig. 5.23).

use crate::cli::args::eta;
use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use crate::cli::bars::with_bar;
use flaneur_bench::hdov_scaling::{self, HdovScalingConfig};
use flaneur_bench::hdov_search::HdovSearchConfig;

/// `flaneur bench hdov-scaling`'s arguments.
#[derive(clap::Args)]
pub struct HdovScalingArgs {
    /// Objects in each city, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = HdovScalingConfig::default().sizes)]
    sizes: Vec<u64>,
    /// Where the cities are built, once, and found again [default: OUT/hdov-cities].
    #[arg(long)]
    cities: Option<PathBuf>,
    /// The cities' citygen seed.
    #[arg(long, default_value_t = HdovScalingConfig::default().city_seed)]
    city_seed: u64,
    /// The DoV's cube-map resolution of the cities' visibility.
    #[arg(long, default_value_t = HdovScalingConfig::default().resolution)]
    resolution: u32,
    /// Queries on each city.
    #[arg(long, default_value_t = HdovScalingConfig::default().search.queries)]
    queries: usize,
    /// Of those, how many also read what they found.
    #[arg(long, default_value_t = HdovScalingConfig::default().search.load_queries)]
    load_queries: usize,
    /// DoV thresholds η, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = HdovScalingConfig::default().search.etas, value_parser = eta)]
    etas: Vec<f32>,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl HdovScalingArgs {
    /// Builds or reuses the cities, searches each, and writes the report.
    pub fn run(self) -> Result<()> {
        let d = HdovScalingConfig::default();
        let cfg = HdovScalingConfig {
            sizes: self.sizes,
            city_seed: self.city_seed,
            resolution: self.resolution,
            search: HdovSearchConfig {
                queries: self.queries,
                load_queries: self.load_queries,
                etas: self.etas,
                ..d.search
            },
            ..d
        };
        let cities = self.cities.unwrap_or_else(|| self.out.join("hdov-cities"));
        let r = with_bar("hdov-scaling", |tick| {
            hdov_scaling::run(&cities, &cfg, tick)
        })?;
        write_report(&self.out, &r)
    }
}
