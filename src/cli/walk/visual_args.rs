//! The options of `flaneur walk --mode visual` alone, the HDoV-tree's search and its
//! client, kept beside the walk's shared ones (η, --selection, --lod-tau) so that the
//! walk's own file does not grow with each of them.

use anyhow::Result;

use crate::cli::args::seconds_ahead;
use flaneur::walk::visual::VisualConfig;

/// `flaneur walk`'s options for --mode visual only.
#[derive(clap::Args)]
pub(super) struct VisualArgs {
    /// With --mode visual: the storage scheme searched (horizontal, vertical, indexed;
    /// default the smallest built).
    #[arg(long)]
    scheme: Option<String>,
    /// With --mode visual: objects refined view by view take a τ stretched by their DoV
    /// (ours; default off).
    #[arg(long)]
    dov_tau: bool,
    /// With --mode visual --selection thesis: each object at the finer of eq. 5.6's
    /// level and --lod-tau's (ours: the object half of --selection screen, which implies
    /// it; default off).
    #[arg(long)]
    finer_by_tau: bool,
    /// With --mode visual --selection screen: the factor --lod-tau is stretched by for an
    /// object whose DoV from the viewcell is at most η (ours; 1: none stretched).
    #[arg(long, value_name = "X", default_value_t = flaneur::walk::visual::FAINT_TAU_STRETCH)]
    faint_tau: f32,
    /// With --mode visual: prefetch, on a thread, the viewcell the eye will be in this
    /// many seconds on, at most 60 (ours, not the thesis's; default off).
    #[arg(long, value_name = "SECONDS", value_parser = seconds_ahead, allow_negative_numbers = true)]
    next_cell_prefetch: Option<f32>,
}

impl VisualArgs {
    /// Sets these options in `cfg`; an error for a scheme that is none of the three.
    pub(super) fn apply(&self, cfg: &mut VisualConfig) -> Result<()> {
        cfg.dov_tau = self.dov_tau;
        cfg.finer_by_tau = self.finer_by_tau;
        cfg.faint_tau = self.faint_tau;
        cfg.prefetch_k = self.next_cell_prefetch;
        if let Some(s) = &self.scheme {
            cfg.scheme = Some(s.parse().map_err(anyhow::Error::msg)?);
        }
        Ok(())
    }
}
