//! The view-dependent error criteria — Zheng 2007 §3.4 (the tests) and §4.4 (the
//! ERROR-EVALUATE and NEED-APPLY of the traversals), with the formulas as the thesis
//! writes them, for a node whose sphere and cone are anchored at its v_c (`dag::attrs`):
//!
//! - out of view (§3.4.1): (γ − φ) > α, where γ is the angle between the view direction
//!   n and v_c − e, φ the angle the bounding sphere subtends from the eye
//!   (sin φ = rad / |v_c − e|) and α the view cone's half-angle;
//! - back-facing (§3.4.2): ((v_c − e)/|v_c − e|)·a > sin θ, a the normal of v_c;
//! - screen-space error (§3.4.3): no split when ap_err < 2τ·tan(α)·d, where
//!   d = (v_c − e)·n and τ is a fraction of the viewport.
//!
//! A node needs a split when none of the three holds; a split node needs a collapse
//! when it would not need a split (one predicate for both passes, so no node is split
//! and collapsed back in one frame for the same view).
//!
//! Choices the thesis leaves open, made here:
//! - The out-of-view test is evaluated on cosines: γ > α + φ ⇔ cos γ < cos(α + φ),
//!   exact since γ and α + φ lie in [0, π] (α < π/2, φ ≤ π/2), where cos is decreasing;
//!   it spares an `acos` and an `asin` per node. An eye inside a node's sphere sees it.
//! - An eye exactly on v_c leaves the direction undefined: the node is in view and not
//!   back-facing.
//! - The priority that orders the priority-oriented traversal (§4.4.1) is the node's
//!   projected error as a fraction of the viewport, ap_err / (2·tan(α)·d): the split
//!   test above is `priority ≥ τ`. A node in view with d ≤ 0 (its sphere reaches behind
//!   the eye) has an infinite priority, and a node out of view or back-facing a negative
//!   one, so it collapses first and splits last.
//! - The view cone stands in for the frustum as in Pajarola's method the thesis follows:
//!   [`View::from_camera`] takes the half-angle of the frustum's diagonal, so the cone
//!   contains the frustum and nothing in view is culled.

use glam::Vec3;

use crate::error::{Error, Result};
use crate::geom::Camera;

/// The viewer as the refinement sees it: the view cone (e, n, α) of Zheng 2007 §3.4.1.
///
/// Fields are public; [`View::validate`] (which [`Refiner::refine`](super::Refiner::refine)
/// calls every frame) rejects a non-finite eye, a look vector that is not of unit length
/// and a field of view outside (0, π).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// The eye e, world coordinates (metres).
    pub eye: Vec3,
    /// The view direction n, a unit vector.
    pub look: Vec3,
    /// The view cone's full apex angle 2α, radians, in (0, π).
    pub fov: f32,
    /// The viewport's size in pixels, when known: only [`View::tau_for_pixels`] needs it.
    pub viewport_px: Option<u32>,
}

impl View {
    /// A view from `eye` along `look` (any non-zero length; it is normalised) with a
    /// cone of full apex angle `fov`. An `Err` on a non-finite eye, a zero or
    /// non-finite look vector, or a field of view outside (0, π).
    pub fn new(eye: Vec3, look: Vec3, fov: f32) -> Result<View> {
        let unit = look
            .try_normalize()
            .ok_or_else(|| Error::Invalid(format!("view: look vector {look} has no direction")))?;
        let view = View {
            eye,
            look: unit,
            fov,
            viewport_px: None,
        };
        view.validate()?;
        Ok(view)
    }

    /// The same view on a viewport of `pixels` (its larger side). An `Err` for 0.
    pub fn with_viewport(self, pixels: u32) -> Result<View> {
        if pixels == 0 {
            return Err(Error::Invalid("view: a viewport of 0 pixels".into()));
        }
        Ok(View {
            viewport_px: Some(pixels),
            ..self
        })
    }

