//! From node ids to footprints: a multipolygon's member ways joined end to end into
//! closed rings, each ring's nodes placed in metres, repeated nodes dropped, and the
//! outcome checked (closed, three corners or more, an area, no crossing edges), with
//! what was repaired or why the building is skipped.

use std::collections::HashMap;

use super::report::{Repair, Skip};

/// A point on the map in metres: east, north.
pub(super) type P2 = [f64; 2];

/// One polygon of a footprint: its outer ring counter-clockwise seen from above, its
/// holes clockwise, neither repeating its first corner at the end.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Polygon {
    pub outer: Vec<P2>,
    pub holes: Vec<Vec<P2>>,
}

/// Joins ways (node lists) into closed rings: each closed way is one, and open ways are
/// chained where one ends at another's end, turned as needed. A chain that cannot be
/// closed is `Skip::Unclosed`.
pub(super) fn join_ways(ways: Vec<Vec<i64>>) -> Result<Vec<Vec<i64>>, Skip> {
    let mut rings = Vec::new();
    let mut open: Vec<Vec<i64>> = Vec::new();
    for w in ways {
        if w.len() >= 2 && w.first() == w.last() {
            rings.push(w);
        } else if !w.is_empty() {
            open.push(w);
        }
    }
    while let Some(mut ring) = open.pop() {
        while ring.first() != ring.last() {
            let end = *ring.last().expect("chains are never empty");
            let Some(i) = open
                .iter()
                .position(|w| w.first() == Some(&end) || w.last() == Some(&end))
            else {
                return Err(Skip::Unclosed);
            };
            let mut next = open.swap_remove(i);
            if next.first() != Some(&end) {
                next.reverse();
            }
            ring.extend_from_slice(&next[1..]);
        }
        rings.push(ring);
    }
    Ok(rings)
}

/// A closed ring of node ids as points, its last (repeated) corner dropped, and
/// repeated nodes (the same id, or the same place, one after the other) dropped too.
pub(super) fn place_ring(
    ring: &[i64],
    at: &HashMap<i64, P2>,
    repairs: &mut Vec<Repair>,
) -> Result<Vec<P2>, Skip> {
    if ring.len() < 2 || ring.first() != ring.last() {
        return Err(Skip::Unclosed);
    }
    let mut points: Vec<P2> = Vec::with_capacity(ring.len());
    let mut repeated = false;
    for id in &ring[..ring.len() - 1] {
        let p = *at.get(id).ok_or(Skip::MissingNodes)?;
        if points.last() == Some(&p) {
            repeated = true;
        } else {
            points.push(p);
        }
    }
    while points.len() > 1 && points.first() == points.last() {
        points.pop();
        repeated = true;
    }
    if repeated {
        repairs.push(Repair::RepeatedNodes);
    }
    if points.len() < 3 {
        return Err(Skip::TooFewCorners);
    }
    Ok(points)
}

/// Twice the signed area of a ring: positive counter-clockwise.
pub(super) fn signed_area2(ring: &[P2]) -> f64 {
    let n = ring.len();
    (0..n)
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum()
}

/// Square metres under which a ring has no area worth a building.
pub(super) const MIN_AREA: f64 = 0.5;

/// Polygons from placed outer and inner rings: outers counter-clockwise, each inner
/// given (clockwise) to the outer that holds it. An inner inside no outer is dropped
/// (`Repair::StrayInner`); a footprint whose outers have no area is skipped.
pub(super) fn polygons(
    outers: Vec<Vec<P2>>,
    inners: Vec<Vec<P2>>,
    repairs: &mut Vec<Repair>,
) -> Result<Vec<Polygon>, Skip> {
    let mut polys: Vec<Polygon> = Vec::new();
    for mut o in outers {
        let a = signed_area2(&o);
        if a.abs() / 2.0 < MIN_AREA {
            repairs.push(Repair::TinyRing);
            continue;
        }
        if a < 0.0 {
            o.reverse();
        }
        polys.push(Polygon {
            outer: o,
            holes: Vec::new(),
        });
    }
    if polys.is_empty() {
        return Err(Skip::NoArea);
    }
    for mut h in inners {
        let a = signed_area2(&h);
        if a.abs() / 2.0 < MIN_AREA {
            repairs.push(Repair::TinyRing);
            continue;
        }
        if a > 0.0 {
            h.reverse();
        }
        match polys.iter_mut().find(|p| inside(&p.outer, h[0])) {
            Some(p) => p.holes.push(h),
            None => repairs.push(Repair::StrayInner),
        }
    }
    if polys.iter().any(crosses_itself) {
        return Err(Skip::SelfIntersecting);
    }
    Ok(polys)
}

