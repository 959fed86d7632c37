//! Distance-priority LRU — Shou 2002, §4.2.4.
//!
//! The root is never evicted. Every other entry has
//! - a level priority P: the thesis numbers levels from the root down and gives lower
//!   (deeper) levels larger P, the same P per level; with our levels (0 = leaf,
//!   `height - 1` = root) that is P = height − 1 − level, so leaves have the largest;
//! - QN, the number of searches since the entry was loaded **or last used**: after
//!   each search QN of every replaceable entry rises by 1, and a loaded entry starts at
//!   0. The thesis resets QN only at load; we also reset it on a hit, which is what its
//!   guarantee 3 ("the later a node is accessed, the more likely it is to reside in
//!   memory") and the name LRU ask for. QN is kept as the search number of the last
//!   load or use, so ageing is O(1) instead of a pass over the entries;
//! - DIST, the block distance between the current query box and the node's MBR.
//!
//! f = α·pp + β·pd + γ·pl, each term divided by its maximum over the current
//! candidates (0 when that maximum is 0); the highest f is evicted. Ties (the thesis:
//! "least recently used and … greatest block-distance") go to the largest QN, then the
//! greatest DIST, then the oldest access (a per-access tick, so the choice is total).
//! The victim scan is O(n) over the entries with no allocation; the thesis's cache
//! held 256 pages.

use std::collections::HashMap;

use super::{Hint, Policy};
use crate::cache::block_distance;
use crate::error::{Error, Result};
use crate::geom::Aabb;

/// The distance-priority LRU policy. `Default` weighs the three terms equally, as the
/// thesis's runs did.
///
/// ```
/// use flaneur::cache::{DpLru, Hint, Policy};
/// use flaneur::geom::Aabb;
/// let mut p = DpLru::new(0.0, 1.0, 0.0).unwrap(); // distance only
/// let leaf = |x: f32| Hint { level: 0, height: 2, mbr: Aabb::new([x, 0.0, 0.0], [x + 1.0, 1.0, 1.0]).unwrap(), dov: 0.0 };
/// p.on_insert(1, &leaf(0.0));
/// p.on_insert(2, &leaf(100.0));
/// let query = Aabb::new([0.0; 3], [5.0; 3]).unwrap();
/// assert_eq!(p.victim(&query), Some(2)); // the far leaf goes first
/// assert!(DpLru::new(0.5, 0.5, 0.5).is_err()); // weights must sum to 1
/// ```
#[derive(Clone, Debug)]
pub struct DpLru {
    alpha: f64,
    beta: f64,
    gamma: f64,
    /// Replaceable entries; `index` maps a key to its slot.
    entries: Vec<Entry>,
    index: HashMap<u64, usize>,
    /// Roots: never evicted, not aged.
    pinned: Vec<u64>,
    /// Searches ended so far.
    searches: u64,
    /// Accesses so far: the final tie-break.
    tick: u64,
}

#[derive(Clone, Copy, Debug)]
struct Entry {
    key: u64,
    /// Level priority P (larger: evicted sooner).
    p: u32,
    mbr: Aabb,
    /// Search number of the last load or use: QN = searches − stamp.
    stamp: u64,
    /// Access number of the last load or use.
    tick: u64,
    /// Scratch for the victim scan: DIST to the current query.
    dist: f32,
}

/// How far two weight sums may differ from 1.
const WEIGHT_TOLERANCE: f64 = 1e-4;

impl Default for DpLru {
    fn default() -> DpLru {
        DpLru::with_weights(1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0)
    }
}

