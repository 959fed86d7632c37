//! `flaneur bench lod-dag` (Zheng 2007, Tables 3.1–3.3).

use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use crate::cli::args::or_default;
use crate::cli::bars::with_bar;
use flaneur_bench::lod_dag::{self, LodDagConfig};

/// `flaneur bench lod-dag`'s arguments.
#[derive(clap::Args)]
pub struct LodDagArgs {
    /// Triangles of each bumpy torus, comma-separated [default: 69451,1087474].
    #[arg(long, value_delimiter = ',')]
    sizes: Vec<usize>,
    /// The bunny and the 69,451-triangle torus only (under a second).
    #[arg(long, conflicts_with = "sizes")]
    quick: bool,
    /// Build the non-redundant DAG (worst case quadratic) only up to this many
    /// triangles [default: always].
    #[arg(long)]
    non_redundant_max: Option<usize>,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl LodDagArgs {
    /// Builds the three DAGs of every model and writes the report.
    pub fn run(self) -> Result<()> {
        let LodDagArgs {
            sizes,
            quick,
            non_redundant_max,
            out,
        } = self;
        let d = if quick {
            LodDagConfig::quick()
        } else {
            LodDagConfig::default()
        };
        let cfg = LodDagConfig {
            sizes: or_default(sizes, d.sizes),
            non_redundant_max,
            ..d
        };
        let r = with_bar("lod-dag models", |p| lod_dag::run_with_progress(&cfg, p))?;
        write_report(&out, &r)
    }
}
