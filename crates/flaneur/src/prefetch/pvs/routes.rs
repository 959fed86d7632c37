//! The two walking routes of Zheng 2007 §7.5 (Fig. 7.6): 3000 steps of 4 m each, the
//! first random with many back-and-forth movements, the second seven straight lines
//! joined by six right-angle turns. The thesis shows them only as a picture; how they
//! are drawn is ours:
//!
//! - Both keep to the walkways of the thesis's synthetic city (the `pvs-prefetch`
//!   experiment's), the middle third of each street, its middle lane of 20 m
//!   viewcells: route 1 where its `walkable` test allows, route 2 by construction. The
//!   thesis's SNP swaps say as much: 1797 on route 2 is exactly 3 × 599, three new
//!   viewcells at every crossing, and 1785 in 585 transactions on route 1 is at least
//!   three each; a walker in a lane beside the buildings would find only two new
//!   viewcells at a crossing along it (the third cell is inside a building).
//! - Route 1 starts at the street crossing nearest the city's centre and keeps a
//!   heading; before each step it changes it with chance 0.04, to the opposite heading
//!   half of those times (the back-and-forth) and to a uniformly random one otherwise:
//!   a new heading every 25 steps (100 m) on average. The thesis gives no figure; at
//!   this one PBNP saves about as large a share of SNP's transactions on route 1 as the
//!   thesis's Table 7.2 shows (17 %), where more frequent turns would make its saving
//!   larger. A step that would leave the walkways is redrawn with a random heading.
//! - Route 2's lines each keep a random distance into their walkway, at least
//!   0.5 m from its edges, and turn where they cross the next line's street. Its
//!   first six lines are a random 85–115 % of a seventh of the route each (in whole
//!   blocks), turning left or right as the city leaves room; the seventh is as long as
//!   the steps left. It needs only the city's street layout ([`StreetGrid`]), not its
//!   PVS table.
//! - On a real city (a database's walkable viewcells) route 1 is the same walk, and
//!   route 2 is [`axis_route`]: lines along x or z that turn early where a building
//!   is in the way.
//! - A route's positions are its start and the point after each step, so a route of n
//!   steps has n + 1. Steps are measured along the route: the step that rounds a
//!   corner of route 2 cuts it, its ends a little less than a step apart.
//! - Both are drawn from a ChaCha8 generator seeded by `seed`.
//! - A route is grid positions, the prefetcher's (double precision, on the ground);
//!   [`to_path`] makes it poses, for a walk to play.

use std::f64::consts::{PI, TAU};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::Position;
use crate::error::{Error, Result};
use crate::path::{CameraPath, Pose};

/// The thesis's routes: 3000 steps of [`THESIS_STEP`].
pub const THESIS_STEPS: usize = 3000;
/// The length of a step of the thesis's routes, metres.
pub const THESIS_STEP: f64 = 4.0;

/// Route 1's chance of changing heading before a step (half of them reversals); why
/// this figure, the module's top comment says.
const TURN_CHANCE: f64 = 0.04;

/// Route 2 keeps at least this far from the edges of its walkways, metres.
const MARGIN: f64 = 0.5;

/// How long a route is and how it is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RouteConfig {
    /// Steps the route takes (its positions are one more).
    pub steps: usize,
    /// Metres per step.
    pub step: f64,
    /// The seed of the ChaCha8 generator the route is drawn from.
    pub seed: u64,
}

impl Default for RouteConfig {
    fn default() -> RouteConfig {
        RouteConfig {
            steps: THESIS_STEPS,
            step: THESIS_STEP,
            seed: 1,
        }
    }
}

impl RouteConfig {
    /// Checks the settings: 1 to 10,000,000 steps of a positive, finite length.
    pub fn validate(&self) -> Result<()> {
        if self.steps == 0 || self.steps > 10_000_000 {
            return Err(Error::Pvs(format!(
                "a route needs 1 to 10,000,000 steps, got {}",
                self.steps
            )));
        }
        if !(self.step.is_finite() && self.step > 0.0) {
            return Err(Error::Pvs(format!(
                "step length {} must be a positive number of metres",
                self.step
            )));
        }
        Ok(())
    }
}

