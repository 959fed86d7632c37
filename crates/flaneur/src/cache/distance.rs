//! Block distance between two boxes — Shou 2002, §4.2.4, the DIST of the
//! distance-priority LRU policy.
//!
//! DIST(A, B) is 0 when the boxes overlap, else the largest of the per-axis gaps, the
//! gap on an axis being the least distance between the two intervals on it (0 where
//! they overlap). Departure: the thesis defines it for real boxes only; here an empty
//! box (`Aabb::EMPTY`, an unknown MBR or no current query) is at distance 0 from
//! everything, and a coordinate that is not a number contributes no gap, so the result
//! is always a finite number or +∞ for infinite boxes, never NaN.

use crate::geom::Aabb;

/// The block distance of Shou 2002 §4.2.4: 0 if `a` and `b` overlap (closed boxes:
/// touching counts), else the maximum over x, y, z of the gap between them on that
/// axis. 0 if either box is empty.
///
/// ```
/// use flaneur::cache::block_distance;
/// use flaneur::geom::Aabb;
/// let a = Aabb::new([0.0, 0.0, 0.0], [10.0, 10.0, 10.0]).unwrap();
/// let b = Aabb::new([13.0, 0.0, 20.0], [15.0, 5.0, 25.0]).unwrap();
/// assert_eq!(block_distance(&a, &b), 10.0); // gaps 3 (x), 0 (y), 10 (z)
/// assert_eq!(block_distance(&a, &a), 0.0);
/// assert_eq!(block_distance(&a, &Aabb::EMPTY), 0.0);
/// ```
pub fn block_distance(a: &Aabb, b: &Aabb) -> f32 {
    if a.is_empty() || b.is_empty() {
        return 0.0;
    }
    // f32::max ignores a NaN operand, so a NaN coordinate yields no gap.
    let gap = |a0: f32, a1: f32, b0: f32, b1: f32| (b0 - a1).max(a0 - b1);
    gap(a.min.x, a.max.x, b.min.x, b.max.x)
        .max(gap(a.min.y, a.max.y, b.min.y, b.max.y))
        .max(gap(a.min.z, a.max.z, b.min.z, b.max.z))
        .max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(min: [f32; 3], max: [f32; 3]) -> Aabb {
        Aabb::new(min, max).unwrap()
    }

    #[test]
    fn overlap_touch_and_containment_are_zero() {
        let a = b([0.0; 3], [10.0; 3]);
        assert_eq!(block_distance(&a, &b([5.0; 3], [20.0; 3])), 0.0);
        assert_eq!(
            block_distance(&a, &b([10.0, 0.0, 0.0], [12.0, 1.0, 1.0])),
            0.0,
            "touching faces"
        );
        assert_eq!(block_distance(&a, &b([2.0; 3], [3.0; 3])), 0.0, "contained");
    }

    #[test]
    fn the_largest_axis_gap_either_side() {
        let a = b([0.0; 3], [10.0; 3]);
        assert_eq!(
            block_distance(&a, &b([14.0, 0.0, 0.0], [15.0, 1.0, 1.0])),
            4.0
        );
        assert_eq!(
            block_distance(&a, &b([-9.0, 0.0, 0.0], [-7.0, 1.0, 1.0])),
            7.0
        );
        // Overlapping on x, apart on y and z: the larger gap counts (not Euclidean).
        let c = b([5.0, 13.0, 16.0], [6.0, 14.0, 17.0]);
        assert_eq!(block_distance(&a, &c), 6.0);
        assert_eq!(block_distance(&c, &a), 6.0, "symmetric");
    }

    #[test]
    fn empty_and_nan_boxes_are_at_zero() {
        let a = b([0.0; 3], [10.0; 3]);
        assert_eq!(block_distance(&Aabb::EMPTY, &a), 0.0);
        let nan = Aabb {
            min: glam::Vec3::splat(f32::NAN),
            max: glam::Vec3::splat(f32::NAN),
        };
        assert!(!block_distance(&a, &nan).is_nan());
    }
}
