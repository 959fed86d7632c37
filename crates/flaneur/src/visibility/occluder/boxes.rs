//! The boxes inside a building's solid, in a frame where its walls run along the axes
//! (Shou 2002 §5.5.1 assumes large convex occluders).
//!
//! A building with setbacks, recessed windows and a pitched roof is not convex, so the
//! test uses convex parts of it, as paper-notes advise: the largest boxes found inside
//! the solid that stand on its footprint. Whatever lies behind such a box from a whole
//! viewcell lies behind the building too, so the PVS stays conservative.
//!
//! Choices made here:
//! - A building is often a stack of shells (a plinth, storeys as open tubes of wall, a
//!   slab between them, a roof) whose faces do not make one consistently oriented
//!   solid; what matters for occlusion is only that a sight line into the box must
//!   cross a face. So the box must lie where the faces enclose (see [`Solid`]): only
//!   outside faces bound the box, and its centre must be enclosed.
//! - Candidates stand on the ground of the object's bounds and are its footprint inset
//!   by an even margin, at eight heights (an eighth of the object's height to all of
//!   it). For each height the smallest margin is found by bisection (each step exact:
//!   no outside face may meet the box), and the candidate with the largest
//!   silhouette, (width + depth) × height, wins. Boxes lower than 2 m or narrower than
//!   1 m are not worth testing against and give none.
//! - A mesh with a hole escapes through it: its faces there are outside faces and its
//!   box, if any, stays clear of the hole's sight lines.
//! - Each candidate's sides are then pushed out one at a time as far as they stay
//!   free, so a notch or recess on one side does not cost the others.
//! - Up to two more boxes are stacked, each the best that stands on the one below (at
//!   least 1 m high): the inside of a roof, a setback tier. The other ground
//!   candidates that no taller one covers (a wide plinth under a narrow tower) follow
//!   them: they hide what their own footprints do.
//! - A footprint whose bounds' centre lies outside it (a perimeter block around its
//!   courtyard, an L, a U) gets little or nothing from boxes grown about that centre.
//!   So the footprint is sampled on a grid a metre off the ground, and from each
//!   enclosed sample that no ground box covers yet (the one with most such neighbours
//!   first) a box is grown the same way, about the sample instead of the centre: up to
//!   eight more, each its own wing of the block.
//! - Each box is shrunk by 1 cm at the end, so rounding in the tests that use it cannot
//!   let it poke out of the solid.
//!
//! [`Solid`]: super::solid::Solid

use std::cell::Cell;

use glam::{Vec2, Vec3};

use super::solid::Solid;
use crate::geom::Aabb;
use crate::visibility::intersect::triangle_meets_box;

/// Candidate heights, as eighths of the object's height.
const HEIGHTS: u32 = 8;
/// Bisection steps on the margin: 2^-14 of the half-width, well under a centimetre.
const STEPS: u32 = 14;
/// What the found box is shrunk by, in metres.
const SAFETY: f32 = 0.01;
const MIN_HEIGHT: f32 = 2.0;
/// Boxes stacked on the first (a roof's inside, a setback tier), and the least height
/// of one.
const STACKED: usize = 3;
const MIN_UPPER_HEIGHT: f32 = 1.0;
const MIN_WIDTH: f32 = 1.0;
/// The footprint's samples per side, and the most boxes grown from them.
const SAMPLES: usize = 16;
const GROWN: usize = 16;
/// The least footprint a grown box must have, in square metres.
const MIN_GROWN_AREA: f32 = 4.0;

