//! `flaneur bench http` (ours): walks over HTTP at set round trips and bandwidths.

use std::path::PathBuf;

use anyhow::{Context, Result};

use super::report::write_report;
use super::walk_setup::WalkSetupArgs;
use crate::cli::args::or_default;
use crate::cli::args::{bandwidth_mbit, round_trip_ms};
use flaneur::Database;
use flaneur_bench::http_walk::{self, HttpBenchConfig};

/// `flaneur bench http`'s arguments.
#[derive(clap::Args)]
pub struct HttpArgs {
    /// A local database file: it is served over HTTP (with `flaneur serve`'s server, on
    /// loopback) and walked through the link, and walked locally beside.
    db: PathBuf,
    #[command(flatten)]
    walk: WalkSetupArgs,
    /// Round trips of the link, ms, comma-separated (default 0, 20, 50, 100, 200).
    #[arg(long, value_name = "MS", value_delimiter = ',', value_parser = round_trip_ms)]
    rtts: Vec<u32>,
    /// Bandwidths of the link, Mbit/s, comma-separated (default 20, 100).
    #[arg(long, value_delimiter = ',', value_parser = bandwidth_mbit)]
    mbits: Vec<f64>,
    #[arg(long, value_name = "MIB", help = format!(
        "The client page cache, MiB [default: {}]",
        flaneur::store::HttpOptions::default().cache_bytes >> 20
    ))]
    cache_mb: Option<usize>,
    /// The index cache's policy: lru, dplru, dov, dovtime, path (default: the Optimal
    /// configuration's, DPLRU).
    #[arg(long)]
    policy: Option<String>,
    /// The index cache's size, KiB (default: the Optimal configuration's, 1024).
    #[arg(long)]
    index_cache_kb: Option<usize>,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl HttpArgs {
    /// Serves the database, walks it at every setting and writes the report.
    pub fn run(self) -> Result<()> {
        let HttpArgs {
            db,
            walk,
            rtts,
            mbits,
            cache_mb,
            policy,
            index_cache_kb,
            out,
        } = self;
        let d = HttpBenchConfig::default();
        let index_cache = index_cache(policy, index_cache_kb, &d);
        let cfg = HttpBenchConfig {
            walk: walk.setup(d.walk),
            rtts_ms: or_default(rtts, d.rtts_ms),
            mbits: or_default(mbits, d.mbits),
            cache_bytes: cache_mb.map_or(d.cache_bytes, |m| m << 20),
            index_cache,
        };
        cfg.validate()?;
        let local = Database::open(&db)?;
        let (origin, name) = crate::cli::serve::spawn(&db)
            .with_context(|| format!("serving {} for the walks", db.display()))?;
        let walks = cfg.walk.patterns.len() * (2 + cfg.rtts_ms.len() * cfg.mbits.len());
        let mut done = 0;
        let r = http_walk::run(&local, origin, &name, &cfg, |what| {
            done += 1;
            eprintln!("walk {done} of {walks}: {what}");
        })?;
        write_report(&out, &r)
    }
}

/// The index cache `--policy` and `--index-cache-kb` ask for, each defaulting to the
/// Optimal configuration's; `None` when neither is given.
fn index_cache(
    policy: Option<String>,
    kb: Option<usize>,
    d: &HttpBenchConfig,
) -> Option<(String, usize)> {
    if policy.is_none() && kb.is_none() {
        return None;
    }
    let (p, bytes) = d.review().index_cache.unwrap_or(("dplru".into(), 1 << 20));
    Some((policy.unwrap_or(p), kb.map_or(bytes, |k| k << 10)))
}
