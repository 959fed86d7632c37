//! The occlusion horizon of one viewpoint over ground-standing occluders (a 2.5D cull
//! map, after Wonka, Wimmer and Schmalstieg 2000): the directions around the eye in
//! angular bins, and in each bin, by distance, how steeply the occluders met so far
//! rise above the eye. A box is hidden when, in every bin it spans, an occluder
//! entered before the box's nearest point rises more steeply than the box's top seen
//! from there.
//!
//! Why it is exact (never hides a visible point): a prism stands on the ground with
//! footprint F (a rectangle, its sides at any angle: buildings follow their streets,
//! not the axes) and top h. A sight line from the eye p (height y) to a point q (plan
//! distance d, height ≤ H) that enters F at plan distance e < d is, there, at height
//! y + (e/d)(q_y − y) ≤ y + (e/d)·max(H − y, 0). If that is at most h, the line is in
//! the prism, and q is hidden. In a bin the occluder is counted only where it covers
//! the bin's whole angle, with e the largest entry distance over the bin (reached at a
//! bin edge or a corner, the front of a convex footprint being a chain of segments),
//! and a box is tested, bin by bin, with its least plan distance within the bin and its
//! top: each bound makes the test stricter. (Its least distance over the whole box in
//! every bin, as a first version took, leaves a long box whose near end shows.) Many
//! occluders fuse: each bin may be closed by a different one.
//!
//! Two savings leave what it says unchanged: the prisms come in groups ([`Group`]), and
//! a group whose bounds are behind the horizon built so far in every bin they span is
//! passed over whole; and a horizon may be built for some boxes only ([`Wanted`]),
//! leaving out the bins they do not touch and what lies beyond them, and stopping once
//! the occluders entered so far hide every one of them (more occluders only hide more);
//! on the way, once half of the boxes still pending are hidden, the bins and distances
//! it enters are narrowed to those of the rest (an entry only a hidden box could reach
//! changes no answer).
//! Such a build passes over a prism or group that touches none of those bins in O(1) (a
//! count of the wanted bins before each). Nor does a build keep an entry that its
//! bin's steepest so far dominates (nearer and no less steep): it is in no front.

use glam::{Vec2, Vec3};
use std::ops::Range;

use crate::geom::Aabb;

mod angles;

use angles::*;

/// Angular bins around the eye.
pub const BINS: usize = 1024;

/// An occluder standing on the ground: a rectangular footprint in (x, z), turned
/// about the vertical by any angle, and the height of its top. Everything of it from
/// the ground up to `top` is inside a solid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prism {
    /// The footprint's centre.
    pub centre: Vec2,
    /// The unit direction of the footprint's first pair of sides; the second pair runs
    /// across it, along `axis.perp()`.
    pub axis: Vec2,
    /// Half the footprint's sides: along `axis`, then across it.
    pub half: Vec2,
    pub top: f32,
}

impl Prism {
    /// The prism whose footprint is the plan rectangle `min`..`max`, sides along x and z.
    pub fn aligned(min: Vec2, max: Vec2, top: f32) -> Prism {
        Prism {
            centre: 0.5 * (min + max),
            axis: Vec2::X,
            half: 0.5 * (max - min),
            top,
        }
    }

    /// `v` (plan) in the footprint's own frame: along `axis` and across it, from the
    /// centre.
    fn local(&self, v: Vec2) -> Vec2 {
        let d = v - self.centre;
        Vec2::new(d.dot(self.axis), d.dot(self.axis.perp()))
    }

    /// A plan direction in the footprint's own frame.
    fn local_direction(&self, v: Vec2) -> Vec2 {
        Vec2::new(v.dot(self.axis), v.dot(self.axis.perp()))
    }

    /// The footprint's corners, in turn around it.
    pub fn corners(&self) -> [Vec2; 4] {
        let (a, b) = (self.axis * self.half.x, self.axis.perp() * self.half.y);
        let c = self.centre;
        [c - a - b, c + a - b, c + a + b, c - a + b]
    }

    /// The plan box around the footprint.
    pub fn bounds(&self) -> (Vec2, Vec2) {
        let reach = self.axis.abs() * self.half.x + self.axis.perp().abs() * self.half.y;
        (self.centre - reach, self.centre + reach)
    }

