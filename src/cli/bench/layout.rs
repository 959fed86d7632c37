//! `flaneur bench layout` (ours): what the order of a database's objects costs over HTTP.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use super::report::write_report;
use crate::cli::args::or_default;
use flaneur::Database;
use flaneur_bench::layout::{self, LayoutBenchConfig};

/// `flaneur bench layout`'s arguments.
#[derive(clap::Args)]
pub struct LayoutArgs {
    /// Local database files of one city (built with `--order hilbert` and `--order
    /// input`, say): each is served over HTTP on loopback and asked the same queries.
    #[arg(required = true)]
    dbs: Vec<PathBuf>,
    #[arg(long, help = format!(
        "Queries per box side [default: {}]",
        flaneur_bench::layout::LayoutBenchConfig::default().queries
    ))]
    queries: Option<usize>,
    /// Sides of the square query boxes, metres, comma-separated (default 100, 200, 400).
    #[arg(long, value_delimiter = ',')]
    sides: Vec<f32>,
    #[arg(long, help = format!(
        "Seed of the query boxes' places [default: {}]",
        flaneur_bench::layout::LayoutBenchConfig::default().seed
    ))]
    seed: Option<u64>,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl LayoutArgs {
    /// Serves each database, queries it and writes the report.
    pub fn run(self) -> Result<()> {
        let LayoutArgs {
            dbs,
            queries,
            sides,
            seed,
            out,
        } = self;
        let d = LayoutBenchConfig::default();
        let cfg = LayoutBenchConfig {
            queries: queries.unwrap_or(d.queries),
            sides: or_default(sides, d.sides),
            seed: seed.unwrap_or(d.seed),
        };
        cfg.validate()?;
        let city = Database::open(&dbs[0])?;
        let mut served = Vec::new();
        for db in &dbs {
            let other = Database::open(db)?;
            if other.objects() != city.objects() || other.bounds() != city.bounds() {
                bail!(
                    "{} and {} hold different cities: the layouts compared must be of one city",
                    dbs[0].display(),
                    db.display()
                );
            }
            let (origin, name) = crate::cli::serve::spawn(db)
                .with_context(|| format!("serving {} for the queries", db.display()))?;
            served.push(layout::served_at(&name, origin, &name));
        }
        let r = layout::run(&city, &served, &cfg, |what| eprintln!("querying {what}"))?;
        write_report(&out, &r)
    }
}