impl DpLru {
    /// The policy with weights α (level priority), β (block distance) and γ (QN). Each
    /// must be a finite number ≥ 0 and α + β + γ must be 1 (within 1e-4).
    pub fn new(alpha: f32, beta: f32, gamma: f32) -> Result<DpLru> {
        let (a, b, g) = (f64::from(alpha), f64::from(beta), f64::from(gamma));
        if ![a, b, g].iter().all(|w| w.is_finite() && *w >= 0.0) {
            return Err(Error::Invalid(format!(
                "distance-priority LRU weights α={alpha}, β={beta}, γ={gamma} must be finite and not negative"
            )));
        }
        if (a + b + g - 1.0).abs() > WEIGHT_TOLERANCE {
            return Err(Error::Invalid(format!(
                "distance-priority LRU weights α={alpha}, β={beta}, γ={gamma} must sum to 1 (they sum to {})",
                a + b + g
            )));
        }
        Ok(DpLru::with_weights(a, b, g))
    }

    fn with_weights(alpha: f64, beta: f64, gamma: f64) -> DpLru {
        DpLru {
            alpha,
            beta,
            gamma,
            entries: Vec::new(),
            index: HashMap::new(),
            pinned: Vec::new(),
            searches: 0,
            tick: 0,
        }
    }

    /// (α, β, γ).
    pub fn weights(&self) -> (f32, f32, f32) {
        (self.alpha as f32, self.beta as f32, self.gamma as f32)
    }

    fn is_default(&self) -> bool {
        let d = 1.0 / 3.0;
        [self.alpha, self.beta, self.gamma]
            .iter()
            .all(|w| (w - d).abs() <= WEIGHT_TOLERANCE)
    }

    /// Level priority: deeper levels larger, leaves largest.
    fn priority(hint: &Hint) -> u32 {
        hint.height
            .saturating_sub(1)
            .saturating_sub(u32::from(hint.level))
    }

    fn remove_entry(&mut self, slot: usize) -> Entry {
        let e = self.entries.swap_remove(slot);
        self.index.remove(&e.key);
        if let Some(moved) = self.entries.get(slot) {
            self.index.insert(moved.key, slot);
        }
        e
    }

    /// Records an access of `key` (load or use): resets its QN, refreshes its hint,
    /// and moves it between the pinned roots and the replaceable entries if its role
    /// changed (a tree that grew by insertion has a new root).
    fn touch(&mut self, key: u64, hint: &Hint) {
        self.tick += 1;
        let pinned_at = self.pinned.iter().position(|k| *k == key);
        if hint.is_root() {
            if let Some(slot) = self.index.get(&key).copied() {
                self.remove_entry(slot);
            }
            if pinned_at.is_none() {
                self.pinned.push(key);
            }
            return;
        }
        if let Some(i) = pinned_at {
            self.pinned.swap_remove(i);
        }
        let e = Entry {
            key,
            p: Self::priority(hint),
            mbr: hint.mbr,
            stamp: self.searches,
            tick: self.tick,
            dist: 0.0,
        };
        match self.index.get(&key) {
            Some(&slot) => self.entries[slot] = e,
            None => {
                self.index.insert(key, self.entries.len());
                self.entries.push(e);
            }
        }
    }
}

impl Policy for DpLru {
    fn name(&self) -> String {
        if self.is_default() {
            "dplru".into()
        } else {
            format!(
                "dplru({},{},{})",
                self.alpha as f32, self.beta as f32, self.gamma as f32
            )
        }
    }

    fn on_hit(&mut self, key: u64, hint: &Hint) {
        if self.index.contains_key(&key) || self.pinned.contains(&key) {
            self.touch(key, hint);
        }
    }

    fn on_insert(&mut self, key: u64, hint: &Hint) {
        self.touch(key, hint);
    }