    /// The prism with its footprint shrunk by `e` on every side, its top kept; `None`
    /// when nothing is left of its footprint.
    pub fn shrunk(&self, e: f32) -> Option<Prism> {
        let half = self.half - e;
        (half.x > 0.0 && half.y > 0.0).then_some(Prism { half, ..*self })
    }

    /// Whether the point `p` (x, y, z) is inside the prism (standing on the ground).
    pub fn contains(&self, p: Vec3) -> bool {
        let l = self.local(plan(p)).abs();
        l.x < self.half.x && l.y < self.half.y && p.y < self.top
    }

    /// Whether the plan point `p` is on the footprint, its edge included.
    fn covers(&self, p: Vec2) -> bool {
        let l = self.local(p).abs();
        l.x <= self.half.x && l.y <= self.half.y
    }

    /// The plan distance from `p` to the footprint.
    fn distance(&self, p: Vec2) -> f32 {
        let l = self.local(p);
        (l.clamp(-self.half, self.half) - l).length()
    }

    /// The plan distance at which the ray from `eye` along `dir` enters the footprint.
    #[cfg(test)]
    fn entry(&self, eye: Vec2, dir: Vec2) -> Option<f32> {
        entry(
            self.local(eye),
            self.local_direction(dir),
            -self.half,
            self.half,
        )
    }
}

/// How a box lies from a plan point, as [`Horizon::hides`] and [`Wanted::add`] both see
/// it: its nearest point and distance, its corners and their pseudo-angles, and the
/// bins it may touch, `first..=last` (unwrapped).
struct BoxView {
    nearest: Vec2,
    d: f32,
    corners: [Vec2; 4],
    angles: [f32; 4],
    reference: f32,
    first: i64,
    last: i64,
}

impl BoxView {
    /// `None` when no horizon of `p` can hide the box: `p` is over it in plan, or it
    /// spans every bin.
    fn of(p: Vec2, min: Vec2, max: Vec2) -> Option<BoxView> {
        let nearest = p.clamp(min, max);
        let d = (nearest - p).length();
        if d <= 0.0 {
            return None;
        }
        let corners = corners2(min, max);
        let (lo, hi, angles) = span(p, &corners);
        let first = floor((lo - PAD) / BIN);
        let last = floor((hi + PAD) / BIN);
        if last - first >= BINS as i64 {
            return None;
        }
        Some(BoxView {
            nearest,
            d,
            corners,
            angles,
            reference: 0.5 * (lo + hi),
            first,
            last,
        })
    }
}

/// The boxes a horizon will be asked about, as the bins they touch and how far out in
/// each: a horizon built for them ([`Horizon::rebuild`]) leaves out every occluder entry
/// that no question about them can reach (in a bin none of them touches, or further
/// than the furthest of them there), and answers for them exactly as the whole horizon
/// would.
pub struct Wanted {
    eye: Vec2,
    /// The eye's height.
    height: f32,
    /// Each box added, as bins `first..=last` (unwrapped), its least plan distance and
    /// the rise of its top over the eye per metre there: what a horizon whose steepest
    /// entries block it in each of those bins hides (see [`Horizon::rebuild`]).
    asked: Vec<Ask>,
    /// How each box added lies from the eye, for [`Horizon::hides_wanted`].
    views: Vec<BoxView>,
    /// Per bin, a plan distance beyond every point of every box added that touches it
    /// (0 for none).
    far: Vec<f32>,
    /// The largest of `far`.
    reach: f32,
}

impl Wanted {
    /// Nothing wanted yet, from `eye`.
    pub fn new(eye: Vec3) -> Wanted {
        Wanted {
            eye: plan(eye),
            height: eye.y,
            asked: Vec::new(),
            views: Vec::new(),
            far: vec![0.0; BINS],
            reach: 0.0,
        }
    }

    /// Nothing wanted, from `eye`, keeping the memory.
    pub fn reset(&mut self, eye: Vec3) {
        self.eye = plan(eye);
        self.height = eye.y;
        self.asked.clear();
        self.views.clear();
        self.far.fill(0.0);
        self.reach = 0.0;
    }

