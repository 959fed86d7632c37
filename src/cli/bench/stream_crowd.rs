//! `flaneur bench stream-crowd` (ours): many clients on one stream server.

use crate::cli::args::frame_ms;
use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use flaneur::lod::Traversal;
use flaneur_bench::stream_crowd::{self, StreamCrowdConfig};

/// A traversal by its short name.
fn parse_traversal(name: &str) -> std::result::Result<Traversal, String> {
    Traversal::ALL
        .into_iter()
        .find(|t| t.name() == name)
        .ok_or_else(|| format!("no traversal {name:?}: give priority, linear or constant"))
}

/// `flaneur bench stream-crowd`'s arguments.
#[derive(clap::Args)]
pub struct StreamCrowdArgs {
    /// Clients at once.
    #[arg(long, default_value_t = StreamCrowdConfig::default().clients)]
    clients: usize,
    /// Triangles of the bumpy-torus landmark.
    #[arg(long, default_value_t = StreamCrowdConfig::default().triangles)]
    triangles: usize,
    /// Frames each client walks.
    #[arg(long, default_value_t = StreamCrowdConfig::default().frames)]
    frames: usize,
    /// Each client's frame period, ms, within (0, 10000].
    #[arg(long, default_value_t = StreamCrowdConfig::default().frame_ms, value_parser = frame_ms, allow_negative_numbers = true)]
    frame_ms: f64,
    /// The sessions' traversal: priority, linear or constant (constant-time, whose
    /// evaluations N bounds).
    #[arg(long, default_value = "priority", value_parser = parse_traversal)]
    traversal: Traversal,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl StreamCrowdArgs {
    /// Runs the crowd and writes the report.
    pub fn run(self) -> Result<()> {
        let cfg = StreamCrowdConfig {
            clients: self.clients,
            triangles: self.triangles,
            frames: self.frames,
            frame_ms: self.frame_ms,
            traversal: self.traversal,
            ..StreamCrowdConfig::default()
        };
        let r = stream_crowd::run(&cfg, |what| eprintln!("stream-crowd: {what}"))?;
        write_report(&self.out, &r)
    }
}