    fn victim(&mut self, query: &Aabb) -> Option<u64> {
        // First pass: DIST per entry and the maxima the terms are normalised by.
        let (mut max_p, mut max_d, mut max_q) = (0u32, 0f32, 0u64);
        let now = self.searches;
        for e in &mut self.entries {
            // Capped so that an infinite box cannot make f NaN.
            e.dist = block_distance(&e.mbr, query).min(f32::MAX);
            max_p = max_p.max(e.p);
            max_d = max_d.max(e.dist);
            max_q = max_q.max(now.saturating_sub(e.stamp));
        }
        // f = α·p/max_p + β·d/max_d + γ·qn/max_q, each weight pre-divided by its maximum.
        let scale = |w: f64, max: f64| if max > 0.0 { w / max } else { 0.0 };
        let wp = scale(self.alpha, f64::from(max_p));
        let wd = scale(self.beta, f64::from(max_d));
        let wq = scale(self.gamma, max_q as f64);
        // Second pass: the highest f, ties by QN, DIST, then the oldest access.
        let (mut slot, mut bf, mut bq, mut bd, mut bt) =
            (usize::MAX, f64::NEG_INFINITY, 0u64, 0f32, u64::MAX);
        for (i, e) in self.entries.iter().enumerate() {
            let qn = now.saturating_sub(e.stamp);
            let f = wp * f64::from(e.p) + wd * f64::from(e.dist) + wq * qn as f64;
            if f > bf
                || (f == bf
                    && (qn > bq || (qn == bq && (e.dist > bd || (e.dist == bd && e.tick < bt)))))
            {
                (slot, bf, bq, bd, bt) = (i, f, qn, e.dist, e.tick);
            }
        }
        (slot != usize::MAX).then(|| self.remove_entry(slot).key)
    }

    fn on_remove(&mut self, key: u64) {
        if let Some(slot) = self.index.get(&key).copied() {
            self.remove_entry(slot);
        } else if let Some(i) = self.pinned.iter().position(|k| *k == key) {
            self.pinned.swap_remove(i);
        }
    }

    fn end_search(&mut self) {
        self.searches += 1;
    }

