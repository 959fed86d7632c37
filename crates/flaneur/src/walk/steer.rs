//! A person steering the camera: held movement keys and mouse motion in, a pose per
//! frame out. Walking keeps the eye at street height and stops it at buildings (the
//! boxes of the objects the walk has loaded around it, grown by a body radius, so it
//! slides along a wall rather than entering it); flying goes anywhere above the ground.
//! No window here: the window turns its events into these calls.

use glam::Vec3;

use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::path::Pose;
use crate::path::EYE_HEIGHT;

/// How far from a wall a walker's eye stays, metres.
const BODY_RADIUS: f32 = 0.4;
/// A steered walker's speed, m/s, unless its caller sets another ([`Steer::speed`]);
/// running is four times it.
pub const WALK_SPEED: f32 = 1.4;
/// How many times faster running is than walking.
const RUN_FACTOR: f32 = 4.0;
/// Radians of turn per pixel of mouse motion.
const MOUSE_SENSITIVITY: f32 = 0.0025;
/// The longest move tested against the walls at once, metres.
const MAX_STEP: f32 = 0.25;
/// How close to straight up or down the view may pitch, radians short of 90°.
const PITCH_MARGIN: f32 = 0.02;

/// A movement key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Move {
    /// Along the view (on the ground when walking).
    Forward,
    /// Against the view.
    Back,
    /// Sideways, to the left of the view.
    Left,
    /// Sideways, to the right of the view.
    Right,
    /// Straight up (flying only).
    Up,
    /// Straight down (flying only).
    Down,
    /// Held with a movement key: four times as fast.
    Run,
}

/// A person steering the camera: held movement keys ([`Move`]) and mouse motion in, a
/// pose per frame out ([`Steer::step`]). Walking keeps the eye at street height
/// ([`EYE_HEIGHT`](crate::path::EYE_HEIGHT) above the ground) and stops it at the boxes
/// it is given (the objects the walk has loaded around it, grown by a body radius of
/// 0.4 m, so that it slides along a wall rather than entering it); flying goes anywhere
/// half a metre or more above the ground. A mouse pixel turns the view by 0.0025 rad. No
/// window here: the window turns its events into these calls.
///
/// ```
/// use flaneur::path::Pose;
/// use flaneur::walk::{Move, Steer};
/// let start = Pose { time: 0.0, position: glam::Vec3::new(0.0, 1.7, 0.0), yaw: 0.0, pitch: 0.0 };
/// let mut steer = Steer::new(start, 0.0)?;
/// steer.key(Move::Forward, true);
/// let pose = steer.step(1.0, &[])?;
/// assert!(pose.position.x > 1.0 && pose.position.y == 1.7); // yaw 0 looks along +x
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct Steer {
    pose: Pose,
    ground: f32,
    held: [bool; 7],
    /// Flying: free height, no collisions.
    pub fly: bool,
    /// Walking speed, m/s (running is four times it); [`WALK_SPEED`] at first.
    pub speed: f32,
}

impl Steer {
    /// Starts at `start` over a ground at height `ground`.
    pub fn new(start: Pose, ground: f32) -> Result<Steer> {
        if !(start.position.is_finite() && start.yaw.is_finite() && start.pitch.is_finite()) {
            return Err(Error::Invalid(format!(
                "a start pose at {} (yaw {}, pitch {}): give finite numbers",
                start.position, start.yaw, start.pitch
            )));
        }
        if !ground.is_finite() {
            return Err(Error::Invalid(format!("ground height {ground}")));
        }
        Ok(Steer {
            pose: start,
            ground,
            held: [false; 7],
            fly: false,
            speed: WALK_SPEED,
        })
    }

    /// Where the camera is now, and when.
    pub fn pose(&self) -> Pose {
        self.pose
    }

    /// Starts the pose's clock again at 0 (a new walk from where the viewer stands).
    pub fn restart_clock(&mut self) {
        self.pose.time = 0.0;
    }

    /// A movement key pressed or released.
    pub fn key(&mut self, key: Move, pressed: bool) {
        self.held[key as usize] = pressed;
    }

    /// Every key released (the window lost focus: it will not hear the releases).
    pub fn release_all(&mut self) {
        self.held = [false; 7];
    }

    /// Mouse motion of `dx`, `dy` pixels: turns and pitches the view.
    pub fn mouse(&mut self, dx: f64, dy: f64) {
        if !(dx.is_finite() && dy.is_finite()) {
            return;
        }
        let limit = std::f32::consts::FRAC_PI_2 - PITCH_MARGIN;
        self.pose.yaw =
            (self.pose.yaw + dx as f32 * MOUSE_SENSITIVITY).rem_euclid(std::f32::consts::TAU);
        self.pose.pitch = (self.pose.pitch - dy as f32 * MOUSE_SENSITIVITY).clamp(-limit, limit);
    }