/// A route's settings, and that it can start at `start`.
fn check_start(
    route: u8,
    start: Position,
    cfg: &RouteConfig,
    walkable: &impl Fn(Position) -> Result<bool>,
) -> Result<()> {
    cfg.validate()?;
    if !start.x.is_finite() || !start.z.is_finite() || !walkable(start)? {
        return Err(Error::Pvs(format!(
            "route {route} cannot start at {start}: it is not a walkable position"
        )));
    }
    Ok(())
}

/// Route 1: a random walk from `start` over the positions `walkable` accepts.
///
/// ```
/// use flaneur::prefetch::pvs::Position;
/// use flaneur::prefetch::pvs::routes::{random_route, RouteConfig};
/// // A square 100 m across round the origin.
/// let square = |p: Position| Ok(p.x.abs() < 50.0 && p.z.abs() < 50.0);
/// let cfg = RouteConfig { steps: 100, ..Default::default() };
/// let route = random_route(Position::new(0.0, 0.0), &cfg, square)?;
/// assert_eq!(route.len(), 101);
/// assert!(route.iter().all(|&p| square(p).unwrap()));
/// # Ok::<(), flaneur::Error>(())
/// ```
pub fn random_route(
    start: Position,
    cfg: &RouteConfig,
    walkable: impl Fn(Position) -> Result<bool>,
) -> Result<Vec<Position>> {
    check_start(1, start, cfg, &walkable)?;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let mut heading: f64 = rng.gen_range(0.0..TAU);
    let mut p = start;
    let mut route = Vec::with_capacity(cfg.steps + 1);
    route.push(p);
    for _ in 0..cfg.steps {
        if rng.gen_bool(TURN_CHANCE) {
            heading = if rng.gen_bool(0.5) {
                (heading + PI) % TAU
            } else {
                rng.gen_range(0.0..TAU)
            };
        }
        let mut tries = 0;
        p = loop {
            let q = Position::new(
                p.x + cfg.step * heading.cos(),
                p.z + cfg.step * heading.sin(),
            );
            if walkable(q)? {
                break q;
            }
            tries += 1;
            if tries > 1000 {
                return Err(Error::Pvs(format!(
                    "route 1 is stuck at {p}: no step of {} m from there is walkable",
                    cfg.step
                )));
            }
            heading = rng.gen_range(0.0..TAU);
        };
        route.push(p);
    }
    Ok(route)
}

/// Route 2: its corners (start, six turns, end) and its positions.
#[derive(Clone, Debug, PartialEq)]
pub struct StraightRoute {
    /// Where its lines meet: the start, the six turns and the end.
    pub corners: Vec<Position>,
    /// The start and the point after each step, along the lines.
    pub positions: Vec<Position>,
}

/// Lines of route 2.
const LINES: usize = 7;

/// A city laid out as a regular grid of square blocks with streets between them and
/// round the edge, as route 2 needs to know it: street `i` (counted from 0 along x or
/// z) spans `i * pitch` to `i * pitch + street` metres across, from the origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreetGrid {
    /// Blocks along each side (streets are one more).
    pub blocks: u32,
    /// Metres from one street to the next (a block and a street).
    pub pitch: f64,
    /// Width of a street, metres.
    pub street: f64,
    /// The city's side, metres, the edge streets included. Given rather than derived
    /// from the others, so that a city measured in whole viewcells keeps its own
    /// arithmetic for where its edge lies.
    pub side: f64,
}

