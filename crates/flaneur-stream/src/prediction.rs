//! How a view f frames ahead is predicted from the last three frames' eye and aim-at
//! points (Zheng 2007 §5.3, §6.2, and ours).

use glam::Vec3;

/// How a view f frames ahead is predicted from the last frames'.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Predictor {
    /// Zheng's first order (§5.3, §6.2): E' = E_c + f·(E_c − E_p).
    Linear,
    /// Ours, second order: E' = E_c + f·v + f²/2·a with v = E_c − E_p and
    /// a = E_c − 2E_p + E_pp, the same for the aim-at point. A turn is a curve the first
    /// order leaves by its tangent, f² times the curvature off after f frames; the second
    /// follows it to f³.
    Quadratic,
}

impl Predictor {
    /// The eye and aim-at point `f` frames ahead of the current `(eye, aim)`, `before`
    /// being the last frame's and `earlier` the one's before (each `None` until there
    /// is one; the second order falls back to the first until both are there).
    pub fn predict(
        self,
        f: f32,
        (eye, aim): (Vec3, Vec3),
        before: Option<(Vec3, Vec3)>,
        earlier: Option<(Vec3, Vec3)>,
    ) -> (Vec3, Vec3) {
        let Some((ep, ap)) = before else {
            return (eye, aim);
        };
        match (self, earlier) {
            (Predictor::Quadratic, Some((epp, app))) => {
                let ahead =
                    |c: Vec3, p: Vec3, pp: Vec3| c + f * (c - p) + 0.5 * f * f * (c - 2.0 * p + pp);
                (ahead(eye, ep, epp), ahead(aim, ap, app))
            }
            _ => (eye + f * (eye - ep), aim + f * (aim - ap)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frame `k` of a circle of radius 10 about the origin, once round in 150 frames,
    /// looking at the centre.
    fn orbit(k: f32) -> (Vec3, Vec3) {
        let angle = k * std::f32::consts::TAU / 150.0;
        (
            Vec3::new(10.0 * angle.cos(), 2.0, 10.0 * angle.sin()),
            Vec3::ZERO,
        )
    }

    fn miss(p: Predictor, path: impl Fn(f32) -> (Vec3, Vec3), f: f32) -> f32 {
        let (e, a) = p.predict(f, path(10.0), Some(path(9.0)), Some(path(8.0)));
        let (te, ta) = path(10.0 + f);
        e.distance(te) + a.distance(ta)
    }

    #[test]
    fn both_orders_follow_a_straight_walk_and_the_second_a_turn_further() {
        let walk = |k: f32| (Vec3::new(k, 1.7, 0.5 * k), Vec3::new(k + 4.0, 1.5, 0.5 * k));
        for p in [Predictor::Linear, Predictor::Quadratic] {
            assert!(miss(p, walk, 9.0) < 1e-4, "{p:?}");
        }
        // Twelve frames round the circle (a 350 ms round trip at 30 ms a frame).
        let (linear, quadratic) = (
            miss(Predictor::Linear, orbit, 12.0),
            miss(Predictor::Quadratic, orbit, 12.0),
        );
        assert!(quadratic < linear / 3.0, "{quadratic} against {linear}");
        // Without a history, the current view; with one frame, the first order.
        let now = walk(5.0);
        assert_eq!(Predictor::Quadratic.predict(4.0, now, None, None), now);
        let (e, _) = Predictor::Quadratic.predict(4.0, now, Some(walk(4.0)), None);
        assert!(e.distance(walk(9.0).0) < 1e-4);
    }
}
