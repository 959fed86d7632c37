//! The directions around a horizon's eye: pseudo-angles (cheaper than `atan2`, ordered
//! as angles are), the angular bins they fall in, and the plan geometry the horizon
//! measures with (spans of quadrilaterals, where a ray enters a rectangle).

use std::sync::OnceLock;

use glam::{Vec2, Vec3, Vec4};

use super::BINS;

pub(super) const BIN: f32 = TURN / BINS as f32;
/// A whole turn of the pseudo-angle (see [`pseudo_angle`]).
pub(super) const TURN: f32 = 4.0;
/// Angles are padded by this (in pseudo-angle units, a turn being 4) so that rounding
/// never widens what an occluder covers or narrows what a box spans.
pub(super) const PAD: f32 = 1e-5;

pub(super) fn plan(v: Vec3) -> Vec2 {
    Vec2::new(v.x, v.z)
}

pub(super) fn corners2(min: Vec2, max: Vec2) -> [Vec2; 4] {
    [min, Vec2::new(max.x, min.y), max, Vec2::new(min.x, max.y)]
}

/// A pseudo-angle of the plan direction `v` (not zero) in [0, 4): the distance walked
/// counter-clockwise from +x along the diamond |x| + |y| = 1 to where `v` meets it. It
/// orders directions as the angle does and is cheaper than `atan2`, which was the
/// largest cost of the conservative test; the bins are equal steps of it, not of the
/// angle (they are up to √2 times wider along the diagonals, which costs nothing in
/// exactness). Opposite directions are 2 apart.
pub(super) fn pseudo_angle(v: Vec2) -> f32 {
    let f = v.y / (v.x.abs() + v.y.abs());
    match (v.x >= 0.0, v.y >= 0.0) {
        (true, true) => f,
        (false, _) => 2.0 - f,
        (true, false) => 4.0 + f,
    }
}

/// The unit direction of pseudo-angle `a` (any real; taken modulo a turn).
pub(super) fn direction(a: f32) -> Vec2 {
    let a = a.rem_euclid(TURN);
    let quadrant = (a as u32).min(3);
    let f = a - quadrant as f32;
    let v = match quadrant {
        0 => Vec2::new(1.0 - f, f),
        1 => Vec2::new(-f, 1.0 - f),
        2 => Vec2::new(f - 1.0, -f),
        _ => Vec2::new(f, f - 1.0),
    };
    v.normalize()
}

/// Pseudo-angle of `v`, unwrapped about `reference` into (reference − 2, reference + 2].
pub(super) fn unwrapped(v: Vec2, reference: f32) -> f32 {
    let mut a = pseudo_angle(v);
    while a - reference > TURN / 2.0 {
        a -= TURN;
    }
    while a - reference <= -TURN / 2.0 {
        a += TURN;
    }
    a
}

/// The angular span of the convex quadrilateral `corners` seen from `eye`, which lies
/// outside it, as (low, high) in pseudo-angles with high − low < 2 (half a turn), and
/// each corner's pseudo-angle on the same unwrapped scale.
///
/// The four corners go through [`pseudo_angle`] and [`unwrapped`] at once, in the lanes
/// of one vector (the same operations, so the same bits): this runs for every group,
/// prism and box a horizon meets or is asked about, and one at a time it was the
/// largest single cost of the conservative test. The corners are not the eye, so no
/// lane divides zero by zero.
pub(super) fn span(eye: Vec2, corners: &[Vec2; 4]) -> (f32, f32, [f32; 4]) {
    let centre = 0.25 * (corners[0] + corners[1] + corners[2] + corners[3]) - eye;
    let reference = Vec4::splat(pseudo_angle(centre));
    let x = Vec4::from(corners.map(|c| c.x)) - eye.x;
    let y = Vec4::from(corners.map(|c| c.y)) - eye.y;
    let f = y / (x.abs() + y.abs());
    let zero = Vec4::ZERO;
    let a = Vec4::select(
        x.cmplt(zero),
        2.0 - f,
        Vec4::select(y.cmplt(zero), 4.0 + f, f),
    );
    // Both pseudo-angles lie in [0, 4): one turn added or taken away at most.
    let a = Vec4::select((a - reference).cmpgt(Vec4::splat(TURN / 2.0)), a - TURN, a);
    let a = Vec4::select((a - reference).cmple(Vec4::splat(-TURN / 2.0)), a + TURN, a);
    let angles = a.to_array();
    let lo = angles.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = angles.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    (lo, hi, angles)
}

/// The unit direction of each bin edge, `BINS + 1` of them from +x counter-clockwise.
pub(super) fn edges() -> &'static [Vec2] {
    static EDGES: OnceLock<Vec<Vec2>> = OnceLock::new();
    EDGES.get_or_init(|| (0..=BINS).map(|k| direction(bin_start(k as i64))).collect())
}

/// The plan distance at which the ray from `eye` along `dir` enters the rectangle.
pub(super) fn entry(eye: Vec2, dir: Vec2, min: Vec2, max: Vec2) -> Option<f32> {
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

/// `x.floor() as i64` for the bins' pseudo-angles (finite, a few turns at most)
/// without a call to the C library's `floorf`, which the baseline x86-64 target makes
/// of `floor` and which was a visible share of the test.
pub(super) fn floor(x: f32) -> i64 {
    let t = x as i64;
    t - i64::from(t as f32 > x)
}

pub(super) fn bin_start(k: i64) -> f32 {
    k as f32 * BIN
}

pub(super) fn bin_of(k: i64) -> usize {
    k.rem_euclid(BINS as i64) as usize
}