/// Route 2: seven straight lines along the streets of `streets` with six right-angle
/// turns, `cfg.steps` steps long.
///
/// ```
/// use flaneur::prefetch::pvs::routes::{straight_route, RouteConfig, StreetGrid};
/// // 12 × 12 blocks of 100 m with 60 m streets.
/// let streets = StreetGrid { blocks: 12, pitch: 160.0, street: 60.0, side: 1980.0 };
/// let route = straight_route(&streets, &RouteConfig { steps: 1000, ..Default::default() })?;
/// assert_eq!(route.corners.len(), 8);
/// assert_eq!(route.positions.len(), 1001);
/// # Ok::<(), flaneur::Error>(())
/// ```
pub fn straight_route(streets: &StreetGrid, cfg: &RouteConfig) -> Result<StraightRoute> {
    cfg.validate()?;
    let street = streets.street;
    let (lane_lo, lane_hi) = (street / 3.0 + MARGIN, 2.0 * street / 3.0 - MARGIN);
    if lane_lo >= lane_hi {
        return Err(Error::Pvs(format!(
            "route 2 keeps {MARGIN} m inside the middle third of a street, which a street {street} m wide does not leave room for"
        )));
    }
    let total = cfg.steps as f64 * cfg.step;
    let blocks = streets.blocks;
    let pitch = streets.pitch;
    let per_line = total / LINES as f64 / pitch;
    let (lo, hi) = (
        (0.85 * per_line).round().max(1.0) as u32,
        (1.15 * per_line).round().max(1.0) as u32,
    );
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    // The coordinate across street `i` of a line `o` metres into it.
    let at = |i: u32, o: f64| f64::from(i) * pitch + o;
    for _attempt in 0..100 {
        // Street indices along x (streets running north–south) and z, and the line's
        // distances into them: a line along x keeps its z street and offset.
        let (mut ix, mut iz) = (rng.gen_range(0..=blocks), rng.gen_range(0..=blocks));
        let (mut ox, mut oz) = (
            rng.gen_range(lane_lo..=lane_hi),
            rng.gen_range(lane_lo..=lane_hi),
        );
        let mut along_x = rng.gen_bool(0.5);
        let mut corners = vec![Position::new(at(ix, ox), at(iz, oz))];
        let mut length = 0.0;
        for _ in 0..LINES - 1 {
            let from = if along_x { ix } else { iz };
            let mut k = rng.gen_range(lo..=hi).min(blocks);
            let fits = |k: u32, up: bool| if up { from + k <= blocks } else { from >= k };
            let mut dirs: Vec<bool> = [true, false].into_iter().filter(|&u| fits(k, u)).collect();
            if dirs.is_empty() {
                k = from.max(blocks - from);
                dirs = vec![from + k <= blocks];
            }
            let up = dirs[rng.gen_range(0..dirs.len())];
            let to = if up { from + k } else { from - k };
            let o = rng.gen_range(lane_lo..=lane_hi);
            if along_x {
                (ix, ox) = (to, o);
            } else {
                (iz, oz) = (to, o);
            }
            let c = Position::new(at(ix, ox), at(iz, oz));
            length += c.distance(*corners.last().expect("the start"));
            corners.push(c);
            along_x = !along_x;
        }
        let left = total - length;
        if left <= 0.0 {
            continue;
        }
        let last = *corners.last().expect("the start");
        let (here, limit) = if along_x {
            (last.x, streets.side)
        } else {
            (last.z, streets.side)
        };
        // The last line runs along its own walkway, which spans the city, so it may go
        // up to the grid's edge either way.
        let room_up = limit - MARGIN - here;
        let room_down = here - MARGIN;
        let ups: Vec<bool> = [(true, room_up), (false, room_down)]
            .into_iter()
            .filter(|&(_, room)| room >= left)
            .map(|(u, _)| u)
            .collect();
        if ups.is_empty() {
            continue;
        }
        let sign = if ups[rng.gen_range(0..ups.len())] {
            1.0
        } else {
            -1.0
        };
        let end = if along_x {
            Position::new(last.x + sign * left, last.z)
        } else {
            Position::new(last.x, last.z + sign * left)
        };
        corners.push(end);
        let positions = sample(&corners, cfg.steps, cfg.step);
        return Ok(StraightRoute { corners, positions });
    }
    Err(Error::Pvs(format!(
        "route 2 of {total} m in seven lines does not fit in a city of {blocks} × {blocks} blocks"
    )))
}

