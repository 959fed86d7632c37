//! The viewer's motion estimated from its poses: velocity and turning rate at a pose, by
//! a causal finite difference (what a prefetcher knows at that frame). Prefetching's
//! prediction (`prefetch::motion`) and a camera path's `velocity_at` and `yaw_rate_at`
//! share them.

use glam::Vec3;

use super::Pose;

/// The viewer's velocity at pose `i` (m/s), by finite difference: from pose `i − 1`
/// to `i` (causal: what a prefetcher knows at frame `i`), and from pose 0 to 1 for
/// `i = 0`. Zero for one pose or none, or where two times do not increase; an `i` past
/// the end is taken as the last pose.
pub fn velocity(poses: &[Pose], i: usize) -> Vec3 {
    let n = poses.len();
    if n < 2 {
        return Vec3::ZERO;
    }
    let i = i.min(n - 1).max(1);
    let (a, b) = (&poses[i - 1], &poses[i]);
    let dt = b.time - a.time;
    let v = (b.position - a.position) / dt as f32;
    if dt > 0.0 && v.is_finite() {
        v
    } else {
        Vec3::ZERO
    }
}

/// The viewer's turning rate at pose `i` (radians per second, positive as yaw grows),
/// by the same causal finite difference as [`velocity`], the yaw step taken the short
/// way round. Zero where that is zero.
pub fn yaw_rate(poses: &[Pose], i: usize) -> f32 {
    let n = poses.len();
    if n < 2 {
        return 0.0;
    }
    let i = i.min(n - 1).max(1);
    let (a, b) = (&poses[i - 1], &poses[i]);
    let dt = (b.time - a.time) as f32;
    let step = (b.yaw - a.yaw + std::f32::consts::PI).rem_euclid(std::f32::consts::TAU)
        - std::f32::consts::PI;
    let rate = step / dt;
    if dt > 0.0 && rate.is_finite() {
        rate
    } else {
        0.0
    }
}