    /// The view cone around a camera's frustum: the camera's eye and forward
    /// direction, and the half-angle of the frustum's diagonal, so that the cone
    /// contains the frustum. An `Err` when the camera is invalid.
    pub fn from_camera(camera: &Camera) -> Result<View> {
        camera.validate()?;
        let (tx, ty) = ((camera.fov_x * 0.5).tan(), (camera.fov_y * 0.5).tan());
        let half = (tx * tx + ty * ty).sqrt().atan();
        View::new(camera.position, camera.forward(), 2.0 * half)
    }

    /// Checks every field; see the type's comment.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: String| Err(Error::Invalid(format!("view: {what}")));
        if !self.eye.is_finite() {
            return bad(format!("eye {} is not finite", self.eye));
        }
        let len = self.look.length();
        if !(len.is_finite() && (len - 1.0).abs() <= 1e-3) {
            return bad(format!(
                "look vector {} must be a unit vector (length {len})",
                self.look
            ));
        }
        if !(self.fov > 0.0 && self.fov < std::f32::consts::PI) {
            return bad(format!(
                "field of view {} must be in (0, pi) radians",
                self.fov
            ));
        }
        if self.viewport_px == Some(0) {
            return bad("a viewport of 0 pixels".into());
        }
        Ok(())
    }

    /// The view cone's half-angle α.
    pub fn half_angle(&self) -> f32 {
        0.5 * self.fov
    }

    /// τ for a screen-space error of `pixels` pixels: `pixels / viewport_px`. An `Err`
    /// without a viewport, or for a number of pixels that is not positive and finite.
    pub fn tau_for_pixels(&self, pixels: f32) -> Result<f32> {
        let viewport = self
            .viewport_px
            .ok_or_else(|| Error::Invalid("view: τ in pixels needs the viewport's size".into()))?;
        if !(pixels.is_finite() && pixels > 0.0) {
            return Err(Error::Invalid(format!(
                "view: a screen-space error of {pixels} pixels must be positive"
            )));
        }
        Ok(pixels / viewport as f32)
    }
}

/// Which of the culling criteria of Zheng 2007 §3.4 apply. The screen-space error
/// always does (through τ); the thesis's experiments (§4.6.1) use both of these.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Criteria {
    /// Coarsen what lies outside the view cone (§3.4.1).
    pub out_of_view: bool,
    /// Coarsen what faces away from the eye (§3.4.2).
    pub back_face: bool,
}

impl Default for Criteria {
    /// Both, as in the thesis's experiments.
    fn default() -> Criteria {
        Criteria {
            out_of_view: true,
            back_face: true,
        }
    }
}

/// What the criteria read of one node: its v_c (sphere centre and cone apex), the unit
/// normal of v_c (the cone's axis; zero when v_c has none), and the attributes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct NodeGeometry {
    pub centre: Vec3,
    pub radius: f32,
    pub axis: Vec3,
    pub cone_sin: f32,
    pub error: f32,
}

/// One node's evaluation (ERROR-EVALUATE, then NEED-APPLY for either pass).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Evaluation {
    /// In view, facing the eye and with an error at or above the threshold.
    pub needs_split: bool,
    /// The order of the priority-oriented traversal; see the module comment.
    pub priority: f32,
}

/// A view, τ and the criteria, with what every node's test shares computed once.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ViewTest {
    eye: Vec3,
    look: Vec3,
    cos_alpha: f32,
    sin_alpha: f32,
    /// 2·tan(α): the screen-space threshold is `tau * two_tan * d`.
    two_tan: f32,
    tau: f32,
    criteria: Criteria,
}

impl ViewTest {
    /// `view` must be valid and `tau` positive (the caller checks both).
    pub fn new(view: &View, tau: f32, criteria: Criteria) -> ViewTest {
        let alpha = view.half_angle();
        ViewTest {
            eye: view.eye,
            look: view.look.normalize(),
            cos_alpha: alpha.cos(),
            sin_alpha: alpha.sin(),
            two_tan: 2.0 * alpha.tan(),
            tau,
            criteria,
        }
    }