/// Route 2's kind over any walkable area (a real city's walkable viewcells): straight
/// lines along x or z joined by right-angle turns, from `start`. Each line is meant to
/// be a random 85–115 % of a seventh of the route, as on the synthetic city, but a line
/// that would step off the walkable area turns early, left or right as the area allows
/// (back the way it came at a dead end), so a real city's route may have more than
/// seven lines.
///
/// ```
/// use flaneur::prefetch::pvs::Position;
/// use flaneur::prefetch::pvs::routes::{axis_route, RouteConfig};
/// // Two streets 8 m wide and 200 m long, crossing at the origin.
/// let plus = |p: Position| {
///     Ok((p.x.abs() < 4.0 || p.z.abs() < 4.0) && p.x.abs().max(p.z.abs()) < 100.0)
/// };
/// let cfg = RouteConfig { steps: 400, ..Default::default() };
/// let route = axis_route(Position::new(0.0, 0.0), &cfg, plus)?;
/// assert_eq!(route.len(), 401);
/// assert!(route.iter().all(|&p| plus(p).unwrap()));
/// // Every step is 4 m along x or along z.
/// assert!(route.windows(2).all(|w| {
///     let (dx, dz) = ((w[1].x - w[0].x).abs(), (w[1].z - w[0].z).abs());
///     (dx.min(dz) < 1e-9) && ((dx.max(dz) - 4.0).abs() < 1e-9)
/// }));
/// # Ok::<(), flaneur::Error>(())
/// ```
pub fn axis_route(
    start: Position,
    cfg: &RouteConfig,
    walkable: impl Fn(Position) -> Result<bool>,
) -> Result<Vec<Position>> {
    check_start(2, start, cfg, &walkable)?;
    const HEADINGS: [(f64, f64); 4] = [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)];
    let per_line = cfg.steps as f64 / LINES as f64;
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let line_length =
        |rng: &mut ChaCha8Rng| (rng.gen_range(0.85..=1.15) * per_line).round().max(1.0) as usize;
    let next = |p: Position, h: usize| {
        let (dx, dz) = HEADINGS[h];
        Position::new(p.x + cfg.step * dx, p.z + cfg.step * dz)
    };
    let open: Vec<usize> = (0..4)
        .filter_map(|h| {
            walkable(next(start, h))
                .map(|ok| ok.then_some(h))
                .transpose()
        })
        .collect::<Result<_>>()?;
    if open.is_empty() {
        return Err(Error::Pvs(format!(
            "route 2 is stuck at {start}: no step of {} m along x or z from there is walkable",
            cfg.step
        )));
    }
    let mut heading = open[rng.gen_range(0..open.len())];
    let mut left = line_length(&mut rng);
    let mut p = start;
    let mut route = Vec::with_capacity(cfg.steps + 1);
    route.push(p);
    while route.len() <= cfg.steps {
        if left == 0 || !walkable(next(p, heading))? {
            // Turn left or right, whichever the area allows; back at a dead end.
            let mut turns = [(heading + 1) % 4, (heading + 3) % 4];
            if rng.gen_bool(0.5) {
                turns.swap(0, 1);
            }
            let mut chosen = None;
            for h in turns.into_iter().chain([(heading + 2) % 4]) {
                if walkable(next(p, h))? {
                    chosen = Some(h);
                    break;
                }
            }
            heading = chosen.ok_or_else(|| {
                Error::Pvs(format!(
                    "route 2 is stuck at {p}: no step of {} m along x or z from there is walkable",
                    cfg.step
                ))
            })?;
            left = line_length(&mut rng);
        }
        p = next(p, heading);
        route.push(p);
        left -= 1;
    }
    Ok(route)
}

/// `route` as poses: the eye `eye_y` above the ground's origin, one position a frame at
/// `fps`, looking level along the step it takes next (the last one along the step that
/// brought it there; a route of one position looks along +x).
pub fn to_path(route: &[Position], eye_y: f32, fps: f32) -> Result<CameraPath> {
    let at = |p: &Position| glam::Vec3::new(p.x as f32, eye_y, p.z as f32);
    let mut yaw = 0.0;
    let poses = route
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let towards = route.get(i + 1).filter(|q| *q != p);
            if let Some(q) = towards {
                yaw = ((q.z - p.z) as f32).atan2((q.x - p.x) as f32);
            }
            Pose {
                time: i as f64 / fps as f64,
                position: at(p),
                yaw,
                pitch: 0.0,
            }
        })
        .collect();
    CameraPath::new(poses)
}

