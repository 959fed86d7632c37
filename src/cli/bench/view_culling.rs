//! `flaneur bench view-culling` (Shou 2002, Table 4.2).

use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use super::walk_setup::WalkSetupArgs;
use crate::cli::args::or_default;
use flaneur_bench::view_culling::{self, ViewCullingConfig};

/// `flaneur bench view-culling`'s arguments.
#[derive(clap::Args)]
pub struct ViewCullingArgs {
    /// The database: a file, or a URL (http://… or https://…) on any HTTP server.
    db: PathBuf,
    #[command(flatten)]
    walk: WalkSetupArgs,
    /// The scale factors, comma-separated (default the thesis's 1.0 ... 3.1).
    #[arg(long, value_delimiter = ',')]
    sfs: Vec<f32>,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl ViewCullingArgs {
    /// Sweeps the scale factor and writes the report.
    pub fn run(self) -> Result<()> {
        let ViewCullingArgs { db, walk, sfs, out } = self;
        let d = ViewCullingConfig::default();
        let cfg = ViewCullingConfig {
            walk: walk.setup(d.walk),
            sfs: or_default(sfs, d.sfs),
            ..d
        };
        let db = crate::cli::source::open(&db)?;
        let r = view_culling::run(&db, &cfg)?;
        write_report(&out, &r)
    }
}
