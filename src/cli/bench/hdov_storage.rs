//! `flaneur bench hdov-storage` (Shou 2002, Table 5.2).

use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use flaneur_bench::hdov_storage;

/// `flaneur bench hdov-storage`'s arguments.
#[derive(clap::Args)]
pub struct HdovStorageArgs {
    /// A database built with --visibility --hdov (all three schemes for the whole
    /// table).
    db: PathBuf,
    /// Also size the schemes of trees over the same objects and viewcells at these
    /// fan-outs (entries a node, comma-separated, each at least 2), without building
    /// them (default: none, only the tree the database holds).
    #[arg(long, value_name = "M,M,...", value_delimiter = ',')]
    fanouts: Vec<u32>,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl HdovStorageArgs {
    /// Reads the tree's head, sizes the fan-outs asked for, and writes the table.
    pub fn run(self) -> Result<()> {
        let db = crate::cli::source::open(&self.db)?;
        let r = hdov_storage::run(&db, &self.fanouts)?;
        write_report(&self.out, &r)
    }
}
