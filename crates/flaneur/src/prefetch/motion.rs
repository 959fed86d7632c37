//! Motion prediction for prefetching (Shou 2002 §4.2.5): what the viewer's motion so
//! far says about where its frustum will be. The viewer's motion is estimated by
//! finite differences of its poses up to the current one (causal: what a prefetcher
//! knows at that frame); the frustum `t` seconds ahead has its far-plane centre at
//! F' = F + t·velocity, and the predicted cell is the box around the frusta from now
//! to k seconds ahead.
//!
//! Departure, named: the thesis predicts the translation only; a viewer turning at a
//! corner leaves such a cell within a few degrees, so the prediction also sweeps the
//! yaw it turns through on the way, up to 45° (`MAX_TURN`).
//!
//! The estimates are the camera paths' ([`crate::path::velocity`], [`crate::path::yaw_rate`],
//! below prefetching); the prediction is the REVIEW walk's, which prefetches the
//! predicted cell when a walk sets its `prefetch_k` (`walk::review::ReviewConfig`).

use glam::Vec3;

use crate::error::{Error, Result};
use crate::geom::{Aabb, Camera};
use crate::path::{velocity, yaw_rate, CameraPath, Pose};

/// The largest turn a prediction foresees, radians: a cell around a wider sweep does
/// not fit the budget beside the viewer's (on the demo city, 90° overflowed 256 MiB on
/// the backward walk and read twice the pages; 45° never overflowed).
pub(crate) const MAX_TURN: f32 = std::f32::consts::FRAC_PI_4;

/// The viewer's motion at a frame, as a prefetcher knows it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ViewerMotion {
    /// Metres per second.
    pub velocity: Vec3,
    /// Radians per second, positive as yaw grows.
    pub yaw_rate: f32,
}

impl ViewerMotion {
    /// The motion at pose `i` of `poses` (see [`velocity`] and [`yaw_rate`]).
    pub fn at(poses: &[Pose], i: usize) -> ViewerMotion {
        ViewerMotion {
            velocity: velocity(poses, i),
            yaw_rate: yaw_rate(poses, i),
        }
    }

    /// The box around the frusta the viewer will have `t` seconds ahead: its eye moved by
    /// t·velocity on the ground (so their far-plane centre is F' = F + t·velocity) and
    /// its view at every yaw it turns through on the way, up to [`MAX_TURN`].
    pub fn frustum_cell(&self, camera: &Camera, t: f32) -> Aabb {
        let eye = camera.position + Vec3::new(self.velocity.x, 0.0, self.velocity.z) * t;
        let turn = (self.yaw_rate * t).clamp(-MAX_TURN, MAX_TURN);
        let at = |yaw: f32| {
            Camera {
                position: eye,
                yaw,
                ..*camera
            }
            .frustum()
            .aabb()
        };
        // One frustum every 15° of the turn: the union of their boxes holds the ones between.
        let steps = (turn.abs() / 15f32.to_radians()).ceil() as usize;
        (1..=steps).fold(at(camera.yaw), |cell, j| {
            cell.union(&at(camera.yaw + turn * j as f32 / steps as f32))
        })
    }

    /// The box around the frusta from now (`frustum_cell`, the box of the current
    /// frustum) to `k` seconds ahead: the predicted cell of §4.2.5, which holds the
    /// frustum whenever, within those k seconds, the viewer leaves the cell it is in.
    pub fn predicted_cell(&self, camera: &Camera, frustum_cell: &Aabb, k: f32) -> Aabb {
        frustum_cell.union(&self.frustum_cell(camera, k))
    }
}

/// The poses a viewer has had so far, from which its motion is estimated frame by
/// frame; they must come in time order, as a path's do.
#[derive(Clone, Debug, Default)]
pub(crate) struct MotionTrack {
    seen: CameraPath,
}

impl MotionTrack {
    /// Takes the pose of frame `frame`; an error if it is not later than the last one.
    pub fn push(&mut self, frame: usize, pose: Pose) -> Result<()> {
        if let Some(last) = self.seen.poses.last() {
            if pose.time.partial_cmp(&last.time) != Some(std::cmp::Ordering::Greater) {
                return Err(Error::Invalid(format!(
                    "frame {frame}: pose at {} s after one at {} s; poses must come in time order",
                    pose.time, last.time
                )));
            }
        }
        self.seen.poses.push(pose);
        Ok(())
    }

    /// The time of the first pose, if any.
    pub fn start(&self) -> Option<f64> {
        self.seen.poses.first().map(|p| p.time)
    }

    /// The viewer's motion at the latest pose.
    pub fn motion(&self) -> ViewerMotion {
        ViewerMotion::at(&self.seen.poses, self.seen.poses.len().saturating_sub(1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(time: f64, x: f32, yaw: f32) -> Pose {
        Pose {
            time,
            position: Vec3::new(x, 1.7, 0.0),
            yaw,
            pitch: 0.0,
        }
    }

    #[test]
    fn a_track_estimates_the_latest_motion_and_refuses_time_going_back() {
        let mut t = MotionTrack::default();
        assert_eq!(t.motion(), ViewerMotion::default());
        t.push(0, pose(0.0, 0.0, 0.0)).unwrap();
        t.push(1, pose(0.5, 2.0, 0.25)).unwrap();
        assert_eq!(t.start(), Some(0.0));
        assert_eq!(t.motion().velocity, Vec3::new(4.0, 0.0, 0.0));
        assert!((t.motion().yaw_rate - 0.5).abs() < 1e-6);
        let e = t.push(2, pose(0.5, 3.0, 0.0)).unwrap_err().to_string();
        assert!(e.contains("frame 2") && e.contains("time order"), "{e}");
    }

    #[test]
    fn the_predicted_cell_holds_the_frusta_ahead() {
        let camera = Camera {
            far: 100.0,
            ..Camera::new(Vec3::new(0.0, 1.7, 0.0), 0.0, 0.0).unwrap()
        };
        let now = camera.frustum().aabb();
        let still = ViewerMotion::default();
        assert_eq!(still.predicted_cell(&camera, &now, 2.0), now);
        let moving = ViewerMotion {
            velocity: Vec3::new(10.0, 5.0, 0.0),
            yaw_rate: 0.0,
        };
        let cell = moving.predicted_cell(&camera, &now, 2.0);
        // F' = F + k·velocity on the ground: 20 m further along x, no higher.
        assert!((cell.max.x - (now.max.x + 20.0)).abs() < 1e-3);
        assert_eq!(cell.max.y, now.max.y);
        // A turn is foreseen up to MAX_TURN, however fast.
        let turning = ViewerMotion {
            velocity: Vec3::ZERO,
            yaw_rate: 10.0,
        };
        let capped = Camera {
            yaw: MAX_TURN,
            ..camera
        };
        let cell = turning.predicted_cell(&camera, &now, 1.0);
        assert!(cell.contains(&capped.frustum().aabb()));
    }
}