    /// Asks for `b`; false (and nothing asked) when no horizon of the eye can hide it.
    pub fn add(&mut self, b: &Aabb) -> bool {
        let p = self.eye;
        let Some(v) = BoxView::of(p, plan(b.min), plan(b.max)) else {
            return false;
        };
        // The furthest point of a rectangle is a corner; a margin over rounding, so
        // that every distance `hides` may ask about in a bin is below it.
        let far = v
            .corners
            .iter()
            .map(|c| (*c - p).length())
            .fold(0.0f32, f32::max)
            * (1.0 + 1e-4)
            + 1e-3;
        for k in v.first..=v.last {
            let f = &mut self.far[bin_of(k)];
            *f = f.max(far);
        }
        self.reach = self.reach.max(far);
        let rise = (b.max.y - self.height).max(0.0);
        self.asked.push(Ask {
            first: v.first,
            last: v.last,
            d: v.d,
            slope: rise / v.d,
            far,
        });
        self.views.push(v);
        true
    }

    /// A plan distance beyond every box added: occluders further from the eye cannot
    /// hide any of them.
    pub fn reach(&self) -> f32 {
        self.reach
    }
}

/// A box asked about, as a build for it sees it: bins `first..=last` (unwrapped), its
/// least plan distance `d`, the rise of its top over the eye per metre there, and a
/// plan distance beyond all of it.
#[derive(Clone, Copy, Debug)]
struct Ask {
    first: i64,
    last: i64,
    d: f32,
    slope: f32,
    far: f32,
}

/// Bounds around a group of prisms: a plan box around their footprints, and their
/// highest top.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Group {
    pub lo: Vec2,
    pub hi: Vec2,
    pub top: f32,
}

impl Group {
    /// The bounds of `prisms`; `None` for none.
    pub fn around<'a>(prisms: impl IntoIterator<Item = &'a Prism>) -> Option<Group> {
        prisms.into_iter().fold(None, |g, o| {
            let (lo, hi) = o.bounds();
            Some(match g {
                None => Group { lo, hi, top: o.top },
                Some(g) => Group {
                    lo: g.lo.min(lo),
                    hi: g.hi.max(hi),
                    top: g.top.max(o.top),
                },
            })
        })
    }
}

/// One viewpoint's horizon.
pub struct Horizon {
    eye: Vec3,
    /// `fronts[starts[b]..starts[b + 1]]`: bin b's (entry distance, steepest rise so
    /// far), distances ascending and rises strictly increasing.
    starts: Vec<u32>,
    fronts: Vec<(f32, f32)>,
    /// Working memory of a build, kept for the next; its per-bin steepest entries
    /// also speed [`Horizon::hides`].
    scratch: Scratch,
}

#[derive(Default)]
struct Scratch {
    steepest: Vec<(f32, f32)>,
    entries: Vec<(u32, f32, f32)>,
    first: Vec<u32>,
    fill: Vec<u32>,
    by_bin: Vec<(f32, f32)>,
    /// Over two turns of bins, how many wanted bins lie before each (empty when every
    /// bin is wanted).
    wanted_before: Vec<u32>,
    pending: Vec<Ask>,
    /// The bins' `far` (see [`Wanted`]) over the boxes still pending.
    far: Vec<f32>,
}

impl Horizon {
    /// A horizon that hides nothing, to be rebuilt ([`Horizon::rebuild`]).
    pub fn empty() -> Horizon {
        Horizon {
            eye: Vec3::ZERO,
            starts: vec![0; BINS + 1],
            fronts: Vec::new(),
            scratch: Scratch::default(),
        }
    }

    /// The horizon of `eye` over `prisms`, none of which may contain the eye's plan
    /// position (those are skipped).
    #[cfg(test)]
    pub fn new(eye: Vec3, prisms: impl IntoIterator<Item = Prism>) -> Horizon {
        let mut h = Horizon::empty();
        let mut sorted: Vec<Prism> = prisms.into_iter().collect();
        sorted.sort_by(|a, b| a.distance(plan(eye)).total_cmp(&b.distance(plan(eye))));
        h.build(eye, [(None, sorted)], true, None);
        h
    }

    /// This horizon made that of `eye` over the prisms of `groups`, reusing its memory.
    /// Each group comes with bounds around all its prisms ([`Group`]); a group wholly
    /// behind the horizon built so far is skipped. The groups are taken in the order
    /// given, which should be about nearest first (by distance from a point near the
    /// eye): the order only decides how much pruning saves, never what the horizon
    /// hides, so the samples of one cell share one sort. With `wanted` (made from the
    /// same eye), it answers only for the boxes added to it, as the whole horizon
    /// would; what it says of any other box means nothing. Such a build stops early
    /// once the steepest entry so far of every bin of every box added is nearer than the
    /// box and rises above its top: each is then hidden, by these entries as by all.
    pub fn rebuild<P: IntoIterator<Item = Prism>>(
        &mut self,
        eye: Vec3,
        groups: impl IntoIterator<Item = (Group, P)>,
        wanted: Option<&Wanted>,
    ) {
        debug_assert!(wanted.is_none_or(|w| w.eye == plan(eye)));
        self.build(
            eye,
            groups.into_iter().map(|(g, p)| (Some(g), p)),
            true,
            wanted,
        );
    }

