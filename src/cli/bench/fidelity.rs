//! `flaneur bench fidelity`: each frame of a walk drawn with the mode's selection and
//! at full detail, and compared (the thesis's Figs. 5.26 and 6.6 as numbers); with
//! `--reference`, the full-detail pictures drawn from another file holding the same city
//! (a format-version-2 file against its version-1 twin).

use crate::cli::args::{eta, lod_tau, selection};
use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use super::report::write_report;
use crate::cli::args::parse_size;
use crate::cli::walk::camera_path;
use flaneur::path::cell_walk;
use flaneur::walk::pvs::PvsPrefetch;
use flaneur::walk::review::{Preset, ReviewConfig};
use flaneur::walk::scene::SceneConfig;
use flaneur::walk::scene::Traversal;
use flaneur::walk::visual::VisualConfig;
use flaneur::walk::{WalkConfig, WalkMode};
use flaneur_bench::pvs_prefetch::PvsPrefetchConfig;

/// `flaneur bench fidelity`'s arguments.
#[derive(clap::Args)]
pub struct FidelityArgs {
    /// The database: a file, or a URL (http://… or https://…) on any HTTP server.
    db: PathBuf,
    /// The file (or URL) the full-detail pictures are drawn from: the same city, e.g. the
    /// version-1 twin of a version-2 database, checked to hold the same objects before
    /// anything is drawn [default: the database itself].
    #[arg(long, value_name = "REF")]
    reference: Option<PathBuf>,
    /// A motion pattern (normal, fast, slow, turning, backward, random), a path
    /// CSV file, or (pvs mode) cells: a walk along the walkable viewcells [default:
    /// normal; cells in pvs mode].
    #[arg(long)]
    path: Option<String>,
    /// review, box, pvs (the viewcell's PVS with PBNP prefetching; the database
    /// must have been built with --visibility), visual (the HDoV-tree under --eta;
    /// built with --visibility --hdov), or the memory scene tree by vsc (under --eta),
    /// pb (under --budget) or conv.
    #[arg(long, default_value = "review")]
    mode: WalkMode,
    /// Frames to draw: of a motion pattern or `cells`, how many to make (default 300);
    /// of a path file, its first N poses (default: all of them).
    #[arg(long, value_name = "N")]
    frames: Option<usize>,
    /// Seed of a generated path: the same seed, the same path.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, value_parser = parse_size, default_value = "256x256")]
    size: (u32, u32),
    /// LOD selection's screen-space error for the mode's pictures, a fraction of the
    /// viewport within [0, 1) (0: the mode's objects at full detail).
    #[arg(long, default_value_t = flaneur::walk::lod_select::DEFAULT_TAU, value_parser = lod_tau, allow_negative_numbers = true)]
    lod_tau: f32,
    /// With --mode visual: the DoV threshold η, within [0, 1].
    #[arg(long, default_value_t = flaneur::walk::visual::DEFAULT_ETA, value_parser = eta, allow_negative_numbers = true)]
    eta: f32,
    /// With --mode pb: the polygon budget, triangles a frame.
    #[arg(long, default_value_t = 20_000)]
    budget: u64,
    /// With --mode visual: objects refined view by view take a τ stretched by their
    /// DoV (ours).
    #[arg(long)]
    dov_tau: bool,
    /// With --mode visual --selection thesis: each object at the finer of eq. 5.6's
    /// level and --lod-tau's (ours: the object half of --selection screen, which implies
    /// it).
    #[arg(long)]
    finer_by_tau: bool,
    /// With --mode visual, vsc or pb: the rule that picks internal LODs and levels.
    /// `screen` (ours, the default): a node's internal LOD only where its DoV ≤ η and
    /// eq. 5.4 allow it and its stored error projects under --lod-tau (from the viewcell
    /// for visual, from the eye for vsc and pb), each object at the finer of eq. 5.6's
    /// level and --lod-tau's. `thesis`: Shou 2002's rules, whatever the screen says.
    #[arg(long, default_value = "screen", value_parser = selection)]
    selection: flaneur::hdov::Selection,
    /// With --mode visual --selection screen: the factor --lod-tau is stretched by for an
    /// object whose DoV from the viewcell is at most η (ours; 1: none stretched).
    #[arg(long, value_name = "X", default_value_t = flaneur::walk::visual::FAINT_TAU_STRETCH)]
    faint_tau: f32,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, value_name = "DIR", default_value = "bench-out")]
    out: PathBuf,
}