    fn len(&self) -> usize {
        self.entries.len() + self.pinned.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node(level: u16, x: f32) -> Hint {
        Hint {
            level,
            height: 3,
            mbr: Aabb::new([x, 0.0, 0.0], [x + 10.0, 10.0, 10.0]).unwrap(),
            dov: 0.0,
        }
    }
    const ROOT: Hint = Hint {
        level: 2,
        height: 3,
        mbr: Aabb::EMPTY,
        dov: 0.0,
    };

    fn q(x: f32) -> Aabb {
        Aabb::new([x, 0.0, 0.0], [x + 10.0, 10.0, 10.0]).unwrap()
    }

    #[test]
    fn weights_must_sum_to_one() {
        assert!(DpLru::new(0.5, 0.3, 0.2).is_ok());
        assert!(
            DpLru::new(0.5, 0.3, 0.20005).is_ok(),
            "within the tolerance"
        );
        assert!(DpLru::new(0.5, 0.3, 0.3).is_err());
        assert!(DpLru::new(1.5, -0.5, 0.0).is_err(), "negative weight");
        assert!(DpLru::new(f32::NAN, 0.5, 0.5).is_err());
        assert_eq!(DpLru::default().name(), "dplru");
        assert_eq!(DpLru::new(1.0, 0.0, 0.0).unwrap().name(), "dplru(1,0,0)");
    }

    #[test]
    fn the_root_is_never_evicted() {
        let mut p = DpLru::new(0.0, 0.0, 1.0).unwrap();
        p.on_insert(100, &ROOT);
        for _ in 0..10 {
            p.end_search(); // the root would have the largest QN if it aged
        }
        p.on_insert(1, &node(0, 0.0));
        p.on_insert(2, &node(1, 0.0));
        assert_eq!(p.len(), 3);
        let mut out = vec![p.victim(&q(0.0)), p.victim(&q(0.0))];
        out.sort();
        assert_eq!(out, [Some(1), Some(2)]);
        assert_eq!(p.victim(&q(0.0)), None, "only the root is left");
        assert_eq!(p.len(), 1);
        p.on_remove(100);
        assert!(p.is_empty());
    }

    #[test]
    fn a_far_leaf_goes_before_a_near_one() {
        let mut p = DpLru::default();
        p.on_insert(1, &node(0, 1000.0)); // far, loaded first
        p.on_insert(2, &node(0, 0.0)); // near
        p.on_insert(3, &node(0, 20.0)); // 10 away
        assert_eq!(p.victim(&q(0.0)), Some(1));
        assert_eq!(p.victim(&q(0.0)), Some(3));
        assert_eq!(p.victim(&q(0.0)), Some(2));
    }

    #[test]
    fn deeper_levels_go_first_and_old_entries_before_new() {
        let mut p = DpLru::new(0.5, 0.0, 0.5).unwrap();
        p.on_insert(1, &node(1, 0.0)); // P = 1
        p.on_insert(2, &node(0, 0.0)); // P = 2, a leaf
        assert_eq!(
            p.victim(&q(0.0)),
            Some(2),
            "same QN: the leaf has the larger P"
        );
        p.on_insert(2, &node(0, 0.0));
        p.end_search();
        p.end_search();
        p.on_hit(2, &node(0, 0.0)); // QN(2) = 0, QN(1) = 2
                                    // f(1) = 0.5·0.5 + 0.5·1 = 0.75; f(2) = 0.5·1 + 0 = 0.5.
        assert_eq!(p.victim(&q(0.0)), Some(1));
    }

    #[test]
    fn ties_go_to_the_largest_qn_then_the_farthest_then_the_oldest() {
        // β = 0 makes DIST a pure tie-break; α = 1 makes every leaf's f equal.
        let mut p = DpLru::new(1.0, 0.0, 0.0).unwrap();
        p.on_insert(1, &node(0, 0.0));
        p.end_search();
        p.on_insert(2, &node(0, 500.0));
        p.on_insert(3, &node(0, 100.0));
        p.on_insert(4, &node(0, 100.0));
        assert_eq!(
            p.victim(&q(0.0)),
            Some(1),
            "least recently used: QN 1 against 0"
        );
        assert_eq!(
            p.victim(&q(0.0)),
            Some(2),
            "equal QN: the greatest block distance"
        );
        assert_eq!(
            p.victim(&q(0.0)),
            Some(3),
            "equal QN and DIST: the oldest access"
        );
        assert_eq!(p.victim(&q(0.0)), Some(4));
        assert_eq!(p.victim(&q(0.0)), None);
    }

    #[test]
    fn infinite_boxes_still_yield_a_victim() {
        let mut p = DpLru::default();
        let far = glam::Vec3::splat(f32::NEG_INFINITY);
        let huge = Hint {
            mbr: Aabb { min: far, max: far },
            ..node(0, 0.0)
        };
        p.on_insert(1, &huge);
        p.on_insert(2, &node(0, 0.0));
        assert_eq!(p.victim(&q(0.0)), Some(1));
        assert_eq!(p.victim(&q(0.0)), Some(2));
    }

    #[test]
    fn a_hit_resets_qn() {
        let mut p = DpLru::new(0.0, 0.0, 1.0).unwrap();
        p.on_insert(1, &node(0, 0.0));
        p.on_insert(2, &node(0, 0.0));
        p.end_search();
        p.on_hit(1, &node(0, 0.0));
        p.on_hit(7, &node(0, 0.0)); // not resident: ignored
        assert_eq!(p.len(), 2);
        assert_eq!(p.victim(&Aabb::EMPTY), Some(2));
    }

    #[test]
    fn a_new_root_is_pinned_and_the_old_one_released() {
        let mut p = DpLru::default();
        p.on_insert(
            1,
            &Hint {
                level: 1,
                height: 2,
                ..ROOT
            },
        );
        // The tree grew: page 1 is now an internal node, page 9 the root.
        p.on_hit(
            1,
            &Hint {
                level: 1,
                height: 3,
                ..ROOT
            },
        );
        p.on_insert(9, &ROOT);
        assert_eq!(p.victim(&Aabb::EMPTY), Some(1));
        assert_eq!(p.victim(&Aabb::EMPTY), None);
    }
}
