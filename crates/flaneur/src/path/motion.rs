//! Camera paths in the motion patterns of Shou 2002 §4.4.1 (Fig. 4.17): the thesis tunes
//! its prefetch factor k on five recorded sessions — normal, fast, slow, turning and
//! backward — without defining them. We define them here, plus a random walk, for any
//! city box, deterministically from a seed.
//!
//! # Where the viewer goes
//!
//! The eye is at street level: `bounds.min.y + 1.7 m` (or the city's top, if the box is
//! lower than that). On the ground it stays inside the city's x/z rectangle shrunk by a
//! margin of `min(7 m, 5 % of the side)` (7 m is half of citygen's default street).
//!
//! Every pattern but `Random` drives along a **street grid** laid over that rectangle:
//! lines one block pitch apart, the pitch being the one of citygen's default city
//! (4 lots × 20 m + a 14 m street = 94 m) stretched so that a whole number of blocks
//! fits (at least one). Edges of the rectangle are streets too (a ring road), so the
//! viewer turns back at the city's edge by turning at its last intersection. At an
//! intersection the viewer turns 90° left or right (evenly) with the pattern's turn
//! probability, or when it cannot go straight on; it goes back only in a dead end.
//!
//! # The patterns
//!
//! Speeds make a 1 km-deep frustum walk meaningful (a car, not a pedestrian). The view
//! turns toward its target heading at most at the pattern's yaw rate, so 90° turns are
//! smooth rotations of the view while the position turns the corner.
//!
//! | pattern    | speed (m/s)          | turns at intersections | yaw rate | view                                  |
//! |------------|----------------------|------------------------|----------|---------------------------------------|
//! | `Normal`   | 15                   | 25 %                   | 90 °/s   | along the street                      |
//! | `Fast`     | 40                   | 25 %                   | 180 °/s  | along the street                      |
//! | `Slow`     | 4                    | 25 %                   | 60 °/s   | along the street                      |
//! | `Turning`  | 15                   | 75 %                   | 120 °/s  | looks around: ±30°, period 4 s        |
//! | `Backward` | 15                   | 25 %                   | 120 °/s  | opposite to the motion (see below)    |
//! | `Random`   | U[2, 40], redrawn    | off the grid (below)   | 180 °/s  | along the motion                      |
//!
//! - `Backward`: the camera looks one way and moves the other. Every U[10, 20] s it
//!   reverses: it starts back along the street it came, and the view swings 180° round
//!   (at the yaw rate, about 1.5 s) to keep looking against the motion. During the first
//!   half of a swing the viewer moves forward; the rest of the time, backward.
//! - `Random`: not bound to streets. Every U[1, 6] s it draws a new speed in
//!   U[2, 40] m/s and turns its heading by U[−120°, 120°]. At the city's edge it is held
//!   inside (clamped) and heads back toward the centre, ±45°.
//!
//! Pitch is `A·sin(2πt / 8 s + φ)` with a random phase: A = 2° (3° for `Turning`, 5° for
//! `Random`). Yaw is continuous (not wrapped into ±π), so consecutive poses differ by the
//! actual turn. Pose `i` is at time `i / fps`. Every pose is finite, and consecutive
//! positions are at most `max speed / fps` apart.

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI, TAU};
use std::str::FromStr;

use glam::{Vec2, Vec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{CameraPath, Pose, EYE_HEIGHT};
use crate::error::{Error, Result};
use crate::geom::Aabb;

/// Nominal block pitch of the street grid, metres: citygen's default 4 lots × 20 m plus
/// a 14 m street.
const BLOCK_PITCH: f32 = 94.0;

/// The frame rates [`generate`] accepts, frames per second.
pub const MIN_FPS: f32 = 0.01;
/// See [`MIN_FPS`].
pub const MAX_FPS: f32 = 10_000.0;

/// A motion pattern of Shou 2002 §4.4.1, or a random walk. See the module docs for the
/// definitions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Motion {
    /// 15 m/s along the streets, turning at a quarter of the intersections.
    Normal,
    /// 40 m/s, as `Normal` otherwise.
    Fast,
    /// 4 m/s, as `Normal` otherwise.
    Slow,
    /// Turning at three quarters of the intersections, the view looking around.
    Turning,
    /// Moving against the view, reversing every 10 to 20 s.
    Backward,
    /// Off the streets: speed and heading redrawn every 1 to 6 s.
    Random,
}

