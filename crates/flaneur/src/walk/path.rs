//! Generated camera paths: a walker at eye height following straight streets and
//! turning at random, deterministically from a seed, staying inside the city.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::{Error, Result};
use crate::geom::Aabb;

/// Eye height of a walker, metres.
pub const EYE_HEIGHT: f32 = 1.7;

/// Camera positions, one per step.
#[derive(Clone, Debug, PartialEq)]
pub struct WalkPath {
    pub positions: Vec<Vec3>,
}

/// A walk of `steps` steps of `step` metres inside `bounds` (on x and z), turning by a
/// right angle with probability `1/segment` per step, and at the city's edge.
pub fn street_walk(
    bounds: &Aabb,
    steps: usize,
    step: f32,
    segment: usize,
    seed: u64,
) -> Result<WalkPath> {
    bounds.validate()?;
    if !(step.is_finite() && step > 0.0) {
        return Err(Error::Invalid(format!(
            "step {step} must be a positive number of metres"
        )));
    }
    let (lo, hi) = (bounds.min, bounds.max);
    let margin = (step * 2.0).min((hi.x - lo.x).min(hi.z - lo.z) * 0.25);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut p = Vec3::new((lo.x + hi.x) * 0.5, lo.y + EYE_HEIGHT, (lo.z + hi.z) * 0.5);
    let dirs = [Vec3::X, Vec3::Z, -Vec3::X, -Vec3::Z];
    let mut d = rng.gen_range(0..4);
    let mut positions = Vec::with_capacity(steps);
    let inside = |q: Vec3| {
        q.x >= lo.x + margin && q.x <= hi.x - margin && q.z >= lo.z + margin && q.z <= hi.z - margin
    };
    for _ in 0..steps {
        positions.push(p);
        if rng.gen_range(0..segment.max(1)) == 0 {
            d = (d + if rng.gen_bool(0.5) { 1 } else { 3 }) % 4;
        }
        let mut tries = 0;
        while !inside(p + dirs[d] * step) && tries < 4 {
            d = (d + 1) % 4;
            tries += 1;
        }
        if tries < 4 {
            p += dirs[d] * step;
        }
    }
    Ok(WalkPath { positions })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stays_inside_and_is_deterministic() {
        let city = Aabb::new([0.0, 0.0, 0.0], [500.0, 40.0, 500.0]).unwrap();
        let a = street_walk(&city, 300, 10.0, 20, 7).unwrap();
        assert_eq!(a, street_walk(&city, 300, 10.0, 20, 7).unwrap());
        assert!(a.positions.iter().all(|p| city.contains_point(*p)));
        assert!(a
            .positions
            .windows(2)
            .all(|w| (w[1] - w[0]).length() <= 10.0 + 1e-3));
    }
}
