//! Generated camera paths: a walker at eye height following straight streets and
//! turning at random, deterministically from a seed, staying inside the city.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{CameraPath, Pose, EYE_HEIGHT};
use crate::error::{Error, Result};
use crate::geom::Aabb;

/// A walk of `steps` steps of `step` metres inside `bounds` (on x and z), turning by a
/// right angle with probability `1/segment` per step, and at the city's edge. One pose
/// per step, a step a second, looking level along the step it takes next (the last one
/// along the step it would take).
pub fn street_walk(
    bounds: &Aabb,
    steps: usize,
    step: f32,
    segment: usize,
    seed: u64,
) -> Result<CameraPath> {
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
    let mut poses = Vec::with_capacity(steps);
    let inside = |q: Vec3| {
        q.x >= lo.x + margin && q.x <= hi.x - margin && q.z >= lo.z + margin && q.z <= hi.z - margin
    };
    for i in 0..steps {
        let at = p;
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
        poses.push(Pose {
            time: i as f64,
            position: at,
            yaw: dirs[d].z.atan2(dirs[d].x),
            pitch: 0.0,
        });
    }
    Ok(CameraPath { poses })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stays_inside_and_is_deterministic() {
        let city = Aabb::new([0.0, 0.0, 0.0], [500.0, 40.0, 500.0]).unwrap();
        let a = street_walk(&city, 300, 10.0, 20, 7).unwrap();
        assert_eq!(a, street_walk(&city, 300, 10.0, 20, 7).unwrap());
        assert!(a.positions().all(|p| city.contains_point(p)));
        let at: Vec<Vec3> = a.positions().collect();
        assert!(at.windows(2).all(|w| (w[1] - w[0]).length() <= 10.0 + 1e-3));
        a.validate().unwrap();
    }
}
