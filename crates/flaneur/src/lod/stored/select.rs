//! Which stored level an object is drawn at: the coarsest whose simplification error,
//! seen from the eye, stays under a screen-space threshold (the LOD core's refinement
//! criterion, Zheng 2007 §3.4: a level of error ε metres is fine enough at distance d
//! when ε < 2τ·tan(α)·d, α half the vertical field of view, τ a fraction of the
//! viewport). Apart from the walk's selection so that a program can ask it of one
//! object (`Database::lod_level_for`) without a walk.

use glam::Vec3;

use super::LevelInfo;
use crate::geom::Aabb;

/// The level of `levels` (finest first) to draw at `distance` metres under `tau` for a
/// vertical field of view `fov_y` (radians): the coarsest whose error is below the
/// threshold, 0 when none but the full mesh is.
///
/// ```
/// use flaneur::lod::LevelInfo;
/// use flaneur::lod::level_for;
/// let levels: Vec<LevelInfo> = [(0, 1000, 0.0), (1, 500, 0.01), (2, 250, 0.2)]
///     .iter()
///     .map(|&(level, triangles, error)| LevelInfo { level, triangles, error })
///     .collect();
/// let fov = 60f32.to_radians();
/// assert_eq!(level_for(&levels, 0.0, fov, 0.001), 0); // touching it: full detail
/// assert_eq!(level_for(&levels, 50.0, fov, 0.001), 1);
/// assert_eq!(level_for(&levels, 1000.0, fov, 0.001), 2);
/// ```
pub fn level_for(levels: &[LevelInfo], distance: f32, fov_y: f32, tau: f32) -> usize {
    let threshold = 2.0 * tau * (fov_y * 0.5).tan() * distance.max(0.0);
    levels
        .iter()
        .rposition(|l| l.error < threshold)
        .unwrap_or(0)
}

/// The distance from `p` to the nearest point of `b`, 0 inside it: how far a viewer
/// at `p` is from the object, for [`level_for`].
pub fn distance_to(b: &Aabb, p: Vec3) -> f32 {
    (b.min - p).max(p - b.max).max(Vec3::ZERO).length()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The thesis's τ, 0.1 % of the viewport.
    const TAU: f32 = 0.001;

    fn levels(errors: &[f32]) -> Vec<LevelInfo> {
        errors
            .iter()
            .enumerate()
            .map(|(level, &error)| LevelInfo {
                level,
                triangles: 1000 >> level,
                error,
            })
            .collect()
    }

    #[test]
    fn farther_is_coarser_and_inside_is_full() {
        let l = levels(&[0.0, 0.01, 0.05, 0.3]);
        let fov = 60f32.to_radians();
        let chosen: Vec<usize> = [0.0, 1.0, 20.0, 100.0, 500.0, 1e5]
            .iter()
            .map(|&d| level_for(&l, d, fov, TAU))
            .collect();
        assert_eq!(chosen[0], 0);
        assert!(chosen.windows(2).all(|w| w[0] <= w[1]), "{chosen:?}");
        assert_eq!(*chosen.last().unwrap(), 3);
        // Each choice meets the criterion, and the next coarser level would not.
        for (&d, &k) in [0.0f32, 1.0, 20.0, 100.0, 500.0].iter().zip(&chosen) {
            let threshold = 2.0 * TAU * (fov * 0.5).tan() * d;
            assert!(k == 0 || l[k].error < threshold);
            if k + 1 < l.len() {
                assert!(l[k + 1].error >= threshold, "d {d}: level {k}");
            }
        }
        assert_eq!(level_for(&[], 100.0, fov, TAU), 0);
    }

    #[test]
    fn distance_is_to_the_box() {
        let b = Aabb::new([0.0, 0.0, 0.0], [10.0, 10.0, 10.0]).unwrap();
        assert_eq!(distance_to(&b, Vec3::splat(5.0)), 0.0);
        assert_eq!(distance_to(&b, Vec3::new(13.0, 5.0, 14.0)), 5.0);
    }
}