/// The start and the point after each of `steps` steps of `step` metres along the
/// polyline through `corners`.
fn sample(corners: &[Position], steps: usize, step: f64) -> Vec<Position> {
    let mut out = Vec::with_capacity(steps + 1);
    let mut seg = 0;
    let mut seg_start = 0.0;
    for k in 0..=steps {
        let s = k as f64 * step;
        while seg + 2 < corners.len() && s > seg_start + corners[seg].distance(corners[seg + 1]) {
            seg_start += corners[seg].distance(corners[seg + 1]);
            seg += 1;
        }
        let (a, b) = (corners[seg], corners[seg + 1]);
        let len = a.distance(b);
        let t = if len > 0.0 {
            ((s - seg_start) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push(Position::new(a.x + t * (b.x - a.x), a.z + t * (b.z - a.z)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_axis_route_turns_where_the_area_ends_and_says_when_stuck() {
        // A plus of two 8 m wide streets, 200 m long, crossing at the origin.
        let plus = |p: Position| {
            Ok((p.x.abs() < 4.0 || p.z.abs() < 4.0) && p.x.abs().max(p.z.abs()) < 100.0)
        };
        let cfg = RouteConfig {
            steps: 1000,
            ..Default::default()
        };
        let r = axis_route(Position::new(0.0, 0.0), &cfg, plus).unwrap();
        assert_eq!(r.len(), 1001);
        assert!(r.iter().all(|&p| plus(p).unwrap()));
        // It reached an end of the plus and came back: more than one line.
        assert!(r.iter().any(|p| p.x.abs().max(p.z.abs()) > 90.0));
        let turns = r.windows(3).filter(|w| {
            let (a, b) = (
                (w[1].x - w[0].x, w[1].z - w[0].z),
                (w[2].x - w[1].x, w[2].z - w[1].z),
            );
            (a.0 - b.0).abs() + (a.1 - b.1).abs() > 1e-9
        });
        assert!(turns.count() >= 5);
        // A lone spot: nowhere to go.
        let spot = |p: Position| Ok(p.x.abs() < 1.0 && p.z.abs() < 1.0);
        let err = axis_route(Position::new(0.0, 0.0), &cfg, spot).unwrap_err();
        assert!(err.to_string().contains("stuck"), "{err}");
        let err = axis_route(Position::new(50.0, 50.0), &cfg, plus).unwrap_err();
        assert!(err.to_string().contains("not a walkable position"), "{err}");
    }

    #[test]
    fn a_route_plays_as_poses() {
        // An open square 1 km across: nothing turns the walk but its own draws.
        let open = |p: Position| Ok(p.x.abs() < 500.0 && p.z.abs() < 500.0);
        let cfg = RouteConfig {
            steps: 50,
            ..Default::default()
        };
        let r = random_route(Position::new(0.0, 0.0), &cfg, open).unwrap();
        let path = to_path(&r, 1.7, 30.0).unwrap();
        assert_eq!(path.len(), r.len());
        for (pose, p) in path.poses.iter().zip(&r) {
            assert_eq!((pose.position.x, pose.position.z), (p.x as f32, p.z as f32));
            assert_eq!(pose.position.y, 1.7);
        }
        // Each pose looks along its step.
        for (w, pose) in r.windows(2).zip(&path.poses) {
            let (s, c) = pose.yaw.sin_cos();
            let step = ((w[1].x - w[0].x) as f32, (w[1].z - w[0].z) as f32);
            assert!((c * step.1 - s * step.0).abs() < 1e-3 && c * step.0 + s * step.1 > 0.0);
        }
        assert!((path.duration() - 50.0 / 30.0).abs() < 1e-9);
        assert!(to_path(&[], 1.7, 30.0).is_err());
    }

    #[test]
    fn route_2_needs_room_and_sound_settings() {
        // 2 × 2 blocks of 100 m with 60 m streets: far too small for 12 km.
        let small = StreetGrid {
            blocks: 2,
            pitch: 160.0,
            street: 60.0,
            side: 380.0,
        };
        let e = straight_route(&small, &RouteConfig::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("does not fit"), "{e}");
        let narrow = StreetGrid {
            street: 2.0,
            ..small
        };
        let cfg = RouteConfig {
            steps: 10,
            ..Default::default()
        };
        let e = straight_route(&narrow, &cfg).unwrap_err().to_string();
        assert!(e.contains("does not leave room"), "{e}");
        for cfg in [
            RouteConfig {
                steps: 0,
                ..Default::default()
            },
            RouteConfig {
                step: f64::NAN,
                ..Default::default()
            },
        ] {
            assert!(straight_route(&small, &cfg).is_err());
        }
    }
}
