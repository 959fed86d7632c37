//! `flaneur bench lod-parallel` (El-Sana & Varshney, Tables 1–2).

use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use crate::cli::args::or_default;
use crate::cli::bars::with_bar;
use flaneur_bench::lod_parallel::{self, LodParallelConfig};

/// `flaneur bench lod-parallel`'s arguments.
#[derive(clap::Args)]
pub struct LodParallelArgs {
    /// Triangles of each bumpy torus, comma-separated [default: 250000,1000000].
    #[arg(long, value_delimiter = ',')]
    triangles: Vec<usize>,
    /// Thread counts, comma-separated; the first is the speed-ups' base
    /// [default: 1 and every core].
    #[arg(long, value_delimiter = ',')]
    threads: Vec<usize>,
    /// Builds per measurement; the median counts.
    #[arg(long, default_value_t = LodParallelConfig::default().repeats)]
    repeats: usize,
    /// City objects for the throughput rows (0: none).
    #[arg(long, default_value_t = LodParallelConfig::default().objects)]
    objects: u64,
    /// Octree leaves hold at most this many triangles on average.
    #[arg(long, default_value_t = LodParallelConfig::default().options.leaf_triangles)]
    leaf_triangles: usize,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl LodParallelArgs {
    /// Times the builds on every thread count and writes the report.
    pub fn run(self) -> Result<()> {
        let LodParallelArgs {
            triangles,
            threads,
            repeats,
            objects,
            leaf_triangles,
            out,
        } = self;
        let d = LodParallelConfig::default();
        let cfg = LodParallelConfig {
            triangles: or_default(triangles, d.triangles),
            threads: or_default(threads, d.threads),
            repeats,
            objects,
            options: flaneur::lod::ParallelOptions {
                leaf_triangles,
                ..d.options
            },
        };
        let r = with_bar("lod-parallel builds", |p| lod_parallel::run(&cfg, p))?;
        write_report(&out, &r)
    }
}