    /// Advances `dt` seconds; walking, stops at `obstacles` (boxes the eye may not
    /// enter). The pose's time advances by `dt`.
    pub fn step(&mut self, dt: f32, obstacles: &[Aabb]) -> Result<Pose> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::Invalid(format!(
                "a step of {dt} s: give a positive time"
            )));
        }
        let held = |k: Move| self.held[k as usize] as i32 as f32;
        let (sin, cos) = self.pose.yaw.sin_cos();
        // Walking moves on the ground whatever the pitch; flying follows the view.
        let forward = if self.fly {
            let (ps, pc) = self.pose.pitch.sin_cos();
            Vec3::new(cos * pc, ps, sin * pc)
        } else {
            Vec3::new(cos, 0.0, sin)
        };
        let right = Vec3::new(-sin, 0.0, cos);
        let mut wish = forward * (held(Move::Forward) - held(Move::Back))
            + right * (held(Move::Right) - held(Move::Left));
        if self.fly {
            wish += Vec3::Y * (held(Move::Up) - held(Move::Down));
        }
        let speed = self.speed
            * if held(Move::Run) > 0.0 {
                RUN_FACTOR
            } else {
                1.0
            };
        let delta = wish.normalize_or_zero() * speed * dt;
        let mut p = self.pose.position;
        if self.fly {
            p += delta;
            p.y = p.y.max(self.ground + 0.5);
        } else {
            p.y = self.ground + EYE_HEIGHT;
            // In short steps, so that a long frame does not pass through a wall; axis
            // by axis, so that a blocked axis leaves the other to slide along. A box
            // the eye is already in (it started there) does not hold it.
            let steps = (delta.length() / MAX_STEP).ceil().max(1.0) as usize;
            let step = delta / steps as f32;
            for _ in 0..steps {
                for axis in [0, 2] {
                    let mut q = p;
                    q[axis] += step[axis];
                    if !obstacles.iter().any(|b| blocks(b, q) && !blocks(b, p)) {
                        p = q;
                    }
                }
            }
        }
        self.pose.position = p;
        self.pose.time += dt as f64;
        Ok(self.pose)
    }
}

/// Whether a walker's eye at `p` would be inside `b` grown by the body radius.
fn blocks(b: &Aabb, p: Vec3) -> bool {
    let (lo, hi) = (b.min - BODY_RADIUS, b.max + BODY_RADIUS);
    p.x > lo.x && p.x < hi.x && p.z > lo.z && p.z < hi.z && p.y > b.min.y && p.y < b.max.y
}

#[cfg(test)]
mod tests {
    use super::*;

    fn start() -> Steer {
        let pose = Pose {
            time: 0.0,
            position: Vec3::new(0.0, 1.7, 0.0),
            yaw: 0.0,
            pitch: 0.0,
        };
        Steer::new(pose, 0.0).unwrap()
    }

    #[test]
    fn walking_stays_at_street_height_and_stops_at_walls() {
        let mut s = start();
        s.key(Move::Forward, true);
        s.key(Move::Left, true);
        s.mouse(0.0, -200.0); // looking up does not lift a walker
        let wall = Aabb::new([3.0, 0.0, -50.0], [10.0, 30.0, 50.0]).unwrap();
        let mut last = s.pose();
        for _ in 0..100 {
            last = s.step(0.1, &[wall]).unwrap();
            assert_eq!(last.position.y, EYE_HEIGHT);
            assert!(
                last.position.x <= 3.0 - BODY_RADIUS + 1e-4,
                "{}",
                last.position
            );
        }
        // Blocked on x, it slid along the wall on z (left of +x is −z).
        assert!(last.position.z < -5.0, "{}", last.position);
        assert!((last.time - 10.0).abs() < 1e-6);
    }

    #[test]
    fn a_walker_starting_against_a_wall_can_leave_it() {
        let mut s = start();
        // The eye is 0.2 m from the wall: inside it grown by the body radius.
        let wall = Aabb::new([0.2, 0.0, -5.0], [5.0, 30.0, 5.0]).unwrap();
        s.key(Move::Back, true);
        let p = s.step(1.0, &[wall]).unwrap().position;
        assert!(p.x < -1.0, "{p}");
        // Walking back into it stops at its grown face.
        s.key(Move::Back, false);
        s.key(Move::Forward, true);
        let p = s.step(5.0, &[wall]).unwrap().position;
        assert!(p.x <= 0.2 - BODY_RADIUS + 1e-4, "{p}");
    }

    #[test]
    fn running_is_faster_and_flying_climbs() {
        let mut walk = start();
        walk.key(Move::Forward, true);
        let slow = walk.step(1.0, &[]).unwrap().position.x;
        let mut run = start();
        run.key(Move::Forward, true);
        run.key(Move::Run, true);
        let fast = run.step(1.0, &[]).unwrap().position.x;
        assert!((fast / slow - RUN_FACTOR).abs() < 1e-3);

        let mut fly = start();
        fly.fly = true;
        fly.key(Move::Up, true);
        let wall = Aabb::new([-1.0, 0.0, -1.0], [1.0, 30.0, 1.0]).unwrap();
        let p = fly.step(2.0, &[wall]).unwrap().position;
        assert!(p.y > 3.0, "{p}");
        fly.key(Move::Up, false);
        fly.key(Move::Down, true);
        let p = fly.step(100.0, &[]).unwrap().position;
        assert_eq!(p.y, 0.5, "flying stops above the ground");
        fly.release_all();
        assert_eq!(fly.step(1.0, &[]).unwrap().position, p);
    }

    #[test]
    fn the_mouse_turns_and_pitch_is_bounded() {
        let mut s = start();
        s.mouse(100.0, 0.0);
        assert!((s.pose().yaw - 100.0 * MOUSE_SENSITIVITY).abs() < 1e-6);
        s.mouse(0.0, -1e6);
        assert!(s.pose().pitch < std::f32::consts::FRAC_PI_2);
        s.mouse(f64::NAN, 0.0);
        assert!(s.pose().yaw.is_finite());
        assert!(s.step(0.0, &[]).is_err() && s.step(f32::NAN, &[]).is_err());
        let bad = Pose {
            position: Vec3::NAN,
            ..s.pose()
        };
        assert!(Steer::new(bad, 0.0).is_err());
    }
}