    /// `prune`: skip, bin by bin, what a nearer and steeper occluder already dominates.
    /// In a street most of the thousands of prisms within reach lie behind the street's
    /// own walls, so taking the prisms nearest first and skipping those bins saves most
    /// of the entry computations. It never changes what the horizon hides (a test
    /// builds both ways): an entry (e, s) with e ≥ e′ and s ≤ s′ of one already in its
    /// bin is never the steepest entered before any distance. A group whose bounds are
    /// so dominated in every bin they span is skipped whole: each of its prisms lies
    /// within those bins, no nearer and no steeper. `wanted`: skip too, bin by bin, what
    /// lies beyond every wanted box in that bin; `hides` only looks at entries nearer
    /// than the box it is asked about.
    fn build<P: IntoIterator<Item = Prism>>(
        &mut self,
        eye: Vec3,
        groups: impl IntoIterator<Item = (Option<Group>, P)>,
        prune: bool,
        wanted: Option<&Wanted>,
    ) {
        let p = plan(eye);
        let edges = edges();
        let mut reach = wanted.map_or(f32::INFINITY, |w| w.reach);
        let Scratch {
            steepest,
            entries,
            first,
            fill,
            by_bin,
            wanted_before,
            pending,
            far,
        } = &mut self.scratch;
        // Per bin, the steepest entry so far and its distance.
        steepest.clear();
        steepest.resize(BINS, (f32::INFINITY, f32::NEG_INFINITY));
        entries.clear();
        // Beyond `far[b]`, in bin b, no entry is ever looked at.
        far.clear();
        match wanted {
            Some(w) => far.extend_from_slice(&w.far),
            None => far.resize(BINS, f32::INFINITY),
        }
        // Whether no entry of `least` or further, `most` or less steep, counts in bin b.
        let dominated = |steepest: &[(f32, f32)], far: &[f32], b: usize, least: f32, most: f32| {
            let (e, s) = steepest[b];
            far[b] <= least || (prune && e <= least && s >= most)
        };
        // The same over the bins `first..=last` (unwrapped, at most a turn), a wanted
        // bin among them found first in O(1): a horizon built for a few boxes is asked
        // about a few bins, and most prisms and groups touch none of them.
        let count_wanted = |wanted_before: &mut Vec<u32>, far: &[f32]| {
            wanted_before.clear();
            wanted_before.push(0);
            for k in 0..2 * BINS {
                let n = wanted_before[k] + u32::from(far[k % BINS] > 0.0);
                wanted_before.push(n);
            }
        };
        wanted_before.clear();
        if wanted.is_some() {
            count_wanted(wanted_before, far);
        }
        let all_dominated = |steepest: &[(f32, f32)],
                             far: &[f32],
                             wanted_before: &[u32],
                             first: i64,
                             last: i64,
                             least: f32,
                             most: f32| {
            let (f, n) = (bin_of(first), (last - first + 1) as usize);
            if !wanted_before.is_empty() && wanted_before[f + n] == wanted_before[f] {
                return true;
            }
            let run = |r: Range<usize>| {
                steepest[r.clone()]
                    .iter()
                    .zip(&far[r])
                    .all(|(&(e, s), &f)| f <= least || (prune && e <= least && s >= most))
            };
            run(f..(f + n).min(BINS)) && run(0..(f + n).saturating_sub(BINS))
        };
        // The boxes wanted that the entries so far may not hide yet, looked at again
        // after every `CHECK` groups: once the steepest entry of each of their bins is
        // nearer than the box and rises above its top, every one of them is hidden
        // (the front keeps that entry or a nearer, steeper one), and the build stops.
        // Until then, once they are half as many as when the bins were last counted,
        // the bins and distances wanted are those of the boxes still pending only: an
        // entry that only a hidden box could ask about changes no answer.
        const CHECK: usize = 16;
        pending.clear();
        if let Some(w) = wanted {
            pending.extend_from_slice(&w.asked);
        }
        let mut counted = pending.len();
        for (n, (group, prisms)) in groups.into_iter().enumerate() {
            if wanted.is_some() && n % CHECK == CHECK - 1 {
                pending.retain(|a| {
                    !(a.first..=a.last).all(|k| {
                        let (e, s) = steepest[bin_of(k)];
                        e < a.d && s >= a.slope
                    })
                });
                if pending.is_empty() {
                    break;
                }
                if 2 * pending.len() <= counted {
                    counted = pending.len();
                    far.fill(0.0);
                    reach = 0.0;
                    for a in pending.iter() {
                        for k in a.first..=a.last {
                            let f = &mut far[bin_of(k)];
                            *f = f.max(a.far);
                        }
                        reach = reach.max(a.far);
                    }
                    count_wanted(wanted_before, far);
                }
            }
            if let Some(g) = group {
                let rise = g.top - eye.y;
                if rise <= 0.0 {
                    continue;
                }
                if (p.clamp(g.lo, g.hi) - p).length() >= reach {
                    continue;
                }
                if let Some(v) = BoxView::of(p, g.lo, g.hi) {
                    let (least, most) = (v.d, rise / v.d);
                    if least >= reach
                        || all_dominated(steepest, far, wanted_before, v.first, v.last, least, most)
                    {
                        continue;
                    }
                }
            }
            for o in prisms {
                if !(o.top > eye.y) || o.covers(p) {
                    continue;
                }
                let nearest = o.distance(p);
                if !(nearest < reach) {
                    continue;
                }
                let rise = o.top - eye.y;
                // No entry of this prism is nearer or steeper than this.
                let (least, most) = (nearest, rise / nearest);
                let corners = o.corners();
                let (lo, hi, angles) = span(p, &corners);
                let first = -floor(-(lo + PAD) / BIN);
                let last = floor((hi - PAD) / BIN) - 1;
                if first > last {
                    continue;
                }
                if all_dominated(steepest, far, wanted_before, first, last, least, most) {
                    continue;
                }
                // The eye in the footprint's frame once per prism; per bin edge only the
                // edge's direction is turned into it.
                let local_eye = o.local(p);
                let at_edge = |k: i64| {
                    entry(
                        local_eye,
                        o.local_direction(edges[bin_of(k)]),
                        -o.half,
                        o.half,
                    )
                };
                // Entry distances at the covered bins' edges, each edge shared by two
                // bins.
                let mut before: Option<(i64, Option<f32>)> = None;
                for k in first..=last {
                    let b = bin_of(k);
                    if dominated(steepest, far, b, least, most) {
                        continue;
                    }
                    let e0 = match before {
                        Some((edge, e)) if edge == k => e,
                        _ => at_edge(k),
                    };
                    let e1 = at_edge(k + 1);
                    before = Some((k + 1, e1));
                    let (Some(e0), Some(e1)) = (e0, e1) else {
                        continue;
                    };
                    let (a0, a1) = (bin_start(k), bin_start(k + 1));
                    let mut e = e0.max(e1);
                    for (c, &a) in corners.iter().zip(&angles) {
                        if a >= a0 && a <= a1 {
                            e = e.max((*c - p).length());
                        }
                    }
                    if e > 0.0 && e < far[b] {
                        let s = rise / e;
                        // An entry the bin's steepest so far dominates (nearer and no
                        // less steep) is never in its front.
                        let (se, ss) = steepest[b];
                        if prune && se <= e && ss >= s {
                            continue;
                        }
                        entries.push((b as u32, e, s));
                        if s > ss {
                            steepest[b] = (e, s);
                        }
                    }
                }
            }
        }
        // Bucket by bin (a counting sort), then order each bin by distance.
        first.clear();
        first.resize(BINS + 1, 0);
        for e in entries.iter() {
            first[e.0 as usize + 1] += 1;
        }
        for b in 0..BINS {
            first[b + 1] += first[b];
        }
        fill.clear();
        fill.extend_from_slice(first);
        by_bin.clear();
        by_bin.resize(entries.len(), (0.0, 0.0));
        for &(b, e, rise) in entries.iter() {
            by_bin[fill[b as usize] as usize] = (e, rise);
            fill[b as usize] += 1;
        }
        self.eye = eye;
        self.starts.clear();
        self.fronts.clear();
        for b in 0..BINS {
            self.starts.push(self.fronts.len() as u32);
            let bin = &mut by_bin[first[b] as usize..first[b + 1] as usize];
            // Entry distances are positive and finite: their bits order as they do.
            bin.sort_unstable_by_key(|x| x.0.to_bits());
            let mut best = f32::NEG_INFINITY;
            for &(e, rise) in bin.iter() {
                if rise > best {
                    best = rise;
                    self.fronts.push((e, rise));
                }
            }
        }
        self.starts.push(self.fronts.len() as u32);
    }

