//! `flaneur bench pvs-prefetch` (Zheng 2007, Table 7.2, Figs. 7.6–7.8).

use crate::cli::args::{border, finite_f64};
use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use crate::cli::args::or_default;
use flaneur::prefetch::pvs::routes::RouteConfig;
use flaneur_bench::pvs_prefetch::{self, PvsPrefetchConfig, SyntheticConfig};

/// `flaneur bench pvs-prefetch`'s arguments.
#[derive(clap::Args)]
pub struct PvsPrefetchArgs {
    /// Buildings along each side of the synthetic city.
    #[arg(long, default_value_t = SyntheticConfig::default().blocks)]
    blocks: u32,
    /// Mean PVS size, a share of the buildings.
    #[arg(long, default_value_t = SyntheticConfig::default().pvs_share, value_parser = finite_f64, allow_negative_numbers = true)]
    share: f64,
    /// Share of a viewcell's PVS that a side neighbour also sees.
    #[arg(long, default_value_t = SyntheticConfig::default().overlap, value_parser = finite_f64, allow_negative_numbers = true)]
    overlap: f64,
    /// Steps of each route.
    #[arg(long, default_value_t = RouteConfig::default().steps)]
    steps: usize,
    /// Metres per step (LANP takes the viewer to set off at one step a step).
    #[arg(long, default_value_t = RouteConfig::default().step, value_parser = finite_f64, allow_negative_numbers = true)]
    step: f64,
    /// PBNP's side and corner regions, a fraction of a cell's side, in (0, 0.5].
    #[arg(long, default_value_t = PvsPrefetchConfig::default().border, value_parser = border, allow_negative_numbers = true)]
    border: f64,
    /// Region sizes of PBNP's sweep, comma-separated [default: 0.1, 0.15, … 0.5].
    #[arg(long, value_delimiter = ',', value_parser = border)]
    borders: Vec<f64>,
    /// Latencies to walk SNP, PBNP and LANP at, steps from asking a transaction to
    /// its answer, comma-separated [default: 0, 1, … 8].
    #[arg(long, value_delimiter = ',')]
    latencies: Vec<usize>,
    /// Client cache entries (viewcells); at least 9.
    #[arg(long, default_value_t = PvsPrefetchConfig::default().capacity)]
    cache: usize,
    /// Draws the PVS table and both routes.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Also run the experiment, both routes and the region sweep, over this
    /// database's precomputed visibility (built with --visibility); its files go to
    /// OUT/pvs-prefetch-db (default: none, the synthetic city only).
    #[arg(long)]
    db: Option<PathBuf>,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl PvsPrefetchArgs {
    /// Runs SNP and PBNP (and LANP under latency) on the synthetic city, and on the database when given, and
    /// writes the reports.
    pub fn run(self) -> Result<()> {
        let PvsPrefetchArgs {
            blocks,
            share,
            overlap,
            steps,
            step,
            border,
            borders,
            latencies,
            cache,
            seed,
            db,
            out,
        } = self;
        let d = PvsPrefetchConfig::default();
        let cfg = PvsPrefetchConfig {
            city: SyntheticConfig {
                blocks,
                pvs_share: share,
                overlap,
                seed,
                ..d.city
            },
            route: RouteConfig { steps, step, seed },
            border,
            capacity: cache,
            borders: or_default(borders, d.borders),
            latencies: or_default(latencies, d.latencies),
        };
        let r = pvs_prefetch::run(&cfg)?;
        write_report(&out, &r)?;
        if let Some(path) = db {
            let db = crate::cli::source::open(&path)?;
            let name = path.display().to_string();
            let r = pvs_prefetch::run_on_database(&db, &name, &cfg)?;
            println!();
            write_report(&out.join("pvs-prefetch-db"), &r)?;
        }
        Ok(())
    }
}
