//! What a walk is asked to be: one enum of the modes, each with its settings. The CLI,
//! the window's keys, the live session and the benches all say which walk they want
//! with it, and [`run`](super::run) walks it.

use super::pvs::{PvsPrefetch, PvsWalkConfig};
use super::review::{Preset, Retrieval, ReviewConfig};
use super::scene::{SceneConfig, Traversal};
use super::visual::{VisualConfig, DEFAULT_ETA};
use super::walk_mode::WalkMode;
use crate::error::Result;

/// A walk's mode and settings.
///
/// ```
/// use flaneur::walk::{review, WalkConfig, WalkMode};
/// let cfg = WalkConfig::from(WalkMode::Box);
/// assert_eq!(cfg.mode(), WalkMode::Box);
/// let review = WalkConfig::Review(review::ReviewConfig::preset(review::Preset::Np));
/// assert_eq!(review.mode(), WalkMode::Review);
/// ```
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub enum WalkConfig {
    /// REVIEW or BOX over disk cells (Shou 2002 ch. 4).
    Review(ReviewConfig),
    /// The PVS client (Zheng 2007 ch. 7).
    Pvs(PvsWalkConfig),
    /// VISUAL over the HDoV-tree (Shou 2002 §5.8.5).
    Visual(VisualConfig),
    /// VSC, PB or CONV over the memory scene tree (Shou 2002 ch. 6).
    Scene(SceneConfig),
}

/// The polygon budget a PB walk draws under unless told otherwise: Fig. 6.7's smallest,
/// 20,000 triangles.
pub const DEFAULT_BUDGET: u64 = 20_000;

impl WalkConfig {
    /// The mode walked, by name.
    pub fn mode(&self) -> WalkMode {
        match self {
            WalkConfig::Review(c) if c.retrieval == Retrieval::Box => WalkMode::Box,
            WalkConfig::Review(_) => WalkMode::Review,
            WalkConfig::Pvs(_) => WalkMode::Pvs,
            WalkConfig::Visual(_) => WalkMode::Visual,
            WalkConfig::Scene(c) => match c.traversal {
                Traversal::Vsc { .. } => WalkMode::Vsc,
                Traversal::Pb { .. } => WalkMode::Pb,
                Traversal::Conv => WalkMode::Conv,
            },
        }
    }

    /// Whether the viewer's thread never waits on a read (the modes that can).
    pub fn never_waits(&self) -> bool {
        match self {
            WalkConfig::Review(c) => c.never_wait,
            WalkConfig::Pvs(c) => c.never_wait,
            WalkConfig::Visual(c) => c.never_wait,
            WalkConfig::Scene(_) => false,
        }
    }

    /// The frustum's depth the walk sees to, metres.
    pub fn far(&self) -> f32 {
        match self {
            WalkConfig::Review(c) => c.far,
            WalkConfig::Pvs(_) => crate::geom::DEFAULT_FAR,
            WalkConfig::Visual(c) => c.far,
            WalkConfig::Scene(c) => c.far,
        }
    }

    /// Checks the settings, naming the first one out of range.
    pub fn validate(&self) -> Result<()> {
        match self {
            WalkConfig::Review(c) => c.validate(),
            WalkConfig::Pvs(c) => c.validate(),
            WalkConfig::Visual(c) => c.validate(),
            WalkConfig::Scene(c) => c.validate(),
        }
    }
}

impl From<WalkMode> for WalkConfig {
    /// The mode at its defaults: REVIEW the thesis's optimal configuration, BOX plain
    /// queries, PVS with PBNP prefetching, VISUAL and VSC under [`DEFAULT_ETA`], PB
    /// under [`DEFAULT_BUDGET`].
    fn from(mode: WalkMode) -> WalkConfig {
        match mode {
            WalkMode::Review => WalkConfig::Review(ReviewConfig::preset(Preset::Optimal)),
            WalkMode::Box => WalkConfig::Review(ReviewConfig::preset(Preset::Box)),
            WalkMode::Pvs => WalkConfig::Pvs(PvsWalkConfig::from(PvsPrefetch::Pbnp {
                border: crate::prefetch::pvs::DEFAULT_BORDER,
            })),
            WalkMode::Visual => WalkConfig::Visual(VisualConfig::default()),
            WalkMode::Vsc => {
                WalkConfig::Scene(SceneConfig::new(Traversal::Vsc { eta: DEFAULT_ETA }))
            }
            WalkMode::Pb => WalkConfig::Scene(SceneConfig::new(Traversal::Pb {
                budget: DEFAULT_BUDGET,
            })),
            WalkMode::Conv => WalkConfig::Scene(SceneConfig::new(Traversal::Conv)),
        }
    }
}

impl From<ReviewConfig> for WalkConfig {
    fn from(c: ReviewConfig) -> WalkConfig {
        WalkConfig::Review(c)
    }
}

impl From<PvsWalkConfig> for WalkConfig {
    fn from(c: PvsWalkConfig) -> WalkConfig {
        WalkConfig::Pvs(c)
    }
}

impl From<PvsPrefetch> for WalkConfig {
    fn from(p: PvsPrefetch) -> WalkConfig {
        WalkConfig::Pvs(p.into())
    }
}

impl From<VisualConfig> for WalkConfig {
    fn from(c: VisualConfig) -> WalkConfig {
        WalkConfig::Visual(c)
    }
}

impl From<SceneConfig> for WalkConfig {
    fn from(c: SceneConfig) -> WalkConfig {
        WalkConfig::Scene(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_mode_at_its_defaults_is_walked_as_that_mode_and_valid() {
        for mode in WalkMode::ALL {
            let cfg = WalkConfig::from(mode);
            assert_eq!(cfg.mode(), mode);
            assert_eq!(mode.name().parse::<WalkMode>(), Ok(mode));
            cfg.validate().unwrap();
            assert!(!cfg.never_waits(), "{mode}: the papers' walks wait");
        }
    }

    #[test]
    fn a_setting_out_of_range_is_named_whatever_the_mode() {
        let mut scene = SceneConfig::new(Traversal::Conv);
        scene.tau = 1.5;
        let err = WalkConfig::Scene(scene).validate().unwrap_err().to_string();
        assert!(err.contains("1.5"), "{err}");
        let review = ReviewConfig {
            sf: 0.5,
            ..ReviewConfig::preset(Preset::Optimal)
        };
        assert!(WalkConfig::Review(review).validate().is_err());
    }
}