impl Motion {
    /// Every pattern, in the order above.
    pub const ALL: [Motion; 6] = [
        Motion::Normal,
        Motion::Fast,
        Motion::Slow,
        Motion::Turning,
        Motion::Backward,
        Motion::Random,
    ];

    /// The lowercase name that [`FromStr`] parses.
    pub fn name(self) -> &'static str {
        match self {
            Motion::Normal => "normal",
            Motion::Fast => "fast",
            Motion::Slow => "slow",
            Motion::Turning => "turning",
            Motion::Backward => "backward",
            Motion::Random => "random",
        }
    }

    /// The range of the viewer's speed in m/s, `(min, max)`; equal for the constant-speed
    /// patterns. No two consecutive poses are more than `max / fps` apart.
    pub fn speed_range(self) -> (f32, f32) {
        match self.params().speed {
            Speed::Constant(v) => (v, v),
            Speed::Redrawn(lo, hi) => (lo, hi),
        }
    }

    fn params(self) -> Params {
        let deg = |d: f32| d.to_radians();
        let base = Params {
            speed: Speed::Constant(15.0),
            turn_probability: 0.25,
            yaw_rate: deg(90.0),
            look_around: 0.0,
            backward: false,
            pitch_amplitude: deg(2.0),
        };
        match self {
            Motion::Normal => base,
            Motion::Fast => Params {
                speed: Speed::Constant(40.0),
                yaw_rate: deg(180.0),
                ..base
            },
            Motion::Slow => Params {
                speed: Speed::Constant(4.0),
                yaw_rate: deg(60.0),
                ..base
            },
            Motion::Turning => Params {
                turn_probability: 0.75,
                yaw_rate: deg(120.0),
                look_around: deg(30.0),
                pitch_amplitude: deg(3.0),
                ..base
            },
            Motion::Backward => Params {
                yaw_rate: deg(120.0),
                backward: true,
                ..base
            },
            Motion::Random => Params {
                speed: Speed::Redrawn(2.0, 40.0),
                yaw_rate: deg(180.0),
                pitch_amplitude: deg(5.0),
                ..base
            },
        }
    }
}

impl std::fmt::Display for Motion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Motion {
    type Err = Error;

    /// Parses a pattern's name, case-insensitively: `normal`, `fast`, `slow`, `turning`,
    /// `backward` or `random`.
    fn from_str(s: &str) -> Result<Motion> {
        let t = s.trim();
        Motion::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(t))
            .ok_or_else(|| {
                let names: Vec<&str> = Motion::ALL.iter().map(|m| m.name()).collect();
                Error::Invalid(format!(
                    "unknown motion pattern '{s}': expected one of {}",
                    names.join(", ")
                ))
            })
    }
}

/// A path of `frames` poses at `fps` through the city `bounds` in the pattern `motion`,
/// the same for the same arguments. Errors on an invalid box, one with no extent on x
/// or z, no frames, or a frame rate outside [`MIN_FPS`]`..=`[`MAX_FPS`].
///
/// ```
/// use flaneur::geom::Aabb;
/// use flaneur::path::motion::{generate, Motion};
/// # fn main() -> flaneur::Result<()> {
/// let city: Aabb = "0,0,0,2000,80,2000".parse()?;
/// let path = generate(&city, Motion::Fast, 300, 30.0, 7)?;
/// assert_eq!(path.len(), 300);
/// assert!(path.poses.iter().all(|p| city.contains_point(p.position)));
/// assert!((path.velocity_at(10).length() - 40.0).abs() < 1.0); // 40 m/s on a straight
/// assert_eq!(path, generate(&city, Motion::Fast, 300, 30.0, 7)?);
/// let camera = path.poses[0].camera()?; // the 1 km, 45° × 45° frustum of §4.4
/// assert!(camera.frustum().contains_point(camera.far_center() - camera.forward()));
/// # Ok(()) }
/// ```
pub fn generate(
    bounds: &Aabb,
    motion: Motion,
    frames: usize,
    fps: f32,
    seed: u64,
) -> Result<CameraPath> {
    Ok(CameraPath {
        poses: poses(bounds, motion, frames, fps, seed)?.collect(),
    })
}

