//! Belady's optimal offline replacement (MIN): on a miss with the cache full, evict the
//! resident page whose next use lies farthest in the future. Not in the thesis; it is
//! the ceiling that design.md asks every cache experiment to report beside LRU,
//! distance-priority LRU (Shou 2002 §4.2.4) and DoV / DT (§5.7).
//!
//! Departure from the textbook MIN: the missed page itself is a candidate, so when its
//! own next use is the farthest (or never) it is served without being cached. The pool
//! does the same when its policy has nothing to evict (DPLRU's pinned root), so this
//! variant bounds every policy the pool can run, where plain MIN would not. Counting is
//! the pool's: every access is one hit or one miss, cold misses count, an eviction is
//! counted per page dropped. O(n log n): next uses are precomputed backwards, and the
//! resident pages are kept in a `BTreeSet` ordered by next use.

use std::collections::{BTreeSet, HashMap};

use super::stats::CacheStats;
use super::trace::Trace;

/// The hits, misses and evictions of Belady's optimal replacement over `trace` with a
/// cache of `capacity_pages` pages.
///
/// ```
/// use flaneur::cache::{belady_replay, Access, Hint, Lru, Trace};
/// use flaneur::geom::Aabb;
/// let at = |page| Access { page, hint: Hint::UNKNOWN, query: Aabb::EMPTY, search: 0 };
/// let t = Trace { accesses: [1, 2, 3, 1, 2, 3, 1, 2, 3].map(at).to_vec(), ..Default::default() };
/// let best = belady_replay(&t, 2);
/// assert_eq!(t.replay(Box::new(Lru::default()), 2).hits, 0); // LRU thrashes
/// assert_eq!(best.hits, 4); // keeps 1 and 2, never caches 3
/// ```
pub fn belady_replay(trace: &Trace, capacity_pages: usize) -> CacheStats {
    let n = trace.accesses.len();
    // next[i]: the index of the next access of the same page, or n for never.
    let mut next = vec![n; n];
    let mut seen: HashMap<u64, usize> = HashMap::new();
    for (i, a) in trace.accesses.iter().enumerate().rev() {
        if let Some(j) = seen.insert(a.page, i) {
            next[i] = j;
        }
    }
    let mut stats = CacheStats::default();
    // Resident pages as (next use, page); `resident` maps a page to its next use.
    let mut by_next: BTreeSet<(usize, u64)> = BTreeSet::new();
    let mut resident: HashMap<u64, usize> = HashMap::new();
    for (i, a) in trace.accesses.iter().enumerate() {
        if let Some(due) = resident.get_mut(&a.page) {
            stats.hits += 1;
            by_next.remove(&(*due, a.page));
            *due = next[i];
            by_next.insert((next[i], a.page));
            continue;
        }
        stats.misses += 1;
        if resident.len() >= capacity_pages {
            match by_next.last().copied() {
                Some((far, page)) if far > next[i] => {
                    by_next.remove(&(far, page));
                    resident.remove(&page);
                    stats.evictions += 1;
                }
                // The new page is needed last (or the cache holds nothing): bypass.
                _ => continue,
            }
        }
        resident.insert(a.page, next[i]);
        by_next.insert((next[i], a.page));
    }
    stats
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cache::{Access, Hint, Lru};
    use crate::geom::Aabb;

    fn trace(pages: &[u64]) -> Trace {
        Trace {
            accesses: pages
                .iter()
                .map(|&page| Access {
                    page,
                    hint: Hint::UNKNOWN,
                    query: Aabb::EMPTY,
                    search: 0,
                })
                .collect(),
            ..Default::default()
        }
    }

    #[test]
    fn the_textbook_sequence() {
        // 7 0 1 2 0 3 0 4 2 3 0 3 2 with 3 frames: only the six cold misses (2 evicts
        // 7, 3 evicts 1, 4 is never used again and bypasses).
        let t = trace(&[7, 0, 1, 2, 0, 3, 0, 4, 2, 3, 0, 3, 2]);
        let s = belady_replay(&t, 3);
        assert_eq!((s.misses, s.evictions), (6, 2));
        assert_eq!(s.hits + s.misses, 13);
    }

    #[test]
    fn capacity_zero_and_bypass() {
        let t = trace(&[1, 2, 1, 2]);
        assert_eq!(
            belady_replay(&t, 0),
            CacheStats {
                hits: 0,
                misses: 4,
                evictions: 0
            }
        );
        // With one frame, 1 2 1 2 1: keeping 1 (bypassing 2) gives two hits.
        let t = trace(&[1, 2, 1, 2, 1]);
        assert_eq!(belady_replay(&t, 1).hits, 2);
        assert!(t.replay(Box::new(Lru::default()), 1).hits <= 2);
    }

    #[test]
    fn never_below_lru_on_random_sequences() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..50 {
            let pages: Vec<u64> = (0..300).map(|_| rng.gen_range(0..40)).collect();
            let t = trace(&pages);
            for cap in [1, 2, 5, 10, 39, 40] {
                let (best, lru) = (
                    belady_replay(&t, cap),
                    t.replay(Box::new(Lru::default()), cap),
                );
                assert!(best.hits >= lru.hits, "cap {cap}: {best:?} < {lru:?}");
                assert_eq!(best.accesses(), lru.accesses());
            }
        }
    }
}