/// Boxes inside the solid of `triangles`: the first standing on its footprint, each
/// next on the one below, then other boxes standing on the footprint that none of
/// those covers (wider and lower ones, and the wings of a block); none when there is
/// no worthwhile one (the mesh is small, flat, open, or does not stand on its bounds'
/// ground).
pub(super) fn occluder_boxes(triangles: Vec<[Vec3; 3]>) -> Vec<Aabb> {
    let mut boxes = Vec::new();
    let Some((lo, hi)) = bounds(&triangles) else {
        return boxes;
    };
    let size = hi - lo;
    if size.y < MIN_HEIGHT || size.x.min(size.z) < MIN_WIDTH {
        return boxes;
    }
    let solid = Solid::new(triangles, lo, hi);
    let outside = Outside::new(&solid);
    let free = |b: &Aabb| outside.free(b);
    let inset = |b: &Aabb| Aabb {
        min: b.min + Vec3::splat(SAFETY),
        max: b.max - Vec3::splat(SAFETY),
    };
    let mut floor = lo.y;
    let mut extra: Vec<Aabb> = Vec::new();
    while boxes.len() < STACKED {
        let min_height = if boxes.is_empty() {
            MIN_HEIGHT
        } else {
            MIN_UPPER_HEIGHT
        };
        let mut best: Option<(f32, Aabb)> = None;
        let mut ground: Vec<Aabb> = Vec::new();
        for k in 1..=HEIGHTS {
            // A hair under the level, or a roof lying on it would always meet the box.
            let height = (hi.y - floor) * k as f32 / HEIGHTS as f32 - SAFETY;
            if height < min_height {
                continue;
            }
            let Some(b) = widest_free(lo, hi, floor, height, &free) else {
                continue;
            };
            if boxes.is_empty() {
                ground.push(b);
            }
            let score = silhouette(&b);
            if best.is_none_or(|(s, _)| score > s) {
                best = Some((score, b));
            }
        }
        let Some((_, b)) = best else { break };
        if !solid.encloses(b.center()) {
            break;
        }
        floor = b.max.y;
        boxes.push(inset(&b));
        // The other boxes standing on the ground that no taller one covers (a wide
        // plinth beside a narrow tower): each hides what its own footprint does.
        for (i, g) in ground.iter().enumerate() {
            let covered = |h: &Aabb| {
                h.max.y >= g.max.y
                    && h.min.x <= g.min.x
                    && h.min.z <= g.min.z
                    && h.max.x >= g.max.x
                    && h.max.z >= g.max.z
            };
            let dominated = covered(&b)
                || ground
                    .iter()
                    .enumerate()
                    .any(|(j, h)| j != i && covered(h) && (h != g || j < i));
            if !dominated && solid.encloses(g.center()) {
                extra.push(inset(g));
            }
        }
    }
    boxes.extend(extra);
    let grown = grown_from_samples(&solid, lo, hi, &boxes, &free);
    boxes.extend(grown.iter().map(inset));
    boxes
}

/// The faces of a solid that are on the outside somewhere (see
/// [`Solid::is_outside`]): a box is free when it meets none of them.
///
/// Whether a face is on the outside costs up to 48 enclosure rays, and most faces of
/// a building never need the answer: a box's test stops at the first outside face
/// that meets it, and most faces meet none of the boxes tried. So a face is asked
/// only when it meets the box being tested, and its answer is kept for the next box.
/// Whether some outside face meets a box does not depend on which faces were asked
/// before, nor in which order, so the boxes are the ones that asking every face first
/// would give.
struct Outside<'a> {
    solid: &'a Solid,
    /// Each face's bounds, as the low x, y, z and high x, y, z of all the faces in
    /// turn: most faces are apart from a candidate box, and the bounds, compared for
    /// many faces at once, tell that before the face's separating-axis test.
    bounds: [Vec<f32>; 6],
    /// The bounds of each run of [`CHUNK`] faces, in the same layout: a face is usually
    /// beside the one before it in a mesh, so a run lies along a wall, and a box
    /// apart from the run's bounds is apart from all its faces.
    chunks: [Vec<f32>; 6],
    /// Per face: whether it is on the outside, once asked ([`UNASKED`] before).
    known: Vec<Cell<u8>>,
    /// The face that last met a box: the searches ask about boxes a little apart
    /// each time, and a face that met one likely meets the next, so it is tried
    /// first (whether any face meets a box does not depend on the order).
    last: Cell<usize>,
}

/// Faces whose bounds are compared at once, and the run that shares one bounds.
const CHUNK: usize = 64;
/// A face's answer in [`Outside::known`]: not asked yet, on the outside, or not.
const UNASKED: u8 = 0;
const OUTSIDE: u8 = 1;
const INSIDE: u8 = 2;

