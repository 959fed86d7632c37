//! The occlusion horizon of one viewpoint over ground-standing occluders (a 2.5D cull
//! map, after Wonka, Wimmer and Schmalstieg 2000): the directions around the eye in
//! angular bins, and in each bin, by distance, how steeply the occluders met so far
//! rise above the eye. A box is hidden when, in every bin it spans, an occluder
//! entered before the box's nearest point rises more steeply than the box's top seen
//! from there.
//!
//! Why it is exact (never hides a visible point): a prism stands on the ground with
//! footprint F and top h. A sight line from the eye p (height y) to a point q (plan
//! distance d, height ≤ H) that enters F at plan distance e < d is, there, at height
//! y + (e/d)(q_y − y) ≤ y + (e/d)·max(H − y, 0). If that is at most h, the line is in
//! the prism, and q is hidden. In a bin the occluder is counted only where it covers
//! the bin's whole angle, with e the largest entry distance over the bin (reached at a
//! bin edge or a corner, the front of a convex footprint being a chain of segments),
//! and a box is tested with its least plan distance and its top: each bound makes the
//! test stricter. Many occluders fuse: each bin may be closed by a different one.

use std::f32::consts::PI;
use std::sync::OnceLock;

use glam::{Vec2, Vec3};

use crate::geom::Aabb;

/// Angular bins around the eye.
pub const BINS: usize = 1024;
const BIN: f32 = 2.0 * PI / BINS as f32;
/// Angles are padded by this (radians) so that rounding never widens what an occluder
/// covers or narrows what a box spans.
const PAD: f32 = 1e-5;

/// An occluder standing on the ground: a footprint in (x, z) and the height of its top.
/// Everything of it from the ground up to `top` is inside a solid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prism {
    pub min: Vec2,
    pub max: Vec2,
    pub top: f32,
}

impl Prism {
    /// The prism shrunk by `e` on every side and at the top; `None` when nothing is
    /// left of its footprint.
    pub fn shrunk(&self, e: f32) -> Option<Prism> {
        let (min, max) = (self.min + e, self.max - e);
        (min.x < max.x && min.y < max.y).then_some(Prism {
            min,
            max,
            top: self.top - e,
        })
    }

    /// Whether the point `p` (x, y, z) is inside the prism (standing on the ground).
    pub fn contains(&self, p: Vec3) -> bool {
        p.x > self.min.x
            && p.x < self.max.x
            && p.z > self.min.y
            && p.z < self.max.y
            && p.y < self.top
    }
}

fn plan(v: Vec3) -> Vec2 {
    Vec2::new(v.x, v.z)
}

fn corners2(min: Vec2, max: Vec2) -> [Vec2; 4] {
    [min, Vec2::new(max.x, min.y), max, Vec2::new(min.x, max.y)]
}

/// Angle of `v` measured so that wrapping about the reference `reference` gives a
/// value in (reference − π, reference + π].
fn unwrapped(v: Vec2, reference: f32) -> f32 {
    let mut a = v.y.atan2(v.x);
    while a - reference > PI {
        a -= 2.0 * PI;
    }
    while a - reference <= -PI {
        a += 2.0 * PI;
    }
    a
}

/// The angular span of the rectangle seen from `eye`, which lies outside it, as
/// (low, high) with high − low < π, and each corner's angle on the same unwrapped scale.
fn span(eye: Vec2, min: Vec2, max: Vec2) -> (f32, f32, [f32; 4]) {
    let centre = 0.5 * (min + max) - eye;
    let reference = centre.y.atan2(centre.x);
    let angles = corners2(min, max).map(|c| unwrapped(c - eye, reference));
    let lo = angles.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = angles.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    (lo, hi, angles)
}

/// The direction of each bin edge, `BINS + 1` of them from −π.
fn edges() -> &'static [Vec2] {
    static EDGES: OnceLock<Vec<Vec2>> = OnceLock::new();
    EDGES.get_or_init(|| {
        (0..=BINS)
            .map(|k| {
                let a = bin_start(k as i64);
                Vec2::new(a.cos(), a.sin())
            })
            .collect()
    })
}

/// The plan distance at which the ray from `eye` along `dir` enters the rectangle.
fn entry(eye: Vec2, dir: Vec2, min: Vec2, max: Vec2) -> Option<f32> {
    let (mut near, mut far) = (0.0f32, f32::INFINITY);
    for k in 0..2 {
        if dir[k].abs() < 1e-12 {
            if eye[k] < min[k] || eye[k] > max[k] {
                return None;
            }
            continue;
        }
        let (a, b) = ((min[k] - eye[k]) / dir[k], (max[k] - eye[k]) / dir[k]);
        near = near.max(a.min(b));
        far = far.min(a.max(b));
    }
    (near <= far).then_some(near)
}

fn bin_start(k: i64) -> f32 {
    k as f32 * BIN - PI
}

