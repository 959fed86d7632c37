//! `flaneur bench stream-blocks`: a walk's cost per frame by each stream scheme
//! (El-Sana's Table 1).

use crate::cli::args::{frame_ms, round_trip_ms, tau, wait_ms};
use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use flaneur_bench::stream_blocks::{self, StreamBlocksConfig};

/// `flaneur bench stream-blocks`'s arguments.
#[derive(clap::Args)]
pub struct StreamBlocksArgs {
    /// Triangles of the bumpy-torus landmark.
    #[arg(long, default_value_t = StreamBlocksConfig::default().triangles)]
    triangles: usize,
    /// Frames of the walk.
    #[arg(long, default_value_t = StreamBlocksConfig::default().frames)]
    frames: usize,
    /// The frame period, ms, within (0, 10000] (what a frame's refinement leaves of it
    /// is idle time).
    #[arg(long, default_value_t = StreamBlocksConfig::default().frame_ms, value_parser = frame_ms, allow_negative_numbers = true)]
    frame_ms: f64,
    /// The link's round trip, ms, within [0, 60000] (0: straight to the server).
    #[arg(long, value_name = "MS", default_value_t = StreamBlocksConfig::default().rtt_ms, value_parser = round_trip_ms)]
    rtt: u32,
    /// The screen-space error streamed to, a fraction of the viewport within (0, 1).
    #[arg(long, default_value_t = StreamBlocksConfig::default().tau, value_parser = tau, allow_negative_numbers = true)]
    tau: f32,
    /// Levels of a block.
    #[arg(long, default_value_t = StreamBlocksConfig::default().levels)]
    levels: u8,
    /// Blocks the bounded cache keeps beyond those the mesh uses.
    #[arg(long, default_value_t = StreamBlocksConfig::default().cache_blocks)]
    cache: usize,
    /// Blocks a prediction asks for.
    #[arg(long, default_value_t = StreamBlocksConfig::default().predict_blocks)]
    predict: usize,
    /// The server's wait after an answer before it predicts, ms, within [0, 3600000].
    #[arg(long, value_name = "MS", default_value_t = StreamBlocksConfig::default().idle_ms, value_parser = wait_ms)]
    idle_ms: u64,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl StreamBlocksArgs {
    /// Walks by each scheme and writes the report.
    pub fn run(self) -> Result<()> {
        let cfg = StreamBlocksConfig {
            triangles: self.triangles,
            frames: self.frames,
            frame_ms: self.frame_ms,
            rtt_ms: self.rtt,
            tau: self.tau,
            levels: self.levels,
            cache_blocks: self.cache,
            predict_blocks: self.predict,
            idle_ms: self.idle_ms,
            ..StreamBlocksConfig::default()
        };
        let r = stream_blocks::run(&cfg, |what| eprintln!("stream-blocks: {what}"))?;
        write_report(&self.out, &r)
    }
}
