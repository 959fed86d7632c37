//! What a scene-tree walk can vary: the traversal and its frustum.

use crate::hdov::Selection;
use crate::walk::scene::Traversal;
use serde::Serialize;

/// What a scene-tree walk can vary.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SceneConfig {
    /// The traversal: CONV, VSC(η) or PB(n).
    pub traversal: Traversal,
    /// Depth of the view frustum, metres.
    pub far: f32,
    /// Which rule picks VSC's and PB's representations: ours ([`Selection::Screen`], the
    /// default) holds each to its stored error projecting under [`SceneConfig::tau`]
    /// from the eye (`walk::scene::traverse_screened`); the thesis's
    /// ([`Selection::Thesis`]) for the Table 6.1 reproduction.
    pub selection: Selection,
    /// The screen rule's threshold, a fraction of the viewport within [0, 1): the
    /// viewer's LOD τ (0, full detail, lets no internal LOD pass).
    pub tau: f32,
}

impl SceneConfig {
    /// `traversal` with REVIEW's frustum depth, under our screen rule at the thesis's τ
    /// of 0.1 %.
    pub fn new(traversal: Traversal) -> SceneConfig {
        SceneConfig {
            traversal,
            far: crate::walk::settings::DEFAULT_FAR,
            selection: Selection::Screen,
            tau: crate::walk::lod_select::DEFAULT_TAU,
        }
    }

    /// Checks the settings, naming the first one out of range.
    pub fn validate(&self) -> crate::error::Result<()> {
        self.traversal.validate()?;
        crate::walk::settings::check_far(self.far)?;
        crate::walk::settings::check_screen_tau(self.tau)
    }
}