    /// (γ − φ) > α, on cosines (module comment).
    pub fn out_of_view(&self, g: &NodeGeometry) -> bool {
        let w = g.centre - self.eye;
        let dist = w.length();
        if dist <= g.radius {
            return false;
        }
        let cos_gamma = w.dot(self.look) / dist;
        let sin_phi = g.radius / dist;
        let cos_phi = (1.0 - sin_phi * sin_phi).max(0.0).sqrt();
        cos_gamma < self.cos_alpha * cos_phi - self.sin_alpha * sin_phi
    }

    /// ((v_c − e)/|v_c − e|)·a > sin θ.
    pub fn back_facing(&self, g: &NodeGeometry) -> bool {
        let w = g.centre - self.eye;
        let dist = w.length();
        dist > 0.0 && w.dot(g.axis) / dist > g.cone_sin
    }

    /// ap_err < 2τ·tan(α)·d, d = (v_c − e)·n.
    pub fn below_screen_error(&self, g: &NodeGeometry) -> bool {
        let d = (g.centre - self.eye).dot(self.look);
        g.error < self.tau * self.two_tan * d
    }

    pub fn evaluate(&self, g: &NodeGeometry) -> Evaluation {
        if (self.criteria.out_of_view && self.out_of_view(g))
            || (self.criteria.back_face && self.back_facing(g))
        {
            return Evaluation {
                needs_split: false,
                priority: -1.0,
            };
        }
        let d = (g.centre - self.eye).dot(self.look);
        let priority = if d > 0.0 {
            g.error / (self.two_tan * d)
        } else {
            f32::INFINITY
        };
        Evaluation {
            needs_split: !self.below_screen_error(g),
            priority,
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;

    fn node(centre: Vec3, radius: f32, axis: Vec3, cone_sin: f32, error: f32) -> NodeGeometry {
        NodeGeometry {
            centre,
            radius,
            axis,
            cone_sin,
            error,
        }
    }

    #[test]
    fn out_of_view_on_cosines_is_the_angle_test() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut disagree = 0;
        let mut out = 0;
        for _ in 0..20_000 {
            let rv = |rng: &mut ChaCha8Rng| {
                Vec3::new(
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                    rng.gen_range(-1.0..1.0),
                )
            };
            let look = rv(&mut rng);
            let Ok(view) = View::new(rv(&mut rng) * 3.0, look, rng.gen_range(0.1..3.0)) else {
                continue;
            };
            let g = node(
                rv(&mut rng) * 3.0,
                rng.gen_range(0.0..1.0),
                Vec3::Y,
                1.0,
                0.0,
            );
            let t = ViewTest::new(&view, 0.01, Criteria::default());
            let w = g.centre - view.eye;
            let literal = w.length() > g.radius && {
                let gamma = (w.dot(view.look) / w.length()).clamp(-1.0, 1.0).acos();
                let phi = (g.radius / w.length()).asin();
                (gamma - phi) > view.half_angle()
            };
            out += literal as usize;
            // Rounding may flip a test that is within a hair of its boundary.
            disagree += (literal != t.out_of_view(&g)) as usize;
        }
        assert!(out > 2_000, "{out}");
        assert!(disagree <= 5, "{disagree}");
    }

    #[test]
    fn the_three_tests_as_the_thesis_writes_them() {
        let view = View::new(Vec3::ZERO, Vec3::Z, 60f32.to_radians()).unwrap();
        let t = ViewTest::new(&view, 0.001, Criteria::default());
        // Ahead, facing the eye (normal toward −z), error well above the threshold.
        let front = node(Vec3::new(0.0, 0.0, 10.0), 0.5, -Vec3::Z, 0.2, 1.0);
        assert!(!t.out_of_view(&front) && !t.back_facing(&front));
        let e = t.evaluate(&front);
        assert!(e.needs_split);
        // Threshold 2τ·tan(30°)·10 ≈ 0.01155.
        assert!((e.priority - 1.0 / (2.0 * 30f32.to_radians().tan() * 10.0)).abs() < 1e-6);
        let fine = NodeGeometry {
            error: 0.0115,
            ..front
        };
        assert!(t.below_screen_error(&fine) && !t.evaluate(&fine).needs_split);
        let coarse = NodeGeometry {
            error: 0.0116,
            ..front
        };
        assert!(t.evaluate(&coarse).needs_split);
        // Facing away: the axis along the line of sight, a narrow cone.
        let back = NodeGeometry {
            axis: Vec3::Z,
            ..front
        };
        assert!(t.back_facing(&back) && !t.evaluate(&back).needs_split);
        assert_eq!(t.evaluate(&back).priority, -1.0);
        // A half-space cone (sin θ = 1) is never back-facing.
        assert!(!t.back_facing(&NodeGeometry {
            cone_sin: 1.0,
            ..back
        }));
        // 40° off axis, a sphere of 5° from the eye: out; of 15°: in.
        let dir = Vec3::new(40f32.to_radians().sin(), 0.0, 40f32.to_radians().cos());
        let side = node(dir * 10.0, 10.0 * 5f32.to_radians().sin(), -dir, 0.0, 1.0);
        assert!(t.out_of_view(&side));
        let wide = NodeGeometry {
            radius: 10.0 * 15f32.to_radians().sin(),
            ..side
        };
        assert!(!t.out_of_view(&wide));
        // Behind the eye but around it: in view, infinite priority.
        let around = node(Vec3::new(0.0, 0.0, -1.0), 2.0, Vec3::Y, 0.0, 0.0);
        let e = t.evaluate(&around);
        assert!(e.needs_split && e.priority == f32::INFINITY);
        // The criteria can be switched off.
        let t = ViewTest::new(
            &view,
            0.001,
            Criteria {
                out_of_view: false,
                back_face: false,
            },
        );
        assert!(t.evaluate(&back).needs_split && t.evaluate(&side).needs_split);
    }

    #[test]
    fn bad_views_are_errors() {
        assert!(View::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Z, 1.0).is_err());
        assert!(View::new(Vec3::ZERO, Vec3::ZERO, 1.0).is_err());
        assert!(View::new(Vec3::ZERO, Vec3::new(0.0, f32::INFINITY, 0.0), 1.0).is_err());
        assert!(View::new(Vec3::ZERO, Vec3::Z, 0.0).is_err());
        assert!(View::new(Vec3::ZERO, Vec3::Z, std::f32::consts::PI).is_err());
        let v = View::new(Vec3::ZERO, Vec3::Z * 7.0, 1.0).unwrap();
        assert!((v.look - Vec3::Z).length() < 1e-6);
        let raw = View {
            look: Vec3::Z * 2.0,
            ..v
        };
        assert!(raw.validate().unwrap_err().to_string().contains("unit"));
        assert!(v.tau_for_pixels(1.0).is_err());
        assert!(v.with_viewport(0).is_err());
        let v = v.with_viewport(1000).unwrap();
        assert_eq!(v.tau_for_pixels(1.0).unwrap(), 0.001);
        assert!(v.tau_for_pixels(-1.0).is_err());
        let cam = Camera::new(Vec3::ONE, 0.3, 0.1).unwrap();
        let v = View::from_camera(&cam).unwrap();
        // The cone of a 45° × 45° frustum reaches its corners: atan(√2·tan 22.5°).
        let expected = 2.0 * (2f32.sqrt() * 22.5f32.to_radians().tan()).atan();
        assert!((v.fov - expected).abs() < 1e-6);
        assert!((v.look - cam.forward()).length() < 1e-6);
    }
}
