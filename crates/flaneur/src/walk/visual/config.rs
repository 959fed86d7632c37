//! What a VISUAL walk can vary: η, the HDoV-tree's scheme, the node cache, the screen
//! rule, prefetching and never waiting; and their defaults.

use crate::error::{Error, Result};
use crate::hdov::{Scheme, Selection};
use crate::walk::settings::check_screen_tau;
use serde::Serialize;

/// The thesis's threshold for VISUAL's walks (Table 5.3, Figs. 5.24–5.26).
pub const DEFAULT_ETA: f32 = 0.001;
/// The factor our screen rule stretches τ by for an object whose DoV from the viewcell
/// is at most η ([`VisualConfig::faint_tau`]). Chosen on the 3,000-object city (seed 1;
/// `bench fidelity --mode visual --frames 40 --size 640x360 --lod-tau 0.001`): 2 gave
/// 49.9 dB at 32,382 triangles a frame, 2.5 49.7 dB at 30,006, 2.8 and 3 43.4 dB
/// (a cliff: coarser levels of the near, faint objects begin to show); 1 (no stretch)
/// 59.5 dB at 45,017.
pub const FAINT_TAU_STRETCH: f32 = 2.5;
/// The node cache's default size: the 400 pages the thesis's caches stay within
/// (§5.8.3), of 4 KiB.
pub const DEFAULT_NODE_CACHE: usize = 400 * 4096;

/// Everything a VISUAL walk can vary.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VisualConfig {
    /// The DoV threshold η of the search: 0 finds every visible object at the detail
    /// of its DoV; larger draws more of the city at nodes' internal LODs.
    pub eta: f32,
    /// The storage scheme searched; `None`: the smallest one built.
    pub scheme: Option<Scheme>,
    /// The node cache: policy name (`lru`, `dov`, `dovtime`, …) and bytes; `None`: nodes
    /// read from the store every time.
    pub node_cache: Option<(String, usize)>,
    /// Next-cell prefetch, ours (the thesis's VISUAL has none): search and load, on a
    /// thread, the viewcell the eye will be in this many seconds on. `None`: off.
    pub prefetch_k: Option<f32>,
    /// Depth of the view frustum, metres.
    pub far: f32,
    /// The fallback's disk cell outside every viewcell: SF times the frustum's box.
    pub fallback_sf: f32,
    /// Which rule picks what is drawn: ours ([`Selection::Screen`], the default) holds a
    /// node's internal LOD to its stored error projecting under [`VisualConfig::tau`]
    /// from the viewcell, and draws each object at the finer of eq. 5.6's level and the
    /// screen-space one; the thesis's ([`Selection::Thesis`]) for the Table 5.3
    /// reproduction.
    pub selection: Selection,
    /// The screen-space threshold the screen rule holds nodes' internal LODs to, a
    /// fraction of the viewport within [0, 1): the viewer's LOD τ (the thesis's 0.1 %;
    /// 0, full detail, lets no internal LOD pass). The objects' levels are LOD
    /// selection's, under the τ the viewer asks for.
    pub tau: f32,
    /// Under the thesis's selection, each object still at the finer of eq. 5.6's level
    /// and LOD selection's screen-space one (ours, the object half of
    /// [`Selection::Screen`]): eq. 5.6 gives full detail only at a DoV of MAXDOV, half
    /// the view's sphere, so a near façade of DoV 0.1 would stay close to its coarsest
    /// level. The finer level is read by LOD selection when first wanted. Off by
    /// default; the screen rule implies it.
    pub finer_by_tau: bool,
    /// Objects refined view by view take a τ stretched by their DoV
    /// ([`dov_tau`](crate::walk::lod_select::dov_tau)): ours, not the thesis's. Off by
    /// default.
    pub dov_tau: bool,
    /// Under our screen rule, the factor τ is stretched by for an object whose DoV from
    /// the viewcell is at most η (ours; [`faint_tau_scale`](super::faint_tau_scale)): eq. 5.6's reading of a
    /// small DoV (little of the object can be seen, so its detail matters little) with
    /// a bound on the error, where eq. 5.6 alone draws such an object at its coarsest
    /// level whatever the screen says. At least 1 (1: every object under τ, VISUAL η 0's
    /// picture); [`FAINT_TAU_STRETCH`] by default. Objects above η, nodes' internal LODs
    /// and the thesis's selection are untouched.
    pub faint_tau: f32,
    /// Play the path's clock this many times faster than real time, as REVIEW does
    /// with prefetching ([`ReviewConfig::pace`](crate::walk::review::ReviewConfig::pace));
    /// `None`: frames back to back.
    pub pace: Option<f32>,
    /// The viewer's thread never waits on a read (ours): the searches and the finds'
    /// meshes are read on a loader thread, coarsest levels first, and each frame draws
    /// what has arrived, its visual misses counted. Off by default (the thesis's walk).
    pub never_wait: bool,
}

impl Default for VisualConfig {
    /// The thesis's VISUAL: η = 0.001, the smallest scheme, a DoV-Time node cache of
    /// 400 pages, no prefetch, REVIEW's frustum depth and SF; with our screen-space
    /// selection under the thesis's τ of 0.1 %.
    fn default() -> VisualConfig {
        VisualConfig {
            eta: DEFAULT_ETA,
            scheme: None,
            node_cache: Some(("dovtime".into(), DEFAULT_NODE_CACHE)),
            prefetch_k: None,
            far: crate::walk::settings::DEFAULT_FAR,
            fallback_sf: crate::walk::settings::DEFAULT_SF,
            dov_tau: false,
            selection: Selection::Screen,
            tau: crate::walk::lod_select::DEFAULT_TAU,
            finer_by_tau: false,
            faint_tau: FAINT_TAU_STRETCH,
            pace: Some(crate::walk::settings::DEFAULT_PACE),
            never_wait: false,
        }
    }
}

impl VisualConfig {
    /// Whether objects are drawn at the finer of eq. 5.6's level and the screen-space
    /// one: the screen rule, or the thesis's with [`VisualConfig::finer_by_tau`].
    pub fn finer_of(&self) -> bool {
        self.selection == Selection::Screen || self.finer_by_tau
    }

    /// Checks the settings, naming the first one out of range.
    pub fn validate(&self) -> Result<()> {
        if !(self.eta.is_finite() && self.eta >= 0.0) {
            return Err(Error::Invalid(format!(
                "a DoV threshold η of {}: give a number ≥ 0",
                self.eta
            )));
        }
        check_screen_tau(self.tau)?;
        if !(self.faint_tau.is_finite() && self.faint_tau >= 1.0) {
            return Err(Error::Invalid(format!(
                "a faint object's τ stretch of {}: give a number ≥ 1 (1: no stretch)",
                self.faint_tau
            )));
        }
        if let Some(k) = self.prefetch_k {
            crate::walk::settings::check_k(k)?;
        }
        crate::walk::settings::check_far(self.far)?;
        crate::walk::settings::check_sf(self.fallback_sf)?;
        if let Some(p) = self.pace {
            crate::walk::settings::check_pace(p)?;
        }
        Ok(())
    }
}
