//! `flaneur bench pvs-tightness` (ours, for Shou 2002 §5.5.1): the conservative PVS
//! against what a dense sampling of each cell sees. Exits with an error naming every
//! seen object missing from its cell's PVS.

use std::path::PathBuf;

use anyhow::{bail, Result};

use super::report::write_report;
use crate::cli::args::finite_f32;
use flaneur::visibility::SampleOptions;
use flaneur_bench::pvs_tightness::{self, PvsTightnessConfig};

/// `flaneur bench pvs-tightness`'s arguments.
#[derive(clap::Args)]
pub struct PvsTightnessArgs {
    /// A database built with --visibility.
    db: PathBuf,
    /// Cells measured, spread evenly over the walkable ones.
    #[arg(long, default_value_t = PvsTightnessConfig::default().cells)]
    cells: usize,
    /// Seeded interior viewpoints a cell, beside its 8 corners and 4 side-face centres.
    #[arg(long, default_value_t = PvsTightnessConfig::default().interior)]
    interior: usize,
    /// Pixels per side of a cube face (N) of each viewpoint's rays.
    #[arg(long, value_name = "N", default_value_t = PvsTightnessConfig::default().resolution)]
    resolution: u32,
    /// Seeds the interior viewpoints.
    #[arg(long, default_value_t = PvsTightnessConfig::default().seed)]
    seed: u64,
    /// Recompute each cell's PVS with this binary's conservative test (told what the
    /// corners' rays met, as a build tells it) instead of reading the stored one.
    #[arg(long)]
    recompute: bool,
    /// With --recompute: the conservative test's patch size, metres (the stored
    /// setting by default).
    #[arg(long, value_name = "METRES", value_parser = finite_f32, allow_negative_numbers = true, requires = "recompute")]
    sample_spacing: Option<f32>,
    /// With --recompute: occluders further than this from a sample point are not used,
    /// metres (the stored setting by default).
    #[arg(long, value_name = "METRES", value_parser = finite_f32, allow_negative_numbers = true, requires = "recompute")]
    occluder_radius: Option<f32>,
    /// Folder for the CSV and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl PvsTightnessArgs {
    /// Samples the cells, writes the report, and fails on any seen object missing from
    /// a PVS.
    pub fn run(self) -> Result<()> {
        let db = crate::cli::source::open(&self.db)?;
        let stored = db
            .visibility()?
            .map(|h| h.settings.samples)
            .unwrap_or_default();
        let recompute = self.recompute.then(|| {
            (self.sample_spacing.is_some() || self.occluder_radius.is_some()).then(|| {
                SampleOptions {
                    spacing: self.sample_spacing.unwrap_or(stored.spacing),
                    radius: self.occluder_radius.unwrap_or(stored.radius),
                }
            })
        });
        let cfg = PvsTightnessConfig {
            cells: self.cells,
            interior: self.interior,
            resolution: self.resolution,
            seed: self.seed,
            recompute,
        };
        let r = pvs_tightness::run(&db, &cfg)?;
        write_report(&self.out, &r)?;
        let missing = r.missing();
        if !missing.is_empty() {
            let named: Vec<String> = missing
                .iter()
                .map(|(cell, id)| format!("object {id} in cell {cell}"))
                .collect();
            bail!(
                "{} seen objects missing from their cell's PVS: {}",
                missing.len(),
                named.join(", ")
            );
        }
        Ok(())
    }
}
