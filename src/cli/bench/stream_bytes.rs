//! `flaneur bench stream-bytes`: one view's stream, view-dependent against
//! view-independent (Kim–Lee–Kobbelt Figs. 8–9).

use crate::cli::args::tau;
use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use flaneur_bench::stream_bytes::{self, StreamBytesConfig};

/// `flaneur bench stream-bytes`'s arguments.
#[derive(clap::Args)]
pub struct StreamBytesArgs {
    /// Triangles of the bumpy-torus landmark.
    #[arg(long, default_value_t = StreamBytesConfig::default().triangles)]
    triangles: usize,
    /// The screen-space error streamed to, a fraction of the viewport within (0, 1).
    #[arg(long, default_value_t = StreamBytesConfig::default().tau, value_parser = tau, allow_negative_numbers = true)]
    tau: f32,
    /// The byte cap the two are compared at.
    #[arg(long, default_value_t = StreamBytesConfig::default().cap)]
    cap: usize,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl StreamBytesArgs {
    /// Streams both ways and writes the report.
    pub fn run(self) -> Result<()> {
        let cfg = StreamBytesConfig {
            triangles: self.triangles,
            tau: self.tau,
            cap: self.cap,
        };
        let r = stream_bytes::run(&cfg, |what| eprintln!("stream-bytes: {what}"))?;
        write_report(&self.out, &r)
    }
}
