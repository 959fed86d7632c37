//! `flaneur bench pvs-http` (ours): the PVS walk's prefetchers over HTTP at set round
//! trips.

use crate::cli::args::{bandwidth_mbit, border, round_trip_ms};
use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use super::report::write_report;
use super::walk_setup::WalkSetupArgs;
use crate::cli::args::or_default;
use flaneur::walk::pvs::PvsPrefetch;
use flaneur::Database;
use flaneur_bench::pvs_http::{self, PvsHttpConfig};

/// `flaneur bench pvs-http`'s arguments.
#[derive(clap::Args)]
pub struct PvsHttpArgs {
    /// A local database file built with --visibility: it is served over HTTP (with
    /// `flaneur serve`'s server, on loopback) and walked through the link, and walked
    /// locally beside.
    db: PathBuf,
    #[command(flatten)]
    walk: WalkSetupArgs,
    /// The rules, comma-separated: snp, pbnp, lanp (default all three).
    #[arg(long, value_delimiter = ',')]
    rules: Vec<String>,
    /// PBNP's and LANP's border regions, a share of the cell's side within (0, 0.5].
    #[arg(long, default_value_t = flaneur::prefetch::pvs::DEFAULT_BORDER, value_parser = border, allow_negative_numbers = true)]
    border: f64,
    /// Round trips of the link, ms, comma-separated (default 0, 20, 50, 100, 200).
    #[arg(long, value_name = "MS", value_delimiter = ',', value_parser = round_trip_ms)]
    rtts: Vec<u32>,
    /// The link's bandwidth, Mbit/s.
    #[arg(long, default_value_t = 100.0, value_parser = bandwidth_mbit, allow_negative_numbers = true)]
    mbit: f64,
    #[arg(long, value_name = "MIB", help = format!(
        "The client page cache, MiB [default: {}]",
        flaneur::store::HttpOptions::default().cache_bytes >> 20
    ))]
    cache_mb: Option<usize>,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl PvsHttpArgs {
    /// Serves the database, walks it with every rule at every setting and writes the
    /// report.
    pub fn run(self) -> Result<()> {
        let PvsHttpArgs {
            db,
            walk,
            rules,
            border,
            rtts,
            mbit,
            cache_mb,
            out,
        } = self;
        let d = PvsHttpConfig::default();
        let rules = rules
            .iter()
            .map(|r| {
                Ok(match r.as_str() {
                    "snp" => PvsPrefetch::Snp,
                    "pbnp" => PvsPrefetch::Pbnp { border },
                    "lanp" => PvsPrefetch::Lanp { border },
                    other => bail!("unknown rule '{other}' (snp, pbnp, lanp)"),
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let default_rules = d
            .rules
            .iter()
            .map(|r| match r {
                PvsPrefetch::Pbnp { .. } => PvsPrefetch::Pbnp { border },
                PvsPrefetch::Lanp { .. } => PvsPrefetch::Lanp { border },
                other => *other,
            })
            .collect();
        let cfg = PvsHttpConfig {
            walk: walk.setup(d.walk),
            rules: or_default(rules, default_rules),
            rtts_ms: or_default(rtts, d.rtts_ms),
            mbit,
            cache_bytes: cache_mb.map_or(d.cache_bytes, |m| m << 20),
        };
        cfg.validate()?;
        let local = Database::open(&db)?;
        let (origin, name) = crate::cli::serve::spawn(&db)
            .with_context(|| format!("serving {} for the walks", db.display()))?;
        let walks = cfg.walk.patterns.len() * cfg.rules.len() * (2 + cfg.rtts_ms.len());
        let mut done = 0;
        let r = pvs_http::run(&local, origin, &name, &cfg, |what| {
            done += 1;
            eprintln!("walk {done} of {walks}: {what}");
        })?;
        write_report(&out, &r)
    }
}