/// One viewpoint's horizon.
pub struct Horizon {
    eye: Vec3,
    /// `fronts[starts[b]..starts[b + 1]]`: bin b's (entry distance, steepest rise so
    /// far), distances ascending and rises strictly increasing.
    starts: Vec<u32>,
    fronts: Vec<(f32, f32)>,
}

impl Horizon {
    /// The horizon of `eye` over `prisms`, none of which may contain the eye's plan
    /// position (those are skipped).
    pub fn new(eye: Vec3, prisms: impl IntoIterator<Item = Prism>) -> Horizon {
        let p = plan(eye);
        let edges = edges();
        let mut entries: Vec<(u32, f32, f32)> = Vec::new();
        for o in prisms {
            let rise = o.top - eye.y;
            let inside = p.x >= o.min.x && p.x <= o.max.x && p.y >= o.min.y && p.y <= o.max.y;
            if rise <= 0.0 || inside {
                continue;
            }
            let (lo, hi, angles) = span(p, o.min, o.max);
            let first = ((lo + PAD + PI) / BIN).ceil() as i64;
            let last = ((hi - PAD + PI) / BIN).floor() as i64 - 1;
            if first > last {
                continue;
            }
            let corners = corners2(o.min, o.max);
            // Entry distances at the covered bins' edges, each edge shared by two bins.
            let mut before = entry(
                p,
                edges[first.rem_euclid(BINS as i64) as usize],
                o.min,
                o.max,
            );
            for k in first..=last {
                let (a0, a1) = (bin_start(k), bin_start(k + 1));
                let after = entry(
                    p,
                    edges[(k + 1).rem_euclid(BINS as i64) as usize],
                    o.min,
                    o.max,
                );
                let (Some(e0), Some(e1)) = (before, after) else {
                    before = after;
                    continue;
                };
                before = after;
                let mut e = e0.max(e1);
                for (c, &a) in corners.iter().zip(&angles) {
                    if a >= a0 && a <= a1 {
                        e = e.max((*c - p).length());
                    }
                }
                if e > 0.0 {
                    entries.push((k.rem_euclid(BINS as i64) as u32, e, rise / e));
                }
            }
        }
        // Bucket by bin (a counting sort), then order each bin by distance.
        let mut first = vec![0u32; BINS + 1];
        for e in &entries {
            first[e.0 as usize + 1] += 1;
        }
        for b in 0..BINS {
            first[b + 1] += first[b];
        }
        let mut fill = first.clone();
        let mut by_bin = vec![(0.0f32, 0.0f32); entries.len()];
        for &(b, e, rise) in &entries {
            by_bin[fill[b as usize] as usize] = (e, rise);
            fill[b as usize] += 1;
        }
        let mut starts = Vec::with_capacity(BINS + 1);
        let mut fronts = Vec::with_capacity(entries.len() / 4);
        for b in 0..BINS {
            starts.push(fronts.len() as u32);
            let bin = &mut by_bin[first[b] as usize..first[b + 1] as usize];
            bin.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
            let mut best = f32::NEG_INFINITY;
            for &(e, rise) in bin.iter() {
                if rise > best {
                    best = rise;
                    fronts.push((e, rise));
                }
            }
        }
        starts.push(fronts.len() as u32);
        Horizon {
            eye,
            starts,
            fronts,
        }
    }

