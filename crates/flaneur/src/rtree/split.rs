//! The linear node split of Ang and Tan (1997), which the thesis used for its R-trees
//! (Shou 2002 §4.1, ref. [3]).
//!
//! For each axis, every entry goes to the side of the node's MBR it lies closer to
//! (its low gap against its high gap); the axis that gives the most even split wins,
//! ties going to the least overlap between the two halves, then to the least total
//! volume. Departure: Ang–Tan has no minimum fill, so when the winner leaves a side
//! with fewer than `min_fill` entries (identical or nested boxes), the entries are
//! sorted by centre along the widest axis and cut in half instead.

use crate::geom::Aabb;

/// (larger side, overlap volume, total volume): lower is better, compared in order.
type SplitScore = (usize, f32, f32);

/// Partitions the entries (given by their MBRs) into two groups of indices.
pub(crate) fn linear_split(mbrs: &[Aabb], min_fill: usize) -> (Vec<usize>, Vec<usize>) {
    let all = mbrs.iter().fold(Aabb::EMPTY, |b, m| b.union(m));
    let mut best: Option<(SplitScore, Vec<usize>, Vec<usize>)> = None;
    for axis in 0..3 {
        let (mut low, mut high) = (Vec::new(), Vec::new());
        for (i, m) in mbrs.iter().enumerate() {
            if m.min[axis] - all.min[axis] < all.max[axis] - m.max[axis] {
                low.push(i);
            } else {
                high.push(i);
            }
        }
        let mbr_of = |side: &[usize]| side.iter().fold(Aabb::EMPTY, |b, &i| b.union(&mbrs[i]));
        let (a, b) = (mbr_of(&low), mbr_of(&high));
        let overlap = a.intersection(&b).map_or(0.0, |o| o.volume());
        let score = (low.len().max(high.len()), overlap, a.volume() + b.volume());
        let better = match &best {
            None => true,
            Some((s, _, _)) => score.0 < s.0 || (score.0 == s.0 && (score.1, score.2) < (s.1, s.2)),
        };
        if better {
            best = Some((score, low, high));
        }
    }
    let (_, low, high) = best.expect("three axes were tried");
    if low.len().min(high.len()) >= min_fill.max(1) {
        return (low, high);
    }
    let extent = all.extent();
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mut order: Vec<usize> = (0..mbrs.len()).collect();
    order.sort_by(|&i, &j| mbrs[i].center()[axis].total_cmp(&mbrs[j].center()[axis]));
    let high = order.split_off(order.len() / 2);
    (order, high)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(x: f32, z: f32) -> Aabb {
        Aabb::new([x, 0.0, z], [x + 1.0, 1.0, z + 1.0]).unwrap()
    }

    #[test]
    fn splits_two_clusters_apart() {
        let mbrs: Vec<Aabb> = (0..5)
            .map(|i| b(i as f32, 0.0))
            .chain((0..5).map(|i| b(i as f32 + 100.0, 0.0)))
            .collect();
        let (l, h) = linear_split(&mbrs, 2);
        assert_eq!(l, vec![0, 1, 2, 3, 4]);
        assert_eq!(h, vec![5, 6, 7, 8, 9]);
    }

    #[test]
    fn identical_boxes_still_split_evenly() {
        let mbrs = vec![b(0.0, 0.0); 9];
        let (l, h) = linear_split(&mbrs, 3);
        assert!(l.len() >= 3 && h.len() >= 3 && l.len() + h.len() == 9);
    }
}