impl<'a> Outside<'a> {
    fn new(solid: &'a Solid) -> Outside<'a> {
        let faces = &solid.triangles;
        let bounds: [Vec<f32>; 6] = std::array::from_fn(|k| {
            faces
                .iter()
                .map(|t| {
                    let (lo, hi) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
                    if k < 3 {
                        lo[k]
                    } else {
                        hi[k - 3]
                    }
                })
                .collect()
        });
        let chunks = std::array::from_fn(|k| {
            bounds[k]
                .chunks(CHUNK)
                .map(|run| {
                    let (lo, hi) = (f32::INFINITY, f32::NEG_INFINITY);
                    if k < 3 {
                        run.iter().fold(lo, |a, &v| a.min(v))
                    } else {
                        run.iter().fold(hi, |a, &v| a.max(v))
                    }
                })
                .collect()
        });
        Outside {
            solid,
            bounds,
            chunks,
            known: vec![Cell::new(UNASKED); faces.len()],
            last: Cell::new(usize::MAX),
        }
    }

    /// Whether the bounds `i` of `bounds` (faces' or runs') meet the closed box `b`.
    #[inline(always)]
    fn near(bounds: &[Vec<f32>; 6], i: usize, b: &Aabb) -> bool {
        let [lx, ly, lz, hx, hy, hz] = bounds;
        (lx[i] <= b.max.x)
            & (ly[i] <= b.max.y)
            & (lz[i] <= b.max.z)
            & (b.min.x <= hx[i])
            & (b.min.y <= hy[i])
            & (b.min.z <= hz[i])
    }

    /// Whether face `i` is on the outside and meets the closed box `b`.
    #[inline]
    fn blocks(&self, i: usize, b: &Aabb) -> bool {
        let known = &self.known[i];
        if known.get() == INSIDE || !triangle_meets_box(&self.solid.triangles[i], b) {
            return false;
        }
        if known.get() == UNASKED {
            let outside = self.solid.is_outside(&self.solid.triangles[i]);
            known.set(if outside { OUTSIDE } else { INSIDE });
        }
        known.get() == OUTSIDE
    }

    /// Whether the closed box `b` meets none of the outside faces.
    fn free(&self, b: &Aabb) -> bool {
        let count = self.known.len();
        let last = self.last.get();
        if last < count && Self::near(&self.bounds, last, b) && self.blocks(last, b) {
            return false;
        }
        // The runs whose bounds meet the box; their faces whose bounds do, a run at a
        // time; then those faces' tests.
        for (run, start) in (0..count).step_by(CHUNK).enumerate() {
            if !Self::near(&self.chunks, run, b) {
                continue;
            }
            let end = (start + CHUNK).min(count);
            let mut near = 0u64;
            for i in start..end {
                near |= u64::from(Self::near(&self.bounds, i, b)) << (i - start);
            }
            while near != 0 {
                let i = start + near.trailing_zeros() as usize;
                near &= near - 1;
                if self.blocks(i, b) {
                    self.last.set(i);
                    return false;
                }
            }
        }
        true
    }
}

/// The bounds of `triangles`; `None` when there are none or one is not finite.
fn bounds(triangles: &[[Vec3; 3]]) -> Option<(Vec3, Vec3)> {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for v in triangles.iter().flatten() {
        if !v.is_finite() {
            return None;
        }
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    (!triangles.is_empty()).then_some((lo, hi))
}

/// What a box standing on the ground hides, roughly: its (width + depth) × height.
fn silhouette(b: &Aabb) -> f32 {
    (b.max.x - b.min.x + b.max.z - b.min.z) * (b.max.y - b.min.y)
}

/// Boxes grown about the samples of the footprint that the ground boxes among `found`
/// leave uncovered (see the module's notes).
fn grown_from_samples(
    solid: &Solid,
    lo: Vec3,
    hi: Vec3,
    found: &[Aabb],
    free: &impl Fn(&Aabb) -> bool,
) -> Vec<Aabb> {
    let y = lo.y + 1.0;
    let step = Vec2::new(hi.x - lo.x, hi.z - lo.z) / SAMPLES as f32;
    let at = |i: usize, j: usize| {
        Vec3::new(
            lo.x + (i as f32 + 0.5) * step.x,
            y,
            lo.z + (j as f32 + 0.5) * step.y,
        )
    };
    let on = |b: &Aabb, p: Vec3| {
        b.min.y <= lo.y + MIN_UPPER_HEIGHT
            && (b.min.x..=b.max.x).contains(&p.x)
            && (b.min.z..=b.max.z).contains(&p.z)
    };
    // Per sample: whether a box may still be grown about it.
    let mut open: Vec<bool> = (0..SAMPLES * SAMPLES)
        .map(|k| {
            let p = at(k % SAMPLES, k / SAMPLES);
            !found.iter().any(|b| on(b, p)) && solid.encloses(p)
        })
        .collect();
    let mut grown: Vec<Aabb> = Vec::new();
    while grown.len() < GROWN {
        // The open sample with most open neighbours: the middle of an uncovered wing.
        let neighbours = |k: usize| {
            let (i, j) = ((k % SAMPLES) as i64, (k / SAMPLES) as i64);
            let mut n = 0;
            for dj in -2..=2 {
                for di in -2..=2 {
                    let (a, b) = (i + di, j + dj);
                    let inside =
                        (0..SAMPLES as i64).contains(&a) && (0..SAMPLES as i64).contains(&b);
                    if inside && open[(b * SAMPLES as i64 + a) as usize] {
                        n += 1;
                    }
                }
            }
            n
        };
        let Some(k) = (0..open.len())
            .filter(|&k| open[k])
            .max_by_key(|&k| (neighbours(k), std::cmp::Reverse(k)))
        else {
            break;
        };
        open[k] = false;
        let seed = at(k % SAMPLES, k / SAMPLES);
        let mut best: Option<(f32, Aabb)> = None;
        for h in 1..=HEIGHTS {
            let height = (hi.y - lo.y) * h as f32 / HEIGHTS as f32 - SAFETY;
            if height < MIN_HEIGHT {
                continue;
            }
            let Some(b) = grown_free(lo, hi, seed, height, free) else {
                continue;
            };
            let score = silhouette(&b);
            if best.is_none_or(|(s, _)| score > s) {
                best = Some((score, b));
            }
        }
        let Some((_, b)) = best else { continue };
        let area = (b.max.x - b.min.x) * (b.max.z - b.min.z);
        if area < MIN_GROWN_AREA || !solid.encloses(b.center()) {
            continue;
        }
        for (m, o) in open.iter_mut().enumerate() {
            if *o && on(&b, at(m % SAMPLES, m / SAMPLES)) {
                *o = false;
            }
        }
        grown.push(b);
    }
    grown
}

/// The box from the ground up `height` grown about `seed` (plan) towards the bounds:
/// the footprint of the bounds drawn in towards a 1 m square about the seed, evenly
/// (each side by the same share of its way), as little as leaves it free, then each
/// side pushed back out on its own; `None` when even the square meets a face.
fn grown_free(
    lo: Vec3,
    hi: Vec3,
    seed: Vec3,
    height: f32,
    free: &impl Fn(&Aabb) -> bool,
) -> Option<Aabb> {
    let r = 0.5 * MIN_WIDTH;
    // Each side's way in from the bounds to the square: low x, high x, low z, high z.
    let way = [
        (seed.x - r - lo.x).max(0.0),
        (hi.x - seed.x - r).max(0.0),
        (seed.z - r - lo.z).max(0.0),
        (hi.z - seed.z - r).max(0.0),
    ];
    let floor = lo.y;
    let candidate = |t: f32| Aabb {
        min: Vec3::new(lo.x + t * way[0], floor + SAFETY, lo.z + t * way[2]),
        max: Vec3::new(hi.x - t * way[1], floor + height, hi.z - t * way[3]),
    };
    if !free(&candidate(1.0)) {
        return None;
    }
    let good = least_free(1.0, |t| free(&candidate(t)));
    let mut b = push_sides(candidate(good), lo, hi, way.map(|w| good * w), free);
    b.min.y = floor;
    Some(b)
}

/// The footprint box from `floor` up `height`, inset by the smallest even margin (to
/// a bisection's precision) that leaves it meeting no outside face, then each side
/// pushed back out on its own as far as it stays free; `None` when even the narrowest
/// worthwhile box meets one.
fn widest_free(
    lo: Vec3,
    hi: Vec3,
    floor: f32,
    height: f32,
    free: &impl Fn(&Aabb) -> bool,
) -> Option<Aabb> {
    // A floor face would always meet a box standing on it: the boxes tested stand a
    // hair above their floor.
    let candidate = |margin: f32| Aabb {
        min: Vec3::new(lo.x + margin, floor + SAFETY, lo.z + margin),
        max: Vec3::new(hi.x - margin, floor + height, hi.z - margin),
    };
    let narrowest = 0.5 * ((hi.x - lo.x).min(hi.z - lo.z) - MIN_WIDTH) - SAFETY;
    if narrowest < 0.0 || !free(&candidate(narrowest)) {
        return None;
    }
    let good = least_free(narrowest, |margin| free(&candidate(margin)));
    let mut b = push_sides(candidate(good), lo, hi, [good; 4], free);
    b.min.y = floor;
    Some(b)
}

/// `b` with each side in turn (low x, high x, low z, high z) pushed out from its
/// margin in from the bounds (`margins`, each known free) as far as it stays free: a
/// footprint with a notch or a recess on one side keeps its other sides.
fn push_sides(
    mut b: Aabb,
    lo: Vec3,
    hi: Vec3,
    margins: [f32; 4],
    free: &impl Fn(&Aabb) -> bool,
) -> Aabb {
    for (side, &margin) in margins.iter().enumerate() {
        let (axis, low) = ([0, 0, 2, 2][side], side % 2 == 0);
        let at = |b: &Aabb, margin: f32| {
            let mut c = *b;
            if low {
                c.min[axis] = lo[axis] + margin;
            } else {
                c.max[axis] = hi[axis] - margin;
            }
            c
        };
        let ok = least_free(margin, |m| free(&at(&b, m)));
        b = at(&b, ok);
    }
    b
}

/// The least inset from 0 up to `known` (itself free) at which `free_at` holds, to a
/// bisection's precision: 0 when it holds there, else a value known to be free.
fn least_free(known: f32, free_at: impl Fn(f32) -> bool) -> f32 {
    if free_at(0.0) {
        return 0.0;
    }
    // `bad` is an inset known to meet a face, `good` one known to be free.
    let (mut bad, mut good) = (0.0f32, known);
    for _ in 0..STEPS {
        let mid = 0.5 * (bad + good);
        if free_at(mid) {
            good = mid;
        } else {
            bad = mid;
        }
    }
    good
}