    /// Whether every point of `b` is hidden from the eye.
    pub fn hides(&self, b: &Aabb) -> bool {
        let p = plan(self.eye);
        let (min, max) = (plan(b.min), plan(b.max));
        let nearest = p.clamp(min, max);
        let d = (nearest - p).length();
        if d <= 0.0 {
            return false;
        }
        let need = (b.max.y - self.eye.y).max(0.0) / d;
        let (lo, hi, _) = span(p, min, max);
        let first = ((lo - PAD + PI) / BIN).floor() as i64;
        let last = ((hi + PAD + PI) / BIN).floor() as i64;
        if last - first >= BINS as i64 {
            return false;
        }
        (first..=last).all(|k| {
            let b = k.rem_euclid(BINS as i64) as usize;
            let front = &self.fronts[self.starts[b] as usize..self.starts[b + 1] as usize];
            // The steepest occluder entered before the box's nearest point.
            let before = front.partition_point(|&(e, _)| e < d);
            before > 0 && front[before - 1].1 >= need
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn prism(min: [f32; 2], max: [f32; 2], top: f32) -> Prism {
        Prism {
            min: Vec2::from(min),
            max: Vec2::from(max),
            top,
        }
    }

    fn b(min: [f32; 3], max: [f32; 3]) -> Aabb {
        Aabb::new(min, max).unwrap()
    }

    #[test]
    fn a_wall_hides_what_is_low_behind_it() {
        let eye = Vec3::new(0.0, 1.6, 0.0);
        let wall = prism([-30.0, 10.0], [30.0, 12.0], 10.0);
        let h = Horizon::new(eye, [wall]);
        assert!(h.hides(&b([-2.0, 0.0, 30.0], [2.0, 15.0, 34.0])));
        // Its top shows: at 30 m a 30 m tower rises above the wall's line (8.4/12 per m).
        assert!(!h.hides(&b([-2.0, 0.0, 30.0], [2.0, 30.0, 34.0])));
        // Beside the wall, or in front of it, or reaching past its end.
        assert!(!h.hides(&b([100.0, 0.0, 20.0], [104.0, 5.0, 24.0])));
        assert!(!h.hides(&b([-2.0, 0.0, 5.0], [2.0, 5.0, 8.0])));
        assert!(!h.hides(&b([25.0, 0.0, 30.0], [200.0, 5.0, 34.0])));
        // Behind the eye.
        assert!(!h.hides(&b([-2.0, 0.0, -34.0], [2.0, 5.0, -30.0])));
    }

    #[test]
    fn two_walls_with_a_gap_hide_only_together_with_a_third() {
        let eye = Vec3::new(0.0, 1.6, 0.0);
        let left = prism([-30.0, 10.0], [-1.0, 12.0], 10.0);
        let right = prism([1.0, 10.0], [30.0, 12.0], 10.0);
        let target = b([-2.0, 0.0, 40.0], [2.0, 5.0, 44.0]);
        assert!(!Horizon::new(eye, [left, right]).hides(&target));
        // A wall further back closes the gap: fusion across depths.
        let back = prism([-5.0, 20.0], [5.0, 22.0], 10.0);
        assert!(Horizon::new(eye, [left, right, back]).hides(&target));
    }

    #[test]
    fn across_the_wrap_of_angles() {
        // Bins wrap at ±π: a wall straight down −x.
        let eye = Vec3::new(0.0, 1.6, 0.0);
        let wall = prism([-12.0, -30.0], [-10.0, 30.0], 10.0);
        let h = Horizon::new(eye, [wall]);
        assert!(h.hides(&b([-34.0, 0.0, -2.0], [-30.0, 5.0, 2.0])));
        assert!(!h.hides(&b([-34.0, 0.0, -2.0], [-30.0, 50.0, 2.0])));
    }

    #[test]
    fn an_eye_inside_a_prism_ignores_it() {
        let eye = Vec3::new(0.0, 1.6, 0.0);
        let around = prism([-5.0, -5.0], [5.0, 5.0], 10.0);
        assert!(!Horizon::new(eye, [around]).hides(&b([20.0, 0.0, 0.0], [22.0, 1.0, 1.0])));
    }

    /// Random prisms and boxes: whenever the horizon hides a box, every sight line from
    /// the eye to a point of the box passes through a prism.
    #[test]
    fn what_it_hides_is_behind_a_prism_on_every_sight_line() {
        use crate::visibility::segment_meets_box;
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (mut hidden, mut lines) = (0, 0);
        for _ in 0..200 {
            let eye = Vec3::new(0.0, rng.gen_range(1.2..2.0), 0.0);
            let prisms: Vec<Prism> = (0..12)
                .map(|_| {
                    let c = Vec2::new(rng.gen_range(-60.0..60.0), rng.gen_range(-60.0..60.0));
                    let h = Vec2::new(rng.gen_range(1.0..15.0), rng.gen_range(1.0..15.0));
                    prism((c - h).into(), (c + h).into(), rng.gen_range(1.0..30.0))
                })
                .filter(|o| {
                    !o.contains(eye) && (plan(eye).clamp(o.min, o.max) - plan(eye)).length() > 0.5
                })
                .collect();
            let horizon = Horizon::new(eye, prisms.iter().copied());
            for _ in 0..50 {
                let c = Vec3::new(
                    rng.gen_range(-150.0..150.0),
                    0.0,
                    rng.gen_range(-150.0..150.0),
                );
                let h = Vec3::new(
                    rng.gen_range(0.5..10.0),
                    rng.gen_range(1.0..40.0),
                    rng.gen_range(0.5..10.0),
                );
                let target = b([c.x - h.x, 0.0, c.z - h.z], [c.x + h.x, h.y, c.z + h.z]);
                if !horizon.hides(&target) {
                    continue;
                }
                hidden += 1;
                for _ in 0..40 {
                    let f = Vec3::new(rng.gen(), rng.gen(), rng.gen());
                    let q = target.min + f * target.extent();
                    lines += 1;
                    assert!(
                        prisms.iter().any(|o| segment_meets_box(
                            eye,
                            q,
                            &b([o.min.x, -1.0, o.min.y], [o.max.x, o.top, o.max.y])
                        )),
                        "the sight line from {eye} to {q} meets no prism"
                    );
                }
            }
        }
        assert!(hidden > 500 && lines > 20_000, "{hidden} boxes hidden");
    }
}