    /// Whether every point of `b` is hidden from the eye.
    pub fn hides(&self, b: &Aabb) -> bool {
        BoxView::of(plan(self.eye), plan(b.min), plan(b.max))
            .is_some_and(|v| self.hides_view(b, &v))
    }

    /// [`Horizon::hides`] for `b`, the `k`th box `wanted` took ([`Wanted::add`] true),
    /// `wanted` made from this horizon's eye: what the box's place from the eye took to
    /// work out is not worked out again.
    pub fn hides_wanted(&self, wanted: &Wanted, k: usize, b: &Aabb) -> bool {
        debug_assert!(wanted.eye == plan(self.eye));
        self.hides_view(b, &wanted.views[k])
    }

    /// Whether every point of `b`, which lies from the eye as `v` says, is hidden.
    fn hides_view(&self, b: &Aabb, v: &BoxView) -> bool {
        let p = plan(self.eye);
        let (min, max) = (plan(b.min), plan(b.max));
        let (nearest, d) = (v.nearest, v.d);
        let rise = (b.max.y - self.eye.y).max(0.0);
        let slope = rise / d;
        let edges = edges();
        // Each bin's steepest entry, kept from the build: it is in the front, or a
        // nearer entry no less steep is, so it blocks the box at its nearest point
        // without a search of the front when it is nearer and steep enough.
        let steepest = &self.scratch.steepest;
        let quick = |&(e, s): &(f32, f32)| e < d && s >= slope;
        // Where the box's nearest point lies, worked out when a bin first needs it.
        let mut near_angle = None;
        // A bin its steepest entry does not block on its own.
        let mut slow = |k: i64| {
            let bin = bin_of(k);
            let front = &self.fronts[self.starts[bin] as usize..self.starts[bin + 1] as usize];
            // The steepest occluder entered before distance `d` rises above `rise / d`.
            let blocked = |d: f32| {
                let before = front.partition_point(|&(e, _)| e < d);
                before > 0 && front[before - 1].1 >= rise / d
            };
            let before = front.partition_point(|&(e, _)| e < d);
            if before > 0 && front[before - 1].1 >= slope {
                return true;
            }
            // Within this bin the box may lie further than its nearest point: its least
            // distance over the bin's wedge is at its nearest point, when that is in the
            // wedge, else where a side of the wedge enters it (the least of a convex
            // function over a convex set), or at a corner in the wedge (taken too, so
            // that a side grazing a corner loses nothing to rounding).
            let (a0, a1) = (bin_start(k) - PAD, bin_start(k + 1) + PAD);
            let inside = |a: f32| a >= a0 && a <= a1;
            if inside(*near_angle.get_or_insert_with(|| unwrapped(nearest - p, v.reference))) {
                return false;
            }
            let mut least = f32::INFINITY;
            for edge in [k, k + 1] {
                if let Some(e) = entry(p, edges[bin_of(edge)], min, max) {
                    least = least.min(e);
                }
            }
            for (c, &a) in v.corners.iter().zip(&v.angles) {
                if inside(a) {
                    least = least.min((*c - p).length());
                }
            }
            // A hair nearer, for rounding; never nearer than the nearest point.
            let least = (least * (1.0 - 1e-5)).max(d);
            least.is_finite() && least > d && blocked(least)
        };
        if steepest.len() != BINS {
            return (v.first..=v.last).all(slow);
        }
        // The bins as at most two runs of the array (the span may wrap past the last
        // bin), each walked in a tight loop, the search only where the quick test fails.
        let (f, n) = (bin_of(v.first), (v.last - v.first + 1) as usize);
        let split = (f + n).min(BINS);
        let mut k = v.first;
        steepest[f..split]
            .iter()
            .chain(&steepest[..f + n - split])
            .all(|st| {
                let here = k;
                k += 1;
                quick(st) || slow(here)
            })
    }
}

#[cfg(test)]
mod tests;
