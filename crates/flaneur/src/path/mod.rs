//! Camera paths: poses over time, from wherever they come. The generators, one file
//! each: `motion`, the motion patterns of Shou 2002 §4.4.1 plus a random walk;
//! `street`, a walker on straight streets; `viewcells`, a walk through a database's
//! walkable viewcells. A path is read and written as a CSV file (a recorded session):
//! [`CameraPath::load_csv`], [`CameraPath::save_csv`] (the file's layout opens
//! `csv.rs`). The viewer's velocity and turning rate at a pose (`rates.rs`) are
//! estimated here, below the prefetchers that predict from them.
//!
//! The two walking routes of Zheng 2007 §7.5 are the PVS prefetcher's
//! ([`crate::prefetch::pvs::routes`]): their grid positions stay in its double
//! precision, and `routes::to_path` makes them a [`CameraPath`].

use std::f32::consts::FRAC_PI_2;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::geom::Camera;

mod csv;
pub mod motion;
mod rates;
mod street;
mod viewcells;

pub use rates::{velocity, yaw_rate};
pub use street::street_walk;
pub use viewcells::{cell_poses, cell_walk, CellPoses};

/// Eye height of a walker, metres.
pub const EYE_HEIGHT: f32 = 1.7;

/// One camera pose of a path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Seconds since the start of the path.
    pub time: f64,
    /// The eye, world coordinates (metres).
    pub position: Vec3,
    /// Radians; 0 looks along +x, increasing toward +z (as [`Camera::yaw`]).
    pub yaw: f32,
    /// Radians, positive up (as [`Camera::pitch`]).
    pub pitch: f32,
}

impl Pose {
    /// The camera at this pose, with the thesis's default frustum (45° × 45°, 1 km).
    pub fn camera(&self) -> Result<Camera> {
        Camera::new(self.position, self.yaw, self.pitch)
    }
}

/// A timed sequence of poses: what [`generate`](motion::generate) makes, what a recorded
/// session holds, what [`CameraPath::save_csv`] writes.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct CameraPath {
    /// The poses, in time order (what [`CameraPath::validate`] checks).
    pub poses: Vec<Pose>,
}

impl CameraPath {
    /// A checked path: at least one pose, all finite, pitch strictly inside ±90°, times
    /// strictly increasing.
    pub fn new(poses: Vec<Pose>) -> Result<CameraPath> {
        let p = CameraPath { poses };
        p.validate()?;
        Ok(p)
    }

    /// Checks what [`CameraPath::new`] checks; the error names the first bad pose.
    pub fn validate(&self) -> Result<()> {
        if self.poses.is_empty() {
            return Err(Error::Invalid("camera path has no poses".into()));
        }
        let mut prev = None;
        for (i, pose) in self.poses.iter().enumerate() {
            check_pose(pose, prev)
                .map_err(|what| Error::Invalid(format!("camera path, pose {i}: {what}")))?;
            prev = Some(pose.time);
        }
        Ok(())
    }

    /// Poses in the path.
    pub fn len(&self) -> usize {
        self.poses.len()
    }

    /// Whether it has no pose (a path [`CameraPath::new`] would refuse).
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }

    /// Where the eye is at each pose, in order.
    pub fn positions(&self) -> impl ExactSizeIterator<Item = Vec3> + '_ {
        self.poses.iter().map(|p| p.position)
    }

    /// Seconds from the first pose to the last; 0 for fewer than two poses.
    pub fn duration(&self) -> f64 {
        match (self.poses.first(), self.poses.last()) {
            (Some(a), Some(b)) => b.time - a.time,
            _ => 0.0,
        }
    }

    /// The viewer's turning rate at pose `i` (radians per second, positive as yaw
    /// grows), by the same causal finite difference as [`CameraPath::velocity_at`], the
    /// yaw step taken the short way round. Zero where that is zero. The estimate is
    /// prefetching's: see [`yaw_rate`].
    pub fn yaw_rate_at(&self, i: usize) -> f32 {
        yaw_rate(&self.poses, i)
    }

    /// The viewer's velocity at pose `i` (m/s), by finite difference: from pose `i − 1`
    /// to `i` (causal: what a prefetcher knows at frame `i`), and from pose 0 to 1 for
    /// `i = 0`. Zero for a path of one pose or none, or where two times do not increase;
    /// an `i` past the end is taken as the last pose. The estimate is prefetching's: see
    /// [`velocity`].
    pub fn velocity_at(&self, i: usize) -> Vec3 {
        velocity(&self.poses, i)
    }
}

/// What makes a pose valid after `prev` (the previous pose's time); the reason if not.
pub(crate) fn check_pose(p: &Pose, prev: Option<f64>) -> std::result::Result<(), String> {
    if !p.time.is_finite() || !p.position.is_finite() || !p.yaw.is_finite() || !p.pitch.is_finite()
    {
        return Err("a value is not finite".into());
    }
    if p.pitch.abs() >= FRAC_PI_2 {
        return Err(format!(
            "pitch {} is not strictly between -pi/2 and pi/2",
            p.pitch
        ));
    }
    if let Some(t) = prev {
        if p.time <= t {
            return Err(format!("time {} does not increase (previous {t})", p.time));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn velocity_by_finite_difference() {
        let pose = |t: f64, x: f32| Pose {
            time: t,
            position: Vec3::new(x, 0.0, 0.0),
            yaw: 0.0,
            pitch: 0.0,
        };
        let one = CameraPath::new(vec![pose(0.0, 1.0)]).unwrap();
        assert_eq!(one.velocity_at(0), Vec3::ZERO);
        assert_eq!(one.duration(), 0.0);
        let p = CameraPath::new(vec![pose(0.0, 0.0), pose(0.5, 1.0), pose(1.0, 3.0)]).unwrap();
        assert_eq!(p.velocity_at(0), Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(p.velocity_at(1), Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(p.velocity_at(2), Vec3::new(4.0, 0.0, 0.0));
        assert_eq!(p.velocity_at(99), Vec3::new(4.0, 0.0, 0.0));
        assert_eq!(p.duration(), 1.0);
        assert_eq!(CameraPath::default().velocity_at(0), Vec3::ZERO);
        assert!(CameraPath::new(vec![]).is_err());
        assert!(CameraPath::new(vec![pose(1.0, 0.0), pose(1.0, 1.0)]).is_err());
        assert!(CameraPath::new(vec![pose(0.0, f32::NAN)]).is_err());
        let steep = Pose {
            pitch: 1.6,
            ..pose(0.0, 0.0)
        };
        assert!(CameraPath::new(vec![steep]).is_err());
        assert!(steep.camera().is_err());
    }
}
