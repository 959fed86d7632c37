//! `flaneur bench stream` (Zheng 2007 Tables 5.1, 6.1, Fig. 6.6): a landmark streamed at
//! set round trips, sequential against predictive.

use crate::cli::args::{frame_ms, round_trip_ms, tau};
use std::path::PathBuf;

use anyhow::{bail, Result};

use super::report::write_report;
use crate::cli::args::or_default;
use flaneur_bench::stream::{self, StreamBenchConfig};
use flaneur_stream::Predictor;

/// `flaneur bench stream`'s arguments.
#[derive(clap::Args)]
pub struct StreamArgs {
    /// Triangles of the bumpy-torus landmark.
    #[arg(long, default_value_t = StreamBenchConfig::default().triangles)]
    triangles: usize,
    /// Frames of each walk.
    #[arg(long, default_value_t = StreamBenchConfig::default().frames)]
    frames: usize,
    /// The client's frame period, ms, within (0, 10000].
    #[arg(long, default_value_t = StreamBenchConfig::default().frame_ms, value_parser = frame_ms, allow_negative_numbers = true)]
    frame_ms: f64,
    /// Round trips of the link, ms, comma-separated [default: 80, 170, 260, 350 (Table 6.1)].
    #[arg(long, value_name = "MS", value_delimiter = ',', value_parser = round_trip_ms)]
    rtts: Vec<u32>,
    /// τ, a fraction of the viewport within (0, 1).
    #[arg(long, default_value_t = StreamBenchConfig::default().tau, value_parser = tau, allow_negative_numbers = true)]
    tau: f32,
    /// The predictive clients, comma-separated: linear (Zheng's first order), quadratic
    /// (ours) [default: both].
    #[arg(long, value_delimiter = ',')]
    predictors: Vec<String>,
    /// Leave out the sequential client (whose walks take most of the time at long round
    /// trips).
    #[arg(long)]
    no_sequential: bool,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl StreamArgs {
    /// Runs every walk and writes the report.
    pub fn run(self) -> Result<()> {
        let d = StreamBenchConfig::default();
        let predictors = self
            .predictors
            .iter()
            .map(|p| match p.as_str() {
                "linear" => Ok(Predictor::Linear),
                "quadratic" => Ok(Predictor::Quadratic),
                other => bail!("--predictors: {other:?} is not linear or quadratic"),
            })
            .collect::<Result<Vec<_>>>()?;
        let cfg = StreamBenchConfig {
            triangles: self.triangles,
            frames: self.frames,
            frame_ms: self.frame_ms,
            rtts_ms: or_default(self.rtts, d.rtts_ms.clone()),
            tau: self.tau,
            predictors: or_default(predictors, d.predictors.clone()),
            sequential: !self.no_sequential,
            ..d
        };
        let r = stream::run(&cfg, |what| eprintln!("stream: {what}"))?;
        write_report(&self.out, &r)
    }
}