/// Whether `p` lies inside `ring` (even-odd rule).
fn inside(ring: &[P2], p: P2) -> bool {
    let n = ring.len();
    let mut odd = false;
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                odd = !odd;
            }
        }
    }
    odd
}

/// Whether any two edges of a polygon's rings cross (meeting at a shared corner is
/// not crossing). Quadratic in the corners: footprints have tens of them.
fn crosses_itself(poly: &Polygon) -> bool {
    let mut edges: Vec<(P2, P2)> = Vec::new();
    for ring in std::iter::once(&poly.outer).chain(&poly.holes) {
        let n = ring.len();
        edges.extend((0..n).map(|i| (ring[i], ring[(i + 1) % n])));
    }
    for i in 0..edges.len() {
        for j in i + 1..edges.len() {
            if proper_cross(edges[i], edges[j]) {
                return true;
            }
        }
    }
    false
}

/// Whether two segments cross at a point inside both; touching, sharing an end and
/// lying on one line are not crossings.
fn proper_cross((a, b): (P2, P2), (c, d): (P2, P2)) -> bool {
    let orient =
        |p: P2, q: P2, r: P2| (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
    let (d1, d2) = (orient(a, b, c), orient(a, b, d));
    let (d3, d4) = (orient(c, d, a), orient(c, d, b));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn placed(points: &[(i64, P2)]) -> HashMap<i64, P2> {
        points.iter().copied().collect()
    }

    #[test]
    fn open_ways_are_joined_into_a_ring_whichever_way_they_run() {
        let rings = join_ways(vec![vec![1, 2, 3], vec![5, 4, 3], vec![5, 1]]).unwrap();
        assert_eq!(rings.len(), 1);
        let r = &rings[0];
        assert_eq!(r.first(), r.last());
        assert_eq!(r.len(), 6, "{r:?}");
        assert_eq!(
            join_ways(vec![vec![1, 2, 3], vec![3, 4]]),
            Err(Skip::Unclosed)
        );
    }

    #[test]
    fn repeated_nodes_are_dropped_and_counted() {
        let at = placed(&[
            (1, [0.0, 0.0]),
            (2, [10.0, 0.0]),
            (3, [10.0, 10.0]),
            (4, [10.0, 10.0]),
        ]);
        let mut repairs = Vec::new();
        let ring = place_ring(&[1, 2, 2, 3, 4, 1], &at, &mut repairs).unwrap();
        assert_eq!(ring, vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]]);
        assert_eq!(repairs, vec![Repair::RepeatedNodes]);
        assert_eq!(
            place_ring(&[1, 2, 9, 1], &at, &mut repairs),
            Err(Skip::MissingNodes)
        );
        assert_eq!(
            place_ring(&[1, 2, 2, 1], &at, &mut repairs),
            Err(Skip::TooFewCorners)
        );
    }

    #[test]
    fn rings_are_turned_holes_found_and_crossings_refused() {
        let square = |s: f64, o: f64| vec![[o, o], [o, o + s], [o + s, o + s], [o + s, o]];
        let mut repairs = Vec::new();
        // A clockwise outer with a hole inside and one outside it.
        let polys = polygons(
            vec![square(10.0, 0.0)],
            vec![square(2.0, 4.0), square(2.0, 40.0)],
            &mut repairs,
        )
        .unwrap();
        assert_eq!(polys.len(), 1);
        assert!(signed_area2(&polys[0].outer) > 0.0);
        assert_eq!(polys[0].holes.len(), 1);
        assert!(signed_area2(&polys[0].holes[0]) < 0.0);
        assert_eq!(repairs, vec![Repair::StrayInner]);
        // A bow tie of unequal lobes (an area, 30 m²) crosses itself.
        let bow = vec![[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 4.0]];
        assert_eq!(
            polygons(vec![bow], vec![], &mut repairs),
            Err(Skip::SelfIntersecting)
        );
        // A sliver has no area.
        let sliver = vec![[0.0, 0.0], [10.0, 0.0], [20.0, 0.001]];
        assert_eq!(
            polygons(vec![sliver], vec![], &mut repairs),
            Err(Skip::NoArea)
        );
    }
}
