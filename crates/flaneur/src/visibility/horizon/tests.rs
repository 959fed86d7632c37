use super::*;

fn prism(min: [f32; 2], max: [f32; 2], top: f32) -> Prism {
    Prism::aligned(Vec2::from(min), Vec2::from(max), top)
}

fn b(min: [f32; 3], max: [f32; 3]) -> Aabb {
    Aabb::new(min, max).unwrap()
}

/// A box standing on the ground: centre within `spread` of the origin, half-sides
/// of 0.5 m to `half`, top 1 m to `height`.
fn random_box(rng: &mut impl rand::Rng, spread: f32, half: f32, height: f32) -> Aabb {
    let c = Vec2::new(
        rng.gen_range(-spread..spread),
        rng.gen_range(-spread..spread),
    );
    let h = Vec2::new(rng.gen_range(0.5..half), rng.gen_range(0.5..half));
    let top = rng.gen_range(1.0..height);
    b([c.x - h.x, 0.0, c.y - h.y], [c.x + h.x, top, c.y + h.y])
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
fn a_turned_wall_hides_what_is_low_behind_it() {
    let eye = Vec3::new(0.0, 1.6, 0.0);
    let mut wall = prism([-30.0, 19.0], [30.0, 21.0], 10.0);
    wall.axis = Vec2::from_angle(0.4);
    let h = Horizon::new(eye, [wall]);
    // Straight behind its middle, and behind it off to one side.
    assert!(h.hides(&b([-2.0, 0.0, 40.0], [2.0, 5.0, 44.0])));
    assert!(h.hides(&b([18.0, 0.0, 30.0], [20.0, 5.0, 32.0])));
    // Behind where the unturned wall would stand, but in front of the turned one:
    // at x = 22 its line is at z = 20 + 22 tan 0.4 ≈ 29.3.
    assert!(!h.hides(&b([20.0, 0.0, 22.0], [24.0, 5.0, 26.0])));
    let unturned = Horizon::new(eye, [prism([-30.0, 19.0], [30.0, 21.0], 10.0)]);
    assert!(unturned.hides(&b([20.0, 0.0, 22.0], [24.0, 5.0, 26.0])));
    assert!(!h.hides(&b([-2.0, 0.0, 40.0], [2.0, 40.0, 44.0])));
}

#[test]
fn a_turned_footprint_keeps_its_shape() {
    let mut o = prism([-4.0, -1.0], [4.0, 1.0], 10.0);
    o.axis = Vec2::from_angle(std::f32::consts::FRAC_PI_2);
    // Now 2 m wide in x and 8 m deep in z.
    let (lo, hi) = o.bounds();
    assert!((lo - Vec2::new(-1.0, -4.0)).length() < 1e-5, "{lo}");
    assert!((hi - Vec2::new(1.0, 4.0)).length() < 1e-5, "{hi}");
    assert!(o.contains(Vec3::new(0.5, 1.0, 3.5)));
    assert!(!o.contains(Vec3::new(3.5, 1.0, 0.5)));
    assert!((o.distance(Vec2::new(5.0, 0.0)) - 4.0).abs() < 1e-5);
    let s = o.shrunk(0.5).unwrap();
    assert_eq!((s.half, s.top), (Vec2::new(3.5, 0.5), 10.0));
    assert!(o.shrunk(1.0).is_none());
    let e = o.entry(Vec2::new(-10.0, 0.0), Vec2::X).unwrap();
    assert!((e - 9.0).abs() < 1e-5, "{e}");
}

/// A long low box close behind a long wall, seen end on: its nearest point is
/// straight ahead, where it would show over the wall at its full height, but in
/// the bins towards its far end it lies further, where the wall hides it.
#[test]
fn a_box_is_tested_bin_by_bin_at_its_distance_there() {
    let eye = Vec3::new(0.0, 1.6, 0.0);
    let wall = prism([-30.0, 10.0], [80.0, 12.0], 10.0);
    let h = Horizon::new(eye, [wall]);
    // Nearest at 13 m: it needs 9.4 / 13 = 0.72; the wall rises 8.4 / 10 there.
    assert!(h.hides(&b([0.0, 0.0, 13.0], [40.0, 11.0, 15.0])));
    // Towards (40, 13) the wall is entered at 32 m and rises 0.26; the box, at
    // its nearest point, would need 0.72 there.
    assert!(!h.hides(&b([-1.0, 0.0, 13.0], [40.0, 14.0, 15.0])));
    // Past the wall's end.
    assert!(!h.hides(&b([0.0, 0.0, 13.0], [150.0, 11.0, 15.0])));
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
fn pseudo_angles_order_directions_as_angles_do() {
    let mut last = -1.0;
    for k in 0..4000 {
        let t = k as f32 / 4000.0 * std::f32::consts::TAU;
        let a = pseudo_angle(Vec2::new(t.cos(), t.sin()));
        assert!(
            (0.0..=TURN).contains(&a) && a >= last,
            "{t}: {a} after {last}"
        );
        last = a;
        let back = pseudo_angle(direction(a));
        assert!(
            (back - a).abs() < 1e-5 || (back - a).abs() > TURN - 1e-5,
            "{a}: {back}"
        );
        assert!((direction(a).length() - 1.0).abs() < 1e-6);
    }
    assert_eq!(pseudo_angle(Vec2::new(-1.0, 0.0)), 2.0);
    assert_eq!(pseudo_angle(Vec2::new(0.0, -3.0)), 3.0);
}

#[test]
fn across_the_wrap_of_angles() {
    // Bins wrap at +x: a wall straight down +x, and for good measure one down −x.
    let eye = Vec3::new(0.0, 1.6, 0.0);
    for x in [10.0, -12.0] {
        let wall = prism([x, -30.0], [x + 2.0, 30.0], 10.0);
        let h = Horizon::new(eye, [wall]);
        let far = 3.0 * x;
        let (lo, hi) = (
            far.min(far + 4.0 * x.signum()),
            far.max(far + 4.0 * x.signum()),
        );
        assert!(h.hides(&b([lo, 0.0, -2.0], [hi, 5.0, 2.0])));
        assert!(!h.hides(&b([lo, 0.0, -2.0], [hi, 50.0, 2.0])));
    }
}

#[test]
fn an_eye_inside_a_prism_ignores_it() {
    let eye = Vec3::new(0.0, 1.6, 0.0);
    let around = prism([-5.0, -5.0], [5.0, 5.0], 10.0);
    assert!(!Horizon::new(eye, [around]).hides(&b([20.0, 0.0, 0.0], [22.0, 1.0, 1.0])));
}

/// A prism standing within `spread` of the origin, half-sides `half` at most, top
/// `top`; turned by a random angle when `turned`.
fn random_prism(
    rng: &mut impl rand::Rng,
    spread: f32,
    half: (f32, f32),
    top: (f32, f32),
    turned: bool,
) -> Prism {
    let c = Vec2::new(
        rng.gen_range(-spread..spread),
        rng.gen_range(-spread..spread),
    );
    let h = Vec2::new(rng.gen_range(half.0..half.1), rng.gen_range(half.0..half.1));
    let mut o = prism((c - h).into(), (c + h).into(), rng.gen_range(top.0..top.1));
    if turned {
        o.axis = Vec2::from_angle(rng.gen_range(0.0..std::f32::consts::TAU));
    }
    o
}

/// The random scenes of the tests below: `count` prisms within `spread` of the origin
/// (see [`random_prism`]), then an eye at a walker's height, within `eye_spread` of the
/// origin in plan (at it for 0).
fn random_scene(
    rng: &mut impl rand::Rng,
    count: usize,
    spread: f32,
    half: (f32, f32),
    top: (f32, f32),
    turned: bool,
    eye_spread: f32,
) -> (Vec3, Vec<Prism>) {
    let prisms = (0..count)
        .map(|_| random_prism(rng, spread, half, top, turned))
        .collect();
    let mut across = || {
        if eye_spread > 0.0 {
            rng.gen_range(-eye_spread..eye_spread)
        } else {
            0.0
        }
    };
    let (x, z) = (across(), across());
    (Vec3::new(x, rng.gen_range(1.2..2.0), z), prisms)
}

fn built(eye: Vec3, prisms: &[Prism], prune: bool, sort: bool, wanted: Option<&Wanted>) -> Horizon {
    let mut h = Horizon::empty();
    let mut given = prisms.to_vec();
    if sort {
        given.sort_by(|a, b| a.distance(plan(eye)).total_cmp(&b.distance(plan(eye))));
    }
    h.build(eye, [(None, given)], prune, wanted);
    h
}

/// `prisms` in groups by the square of side `tile` their centres are in, nearest
/// `eye` first.
fn tiled(prisms: &[Prism], eye: Vec3, tile: f32) -> Vec<(Group, Vec<Prism>)> {
    let mut by_tile: Vec<((i32, i32), Vec<Prism>)> = Vec::new();
    for o in prisms {
        let t = (o.centre / tile).floor();
        let key = (t.x as i32, t.y as i32);
        match by_tile.iter_mut().find(|(k, _)| *k == key) {
            Some((_, v)) => v.push(*o),
            None => by_tile.push((key, vec![*o])),
        }
    }
    let mut groups: Vec<(Group, Vec<Prism>)> = by_tile
        .into_iter()
        .map(|(_, v)| (Group::around(&v).unwrap(), v))
        .collect();
    let from = |g: &Group| (plan(eye).clamp(g.lo, g.hi) - plan(eye)).length();
    groups.sort_by(|a, b| from(&a.0).total_cmp(&from(&b.0)));
    groups
}

/// A street of random blocks, where pruning skips most entries: the pruned horizon
/// hides exactly what the full one hides.
#[test]
fn pruning_changes_nothing_it_hides() {
    for turned in [false, true] {
        pruning_changes_nothing_it_hides_with(turned);
    }
}

fn pruning_changes_nothing_it_hides_with(turned: bool) {
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let (mut hidden, mut shown) = (0, 0);
    for _ in 0..40 {
        let (eye, prisms) = random_scene(
            &mut rng,
            120,
            300.0,
            (2.0, 20.0),
            (3.0, 60.0),
            turned,
            100.0,
        );
        let pruned = built(eye, &prisms, true, true, None);
        let full = built(eye, &prisms, false, false, None);
        // Pruned in the order given (shuffled), not nearest first.
        let unsorted = built(eye, &prisms, true, false, None);
        // In groups, nearest first, then in groups in no order.
        let mut grouped = Horizon::empty();
        grouped.rebuild(eye, tiled(&prisms, eye, 40.0), None);
        let mut shuffled = tiled(&prisms, eye, 40.0);
        shuffled.reverse();
        let mut reversed = Horizon::empty();
        reversed.rebuild(eye, shuffled, None);
        assert!(grouped.fronts.len() <= full.fronts.len());
        assert!(pruned.fronts.len() <= full.fronts.len());
        for _ in 0..500 {
            let target = random_box(&mut rng, 400.0, 20.0, 80.0);
            let hides = full.hides(&target);
            assert_eq!(pruned.hides(&target), hides, "{target:?} from {eye}");
            assert_eq!(unsorted.hides(&target), hides, "{target:?} from {eye}");
            assert_eq!(grouped.hides(&target), hides, "{target:?} from {eye}");
            assert_eq!(reversed.hides(&target), hides, "{target:?} from {eye}");
            if hides {
                hidden += 1;
            } else {
                shown += 1;
            }
        }
    }
    assert!(
        hidden > 1_000 && shown > 1_000,
        "{hidden} hidden, {shown} shown (turned: {turned})"
    );
}

/// A horizon built for a few boxes, one horizon rebuilt from eye to eye: it answers
/// for those boxes as the whole horizon does, though it holds far fewer entries.
/// A horizon built for some boxes takes no more groups once a near wall hides them all:
/// of a wall and 200 groups beyond it, at most one round of checks' worth is taken.
#[test]
fn a_horizon_for_some_boxes_stops_once_they_are_all_hidden() {
    let eye = Vec3::new(0.0, 1.5, 0.0);
    let wall = prism([5.0, -20.0], [6.0, 20.0], 30.0);
    let target = b([20.0, 0.0, -1.0], [22.0, 5.0, 1.0]);
    let mut wanted = Wanted::new(eye);
    assert!(wanted.add(&target));
    let beyond = (0..200).map(|k| {
        let x = 30.0 + k as f32;
        prism([x, -1.0], [x + 0.5, 1.0], 2.0)
    });
    let taken = std::cell::Cell::new(0);
    let groups = std::iter::once(wall).chain(beyond).map(|o| {
        taken.set(taken.get() + 1);
        (Group::around([&o]).unwrap(), [o])
    });
    let mut h = Horizon::empty();
    h.rebuild(eye, groups, Some(&wanted));
    assert!(h.hides(&target));
    assert!(taken.get() <= 16, "{} of 201 groups taken", taken.get());
}

#[test]
fn a_horizon_for_some_boxes_answers_for_them_as_the_whole_one() {
    // Few boxes over a few groups; then more boxes over many small groups, where a
    // build narrows its bins to the boxes still pending several times over.
    // A build for a few boxes keeps a small share of the whole horizon's entries.
    let (kept, all) = some_boxes_answer_as_the_whole_one(50.0, 1..12);
    assert!(kept * 3 < all, "{kept} entries kept of {all}");
    some_boxes_answer_as_the_whole_one(15.0, 12..60);
}

/// Random scenes in groups of prisms `tile` metres a side, each asked about a number
/// of random boxes in `boxes`: entries kept, and entries in the whole horizons.
fn some_boxes_answer_as_the_whole_one(tile: f32, boxes: Range<usize>) -> (usize, usize) {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(23);
    let (mut hidden, mut shown, mut kept, mut all) = (0, 0, 0, 0);
    let mut reused = Horizon::empty();
    let mut wanted = Wanted::new(Vec3::ZERO);
    for round in 0..60 {
        let turned = round % 2 == 1;
        let (eye, prisms) = random_scene(
            &mut rng,
            150,
            300.0,
            (2.0, 20.0),
            (3.0, 60.0),
            turned,
            100.0,
        );
        let full = built(eye, &prisms, false, false, None);
        let targets: Vec<Aabb> = (0..rng.gen_range(boxes.clone()))
            .map(|_| random_box(&mut rng, 400.0, 20.0, 80.0))
            .collect();
        wanted.reset(eye);
        let asked: Vec<&Aabb> = targets.iter().filter(|t| wanted.add(t)).collect();
        reused.rebuild(eye, tiled(&prisms, eye, tile), Some(&wanted));
        kept += reused.fronts.len();
        all += full.fronts.len();
        // The answer from the place each box was asked at is the same.
        for (k, t) in asked.iter().enumerate() {
            assert_eq!(
                reused.hides_wanted(&wanted, k, t),
                reused.hides(t),
                "{t:?} from {eye}"
            );
        }
        for t in &targets {
            let hides = full.hides(t);
            if asked.contains(&t) {
                assert_eq!(reused.hides(t), hides, "{t:?} from {eye}");
            } else {
                assert!(!hides, "{t:?} from {eye}: refused, yet hidden");
            }
            if hides {
                hidden += 1;
            } else {
                shown += 1;
            }
        }
    }
    assert!(hidden > 50 && shown > 50, "{hidden} hidden, {shown} shown");
    (kept, all)
}

/// Random prisms and boxes: whenever the horizon hides a box, every sight line from
/// the eye to a point of the box passes through a prism. Prisms along the axes, then
/// turned ones.
#[test]
fn what_it_hides_is_behind_a_prism_on_every_sight_line() {
    for turned in [false, true] {
        what_it_hides_is_behind_a_prism_with(turned);
    }
}

fn what_it_hides_is_behind_a_prism_with(turned: bool) {
    use crate::visibility::intersect::segment_meets_box;
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let (mut hidden, mut lines) = (0, 0);
    for _ in 0..200 {
        let (eye, mut prisms) =
            random_scene(&mut rng, 12, 60.0, (1.0, 15.0), (1.0, 30.0), turned, 0.0);
        prisms.retain(|o| !o.contains(eye) && o.distance(plan(eye)) > 0.5);
        let horizon = Horizon::new(eye, prisms.iter().copied());
        for _ in 0..50 {
            let target = random_box(&mut rng, 150.0, 10.0, 40.0);
            if !horizon.hides(&target) {
                continue;
            }
            hidden += 1;
            for _ in 0..40 {
                let f = Vec3::new(rng.gen(), rng.gen(), rng.gen());
                let q = target.min + f * target.extent();
                lines += 1;
                assert!(
                    prisms.iter().any(|o| {
                        // In the prism's own frame, where it is a box.
                        let local = |v: Vec3| {
                            let l = o.local(plan(v));
                            Vec3::new(l.x, v.y, l.y)
                        };
                        let h = o.half;
                        let own = b([-h.x, -1.0, -h.y], [h.x, o.top, h.y]);
                        segment_meets_box(local(eye), local(q), &own)
                    }),
                    "the sight line from {eye} to {q} meets no prism"
                );
            }
        }
    }
    assert!(
        hidden > 500 && lines > 20_000,
        "{hidden} boxes hidden (turned: {turned})"
    );
}

#[test]
fn the_bins_floor_is_the_floor() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let whole = (-3000..3000).map(|k| k as f32);
    let near_whole = (-3000..3000).flat_map(|k| {
        let x = k as f32;
        [x.next_down(), x.next_up(), x - 0.5, x + 1e-3]
    });
    let random = (0..10_000).map(|_| rng.gen_range(-2100.0f32..2100.0));
    for x in whole.chain(near_whole).chain(random.collect::<Vec<_>>()) {
        assert_eq!(floor(x), x.floor() as i64, "floor of {x}");
    }
}
