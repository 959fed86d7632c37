//! `flaneur bench visual-http` (ours): the VISUAL walk never waiting on a read, over
//! HTTP at set round trips.

use crate::cli::args::{finite_f32, finite_f64};
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
    /// The DoV threshold η of the searches.
    #[arg(long, default_value_t = flaneur::walk::visual::DEFAULT_ETA, value_parser = finite_f32, allow_negative_numbers = true)]
    eta: f32,
    /// The next-cell prefetch, seconds ahead (ours; negative: off).
    #[arg(long, default_value_t = flaneur::walk::review::DEFAULT_K, value_parser = finite_f32, allow_negative_numbers = true)]
    k: f32,
    /// Round trips of the link, ms, comma-separated (default 0, 20, 50, 100, 200).
    #[arg(long, value_delimiter = ',')]
    rtts: Vec<u32>,
    /// The link's bandwidth, Mbit/s.
    #[arg(long, default_value_t = 100.0, value_parser = finite_f64, allow_negative_numbers = true)]
    mbit: f64,
    /// The client page cache, MiB.
    #[arg(long)]
    cache_mb: Option<usize>,
    #[arg(long, default_value = "bench-out")]
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
