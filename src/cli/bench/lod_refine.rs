//! `flaneur bench lod-refine` (Zheng 2007, Tables 4.1, 4.3, Figs. 4.11, 4.12).

use std::path::PathBuf;

use anyhow::Result;

use super::report::write_report;
use crate::cli::args::or_default;
use crate::cli::args::tau;
use flaneur_bench::lod_refine::{self, LodRefineConfig};

/// `flaneur bench lod-refine`'s arguments.
#[derive(clap::Args)]
pub struct LodRefineArgs {
    /// Triangles of the bumpy-torus landmark.
    #[arg(long, default_value_t = lod_refine::DEFAULT_TRIANGLES)]
    triangles: usize,
    /// Frames of the scripted orbit.
    #[arg(long, default_value_t = lod_refine::DEFAULT_FRAMES)]
    frames: usize,
    /// Screen-space errors τ, fractions of the viewport, comma-separated; one run each
    /// [default: 0.001 (the thesis's), 0.0003, 0.0002, 0.0001].
    #[arg(long, value_delimiter = ',', value_parser = tau)]
    taus: Vec<f32>,
    /// Triangle budget (0: none, fidelity alone).
    #[arg(long, default_value_t = flaneur::lod::THESIS_BUDGET)]
    budget: usize,
    /// N: operators per pass (priority, linear) or nodes evaluated (constant-time).
    #[arg(long, default_value_t = flaneur::lod::THESIS_MAX_WORK)]
    max_work: usize,
    /// Runs of each orbit; a frame's times are the shortest over them.
    #[arg(long, default_value_t = LodRefineConfig::default().repeats)]
    repeats: usize,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl LodRefineArgs {
    /// Runs the orbit at every τ and writes the report.
    pub fn run(self) -> Result<()> {
        let LodRefineArgs {
            triangles,
            frames,
            taus,
            budget,
            max_work,
            repeats,
            out,
        } = self;
        let d = LodRefineConfig::default();
        let cfg = LodRefineConfig {
            triangles,
            frames,
            taus: or_default(taus, d.taus.clone()),
            orbit: flaneur_bench::lod_orbit::OrbitConfig {
                budget: (budget > 0).then_some(budget),
                max_work,
                ..d.orbit
            },
            repeats,
            ..d
        };
        println!("lod-refine: a bumpy torus of about {triangles} triangles, {frames} frames");
        let r = lod_refine::run(&cfg)?;
        write_report(&out, &r)
    }
}