/// The poses [`generate`] makes, one at a time as they are asked for, in constant
/// memory: a walk of an hour, or of a year, need not hold its path.
///
/// ```
/// use flaneur::geom::Aabb;
/// use flaneur::path::motion::{generate, poses, Motion};
/// # fn main() -> flaneur::Result<()> {
/// let city: Aabb = "0,0,0,2000,80,2000".parse()?;
/// let lazy: Vec<_> = poses(&city, Motion::Turning, 500, 30.0, 3)?.collect();
/// assert_eq!(lazy, generate(&city, Motion::Turning, 500, 30.0, 3)?.poses);
/// assert_eq!(poses(&city, Motion::Normal, 1_000_000_000, 30.0, 3)?.len(), 1_000_000_000);
/// # Ok(()) }
/// ```
pub fn poses(
    bounds: &Aabb,
    motion: Motion,
    frames: usize,
    fps: f32,
    seed: u64,
) -> Result<MotionPoses> {
    bounds.validate()?;
    let ext = bounds.extent();
    if !(ext.x > 0.0 && ext.z > 0.0) {
        return Err(Error::Invalid(format!(
            "city {bounds} has no extent on x or z to walk in"
        )));
    }
    if frames == 0 {
        return Err(Error::Invalid(
            "a camera path needs at least one frame".into(),
        ));
    }
    if !(MIN_FPS..=MAX_FPS).contains(&fps) {
        return Err(Error::Invalid(format!(
            "frame rate {fps} must be in {MIN_FPS}..={MAX_FPS} frames per second"
        )));
    }
    let params = motion.params();
    let margin = Vec2::new((ext.x * 0.05).min(7.0), (ext.z * 0.05).min(7.0));
    let area = Rect {
        min: Vec2::new(bounds.min.x, bounds.min.z) + margin,
        max: Vec2::new(bounds.max.x, bounds.max.z) - margin,
    };
    let eye_y = (bounds.min.y + EYE_HEIGHT).min(bounds.max.y);

    let mut rng =
        ChaCha8Rng::seed_from_u64(seed ^ (motion as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let mover = match params.speed {
        Speed::Constant(speed) => {
            Mover::Street(Street::new(area, speed, params.turn_probability, &mut rng))
        }
        Speed::Redrawn(lo, hi) => Mover::Free(Free::new(area, lo, hi)),
    };
    let pitch_phase = rng.gen_range(0.0..TAU);
    let look_phase = rng.gen_range(0.0..TAU);
    let next_reverse = rng.gen_range(10.0..20.0);
    Ok(MotionPoses {
        params,
        mover,
        rng,
        pitch_phase,
        look_phase,
        next_reverse,
        fps,
        eye_y,
        yaw: f32::NAN,
        next: 0,
        frames,
    })
}

/// The poses of a motion pattern, made as they are asked for ([`poses`]).
pub struct MotionPoses {
    params: Params,
    mover: Mover,
    rng: ChaCha8Rng,
    pitch_phase: f32,
    look_phase: f32,
    next_reverse: f32,
    fps: f32,
    eye_y: f32,
    /// The last pose's yaw; NaN before the first.
    yaw: f32,
    /// The index of the next pose.
    next: usize,
    frames: usize,
}

impl Iterator for MotionPoses {
    type Item = Pose;

    fn next(&mut self) -> Option<Pose> {
        if self.next >= self.frames {
            return None;
        }
        let (i, params, dt) = (self.next, self.params, 1.0 / self.fps);
        self.next += 1;
        let time = i as f64 / self.fps as f64;
        let t = time as f32;
        if i > 0 {
            if params.backward && t >= self.next_reverse {
                self.mover.reverse();
                self.next_reverse = t + self.rng.gen_range(10.0..20.0);
            }
            self.mover.advance(dt, &mut self.rng);
        }
        let mut target = self.mover.heading();
        if params.backward {
            target += PI;
        }
        target += params.look_around * (TAU * t / 4.0 + self.look_phase).sin();
        self.yaw = if self.yaw.is_nan() {
            target
        } else {
            self.yaw + wrap(target - self.yaw).clamp(-params.yaw_rate * dt, params.yaw_rate * dt)
        };
        let p = self.mover.position();
        Some(Pose {
            time,
            position: Vec3::new(p.x, self.eye_y, p.y),
            yaw: self.yaw,
            pitch: params.pitch_amplitude * (TAU * t / 8.0 + self.pitch_phase).sin(),
        })
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = self.frames - self.next;
        (left, Some(left))
    }
}

impl ExactSizeIterator for MotionPoses {}

#[derive(Clone, Copy)]
enum Speed {
    Constant(f32),
    /// Redrawn uniformly in `[min, max)` every few seconds (the random walk).
    Redrawn(f32, f32),
}

/// A pattern's numbers: the rows of the table in the module docs.
#[derive(Clone, Copy)]
struct Params {
    speed: Speed,
    turn_probability: f64,
    /// Radians per second.
    yaw_rate: f32,
    /// Amplitude of the look-around swing, radians (period 4 s).
    look_around: f32,
    backward: bool,
    pitch_amplitude: f32,
}

/// The ground rectangle the viewer stays in, (x, z).
#[derive(Clone, Copy)]
struct Rect {
    min: Vec2,
    max: Vec2,
}

/// (-π, π] copy of an angle.
fn wrap(a: f32) -> f32 {
    let w = a.rem_euclid(TAU);
    if w > PI {
        w - TAU
    } else {
        w
    }
}

/// How the viewer moves on the ground: along streets, or freely.
enum Mover {
    Street(Street),
    Free(Free),
}

impl Mover {
    fn advance(&mut self, dt: f32, rng: &mut ChaCha8Rng) {
        match self {
            Mover::Street(s) => s.advance(s.speed * dt, rng),
            Mover::Free(f) => f.advance(dt, rng),
        }
    }

    fn reverse(&mut self) {
        match self {
            Mover::Street(s) => s.reverse(),
            Mover::Free(f) => f.heading += PI,
        }
    }

    fn position(&self) -> Vec2 {
        match self {
            Mover::Street(s) => s.position(),
            Mover::Free(f) => f.position,
        }
    }

    /// Direction of travel, radians (0 = +x, π/2 = +z).
    fn heading(&self) -> f32 {
        match self {
            Mover::Street(s) => s.dir as f32 * FRAC_PI_2,
            Mover::Free(f) => f.heading,
        }
    }
}

/// Grid directions, indexed so that direction `d` has heading `d · π/2`.
const DIRS: [(i64, i64); 4] = [(1, 0), (0, 1), (-1, 0), (0, -1)];

/// A driver on the street grid: left `node`, heading `dir`, `s` metres along the block.
struct Street {
    origin: Vec2,
    /// Block size on x and z.
    pitch: Vec2,
    /// Blocks on x and z; nodes are `0..=blocks`.
    blocks: (i64, i64),
    node: (i64, i64),
    dir: usize,
    s: f32,
    speed: f32,
    turn_probability: f64,
}

impl Street {
    fn new(area: Rect, speed: f32, turn_probability: f64, rng: &mut ChaCha8Rng) -> Street {
        let size = area.max - area.min;
        let count = |w: f32| (w / BLOCK_PITCH).round().clamp(1.0, 1e6) as i64;
        let blocks = (count(size.x), count(size.y));
        let pitch = Vec2::new(size.x / blocks.0 as f32, size.y / blocks.1 as f32);
        let node = (blocks.0 / 2, blocks.1 / 2);
        let mut s = Street {
            origin: area.min,
            pitch,
            blocks,
            node,
            dir: 0,
            s: 0.0,
            speed,
            turn_probability,
        };
        let open: Vec<usize> = (0..4).filter(|&d| s.open(node, d)).collect();
        s.dir = open[rng.gen_range(0..open.len())];
        s
    }

    fn open(&self, (i, j): (i64, i64), d: usize) -> bool {
        let (a, b) = (i + DIRS[d].0, j + DIRS[d].1);
        (0..=self.blocks.0).contains(&a) && (0..=self.blocks.1).contains(&b)
    }

    fn block_len(&self) -> f32 {
        if self.dir.is_multiple_of(2) {
            self.pitch.x
        } else {
            self.pitch.y
        }
    }

    fn next_node(&self) -> (i64, i64) {
        (
            self.node.0 + DIRS[self.dir].0,
            self.node.1 + DIRS[self.dir].1,
        )
    }

    fn position(&self) -> Vec2 {
        let base = self.origin
            + Vec2::new(
                self.node.0 as f32 * self.pitch.x,
                self.node.1 as f32 * self.pitch.y,
            );
        let (dx, dz) = DIRS[self.dir];
        let p = base + Vec2::new(dx as f32, dz as f32) * self.s;
        // Rounding must not carry the viewer past the ring road.
        p.clamp(
            self.origin,
            self.origin + self.pitch * Vec2::new(self.blocks.0 as f32, self.blocks.1 as f32),
        )
    }

    /// Moves `step` metres along the streets, turning at intersections. The position
    /// moves by at most `step` (by less when the step turns a corner).
    fn advance(&mut self, mut step: f32, rng: &mut ChaCha8Rng) {
        // Bounded: a city whose blocks are far smaller than a step would loop long.
        for _ in 0..1000 {
            let left = self.block_len() - self.s;
            if step < left {
                self.s += step;
                return;
            }
            step -= left.max(0.0);
            self.node = self.next_node();
            self.s = 0.0;
            self.dir = self.choose(rng);
            if step <= 0.0 {
                return;
            }
        }
    }

    /// The way on from `self.node`, arriving along `self.dir`.
    fn choose(&self, rng: &mut ChaCha8Rng) -> usize {
        let d = self.dir;
        let sides: Vec<usize> = [(d + 1) % 4, (d + 3) % 4]
            .into_iter()
            .filter(|&e| self.open(self.node, e))
            .collect();
        let straight = self.open(self.node, d);
        if straight && (sides.is_empty() || !rng.gen_bool(self.turn_probability)) {
            d
        } else if !sides.is_empty() {
            sides[rng.gen_range(0..sides.len())]
        } else {
            (d + 2) % 4
        }
    }

    /// Turns back along the current block.
    fn reverse(&mut self) {
        let len = self.block_len();
        self.node = self.next_node();
        self.dir = (self.dir + 2) % 4;
        self.s = (len - self.s).max(0.0);
    }
}

/// A free walker: the random pattern.
struct Free {
    area: Rect,
    position: Vec2,
    heading: f32,
    speed: f32,
    /// Seconds until the next speed and heading change.
    next_change: f32,
    speeds: (f32, f32),
}

impl Free {
    fn new(area: Rect, lo: f32, hi: f32) -> Free {
        // The first advance draws speed and heading.
        Free {
            area,
            position: (area.min + area.max) * 0.5,
            heading: 0.0,
            speed: 0.0,
            next_change: 0.0,
            speeds: (lo, hi),
        }
    }

    fn advance(&mut self, dt: f32, rng: &mut ChaCha8Rng) {
        self.next_change -= dt;
        if self.next_change <= 0.0 {
            self.speed = rng.gen_range(self.speeds.0..self.speeds.1);
            self.heading += rng.gen_range(-120f32..120.0).to_radians();
            self.next_change = rng.gen_range(1.0..6.0);
        }
        let (s, c) = self.heading.sin_cos();
        let want = self.position + Vec2::new(c, s) * (self.speed * dt);
        // Clamping to a convex set moves a point no farther than it was asked to go.
        let at = want.clamp(self.area.min, self.area.max);
        if at != want {
            let home = (self.area.min + self.area.max) * 0.5 - at;
            let back = if home.length_squared() > 0.0 {
                home.y.atan2(home.x)
            } else {
                self.heading + PI
            };
            // Keep the heading continuous: turn by the wrapped difference.
            self.heading += wrap(back - self.heading) + rng.gen_range(-FRAC_PI_4..FRAC_PI_4);
        }
        self.position = at;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn city() -> Aabb {
        Aabb::new([0.0, 0.0, 0.0], [1000.0, 50.0, 600.0]).unwrap()
    }

    #[test]
    fn names_round_trip() {
        for m in Motion::ALL {
            assert_eq!(m.name().parse::<Motion>().unwrap(), m);
            assert_eq!(m.to_string().to_uppercase().parse::<Motion>().unwrap(), m);
            assert_eq!(
                serde_json::to_string(&m).unwrap(),
                format!("\"{}\"", m.name())
            );
        }
        assert!("sideways".parse::<Motion>().is_err());
    }

    #[test]
    fn bad_arguments_are_errors() {
        let c = city();
        assert!(generate(&c, Motion::Normal, 0, 30.0, 1).is_err());
        assert!(generate(&c, Motion::Normal, 10, 0.0, 1).is_err());
        assert!(generate(&c, Motion::Normal, 10, f32::NAN, 1).is_err());
        assert!(generate(&c, Motion::Normal, 10, f32::INFINITY, 1).is_err());
        assert!(generate(&c, Motion::Normal, 10, 1e-30, 1).is_err());
        let flat = Aabb::new([0.0, 0.0, 5.0], [100.0, 10.0, 5.0]).unwrap();
        assert!(generate(&flat, Motion::Random, 10, 30.0, 1).is_err());
        let nan = Aabb {
            min: Vec3::splat(f32::NAN),
            max: Vec3::ONE,
        };
        assert!(generate(&nan, Motion::Random, 10, 30.0, 1).is_err());
    }

    #[test]
    fn tiny_and_low_cities_still_work() {
        // A city smaller than one step of the fast pattern, and one lower than the eye.
        for bounds in [
            Aabb::new([0.0, 0.0, 0.0], [0.5, 0.5, 0.5]).unwrap(),
            Aabb::new([-3.0, 0.0, 10.0], [300.0, 0.0, 40.0]).unwrap(),
        ] {
            for m in Motion::ALL {
                let p = generate(&bounds, m, 200, 30.0, 9).unwrap();
                p.validate().unwrap();
                assert!(
                    p.poses.iter().all(|q| bounds.contains_point(q.position)),
                    "{m} left {bounds}"
                );
                let (_, max) = m.speed_range();
                assert!(p
                    .poses
                    .windows(2)
                    .all(|w| (w[1].position - w[0].position).length() <= max / 30.0 + 1e-3));
            }
        }
    }

    #[test]
    fn street_patterns_stay_on_the_grid() {
        let c = city();
        for m in [
            Motion::Normal,
            Motion::Turning,
            Motion::Backward,
            Motion::Fast,
        ] {
            let p = generate(&c, m, 3000, 30.0, 4).unwrap();
            let s = Street::new(
                Rect {
                    min: Vec2::splat(7.0),
                    max: Vec2::new(993.0, 593.0),
                },
                15.0,
                0.25,
                &mut ChaCha8Rng::seed_from_u64(0),
            );
            for q in &p.poses {
                let g = (Vec2::new(q.position.x, q.position.z) - s.origin) / s.pitch;
                let off = (g - g.round()).abs();
                assert!(
                    off.min_element() < 1e-3,
                    "{m} off the streets at {}",
                    q.position
                );
            }
        }
    }

    #[test]
    fn wrap_is_half_open() {
        assert!((wrap(3.0 * PI) - PI).abs() < 1e-5);
        assert!((wrap(-0.5) + 0.5).abs() < 1e-6);
        assert!((wrap(TAU + 0.25) - 0.25).abs() < 1e-5);
    }
}
