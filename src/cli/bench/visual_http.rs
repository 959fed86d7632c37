//! `flaneur bench visual-http` (ours): the VISUAL walk never waiting on a read, over
//! HTTP at set round trips.

use crate::cli::args::{bandwidth_mbit, eta, round_trip_ms, seconds_ahead};
use std::path::PathBuf;

use anyhow::{Context, Result};

use super::report::write_report;
use super::walk_setup::WalkSetupArgs;
use crate::cli::args::or_default;
use flaneur::Database;
use flaneur_bench::visual_http::{self, VisualHttpConfig};

/// `flaneur bench visual-http`'s arguments.
#[derive(clap::Args)]
pub struct VisualHttpArgs {
    /// A local database file built with --visibility --hdov: it is served over HTTP
    /// (with `flaneur serve`'s server, on loopback) and walked through the link, and
    /// walked locally beside.
    db: PathBuf,
    #[command(flatten)]
    walk: WalkSetupArgs,
    /// The DoV threshold η of the searches, within [0, 1].
    #[arg(long, default_value_t = flaneur::walk::visual::DEFAULT_ETA, value_parser = eta, allow_negative_numbers = true)]
    eta: f32,
    /// The next-cell prefetch, seconds ahead, at most 60 (ours; negative: off).
    #[arg(long, value_name = "SECONDS", default_value_t = flaneur::walk::settings::DEFAULT_K, value_parser = seconds_ahead, allow_negative_numbers = true)]
    k: f32,
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

impl VisualHttpArgs {
    /// Serves the database, walks it at every setting and writes the report.
    pub fn run(self) -> Result<()> {
        let VisualHttpArgs {
            db,
            walk,
            eta,
            k,
            rtts,
            mbit,
            cache_mb,
            out,
        } = self;
        let d = VisualHttpConfig::default();
        let cfg = VisualHttpConfig {
            walk: walk.setup(d.walk),
            eta,
            prefetch_k: (k >= 0.0).then_some(k),
            rtts_ms: or_default(rtts, d.rtts_ms),
            mbit,
            cache_bytes: cache_mb.map_or(d.cache_bytes, |m| m << 20),
        };
        cfg.validate()?;
        let local = Database::open(&db)?;
        let (origin, name) = crate::cli::serve::spawn(&db)
            .with_context(|| format!("serving {} for the walks", db.display()))?;
        let walks = cfg.walk.patterns.len() * (2 + cfg.rtts_ms.len());
        let mut done = 0;
        let r = visual_http::run(&local, origin, &name, &cfg, |what| {
            done += 1;
            eprintln!("walk {done} of {walks}: {what}");
        })?;
        write_report(&out, &r)
    }
}
