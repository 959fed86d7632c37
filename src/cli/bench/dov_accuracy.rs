//! `flaneur bench dov-accuracy` (ours, for Shou 2002 §5.5.2): the rasterised DoVs a
//! build stores against the ray-cast reference. Exits with an error naming every cell
//! whose DoVs differ by more than the limit.

use std::path::PathBuf;

use anyhow::{bail, Result};

use super::report::write_report;
use crate::cli::args::finite_f32;
use flaneur_bench::dov_accuracy::{self, DovAccuracyConfig};

/// `flaneur bench dov-accuracy`'s arguments.
#[derive(clap::Args)]
pub struct DovAccuracyArgs {
    /// A database built with --visibility.
    db: PathBuf,
    /// Cells measured, spread evenly over the walkable ones.
    #[arg(long, default_value_t = DovAccuracyConfig::default().cells)]
    cells: usize,
    /// Pixels per side of a cube face (N) for both sources.
    #[arg(long, value_name = "N", default_value_t = DovAccuracyConfig::default().resolution)]
    resolution: u32,
    /// The largest sum of absolute DoV differences a cell may have, in shares of the
    /// view sphere; a cell over it fails the command.
    #[arg(long, value_name = "SHARE", value_parser = finite_f32, allow_negative_numbers = true, default_value_t = 0.01)]
    limit: f32,
    /// Folder for the CSV and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl DovAccuracyArgs {
    /// Measures the cells, writes the report, and fails on any cell over the limit.
    pub fn run(self) -> Result<()> {
        if !(self.limit >= 0.0) {
            bail!("--limit {} must be a share from 0 up", self.limit);
        }
        let db = crate::cli::source::open(&self.db)?;
        let cfg = DovAccuracyConfig {
            cells: self.cells,
            resolution: self.resolution,
        };
        let r = dov_accuracy::run(&db, &cfg)?;
        write_report(&self.out, &r)?;
        let over: Vec<String> = r
            .rows
            .iter()
            .filter(|row| row.difference > f64::from(self.limit))
            .map(|row| format!("cell {} ({:.2e})", row.cell, row.difference))
            .collect();
        if !over.is_empty() {
            bail!(
                "{} cells' DoVs differ from the ray-cast reference by more than {}: {}",
                over.len(),
                self.limit,
                over.join(", ")
            );
        }
        Ok(())
    }
}