impl FidelityArgs {
    /// Draws every frame twice, compares them and writes the report.
    pub fn run(self) -> Result<()> {
        let db_name = self.db.display().to_string();
        let db = crate::cli::source::open(&self.db)?;
        let reference = match &self.reference {
            Some(r) => {
                let (r, name) = (crate::cli::source::open(r)?, r.display().to_string());
                // Before the GPU is asked for: another city is the first thing to hear of.
                flaneur_bench::fidelity::same_city(&db, &r)
                    .with_context(|| format!("{name} against {db_name}"))?;
                Some((r, name))
            }
            None => None,
        };
        let mode = self.mode;
        let over_cells = !matches!(mode, WalkMode::Review | WalkMode::Box);
        if over_cells && !db.has_visibility() {
            bail!(
                "{} has no precomputed visibility for the {mode} mode (build it with --visibility)",
                db.store().path().display()
            );
        }
        let fps = 30.0;
        let path = (self.path.clone())
            .unwrap_or_else(|| if over_cells { "cells" } else { "normal" }.to_string());
        let poses = match path.as_str() {
            "cells" if over_cells => {
                cell_walk(&db, self.frames.unwrap_or(300), 1.4 / fps, fps, self.seed)?
            }
            other => camera_path(&db, other, (self.frames, 300), fps, self.seed)?,
        };
        let walk = self.walk_config();
        let gpu = flaneur_render::Gpu::headless()?;
        let size = self.size;
        println!(
            "fidelity: {} frames of {} in {mode} mode, {} × {}, each drawn twice{}",
            poses.poses.len(),
            path,
            size.0,
            size.1,
            reference
                .as_ref()
                .map_or(String::new(), |(_, name)| format!(
                    ", the full-detail pictures from {name}"
                ))
        );
        let bar = indicatif::ProgressBar::new(poses.poses.len() as u64);
        let drawing = flaneur_bench::fidelity::Drawing {
            width: size.0,
            height: size.1,
            lod_tau: (self.lod_tau != 0.0).then_some(self.lod_tau),
        };
        let label = self.label(&walk);
        let tick = |_| bar.inc(1);
        let r = match &reference {
            Some((r, name)) => {
                let r = flaneur_bench::fidelity::Reference { db: r, name };
                let walk = (&walk, label.as_str());
                flaneur_bench::fidelity::run_against(&db, r, &gpu, &poses, walk, &drawing, tick)?
            }
            None => flaneur_bench::fidelity::run(&db, &gpu, &poses, &walk, &label, &drawing, tick)?,
        };
        bar.finish_and_clear();
        write_report(&self.out, &r)
    }

    /// The walk drawn: REVIEW or BOX unpaced, PVS with PBNP prefetching, VISUAL under
    /// --eta unpaced, the scene tree under --eta or --budget; the LOD flags as given.
    fn walk_config(&self) -> WalkConfig {
        let (eta, tau, selection) = (self.eta, self.lod_tau, self.selection);
        let scene = |traversal| {
            WalkConfig::Scene(SceneConfig {
                selection,
                tau,
                ..SceneConfig::new(traversal)
            })
        };
        match self.mode {
            WalkMode::Review | WalkMode::Box => WalkConfig::Review(ReviewConfig {
                pace: None,
                ..ReviewConfig::preset(match self.mode {
                    WalkMode::Box => Preset::Box,
                    _ => Preset::Optimal,
                })
            }),
            WalkMode::Pvs => WalkConfig::from(PvsPrefetch::Pbnp {
                border: PvsPrefetchConfig::default().border,
            }),
            WalkMode::Visual => WalkConfig::Visual(VisualConfig {
                eta,
                dov_tau: self.dov_tau,
                finer_by_tau: self.finer_by_tau,
                selection,
                tau,
                faint_tau: self.faint_tau,
                pace: None,
                ..VisualConfig::default()
            }),
            WalkMode::Vsc => scene(Traversal::Vsc { eta }),
            WalkMode::Pb => scene(Traversal::Pb {
                budget: self.budget,
            }),
            WalkMode::Conv => scene(Traversal::Conv),
        }
    }

    /// The walk's name in the report: the mode, with VISUAL's and the scene tree's
    /// settings.
    fn label(&self, walk: &WalkConfig) -> String {
        let selection = self.selection.name();
        match walk {
            WalkConfig::Visual(v) => format!(
                "visual (η = {}, {selection} selection{}{})",
                v.eta,
                if v.dov_tau { ", DoV τ" } else { "" },
                if v.finer_by_tau { ", finer by τ" } else { "" }
            ),
            WalkConfig::Scene(s) if s.traversal == Traversal::Conv => s.traversal.label(),
            WalkConfig::Scene(s) => format!("{}, {selection} selection", s.traversal.label()),
            _ => self.mode.name().to_string(),
        }
    }
}
