//! The path policy (ours, not in the thesis): an online approximation of Belady's
//! optimum (`belady.rs`) that reads the future from the viewer's motion instead of the
//! trace. Shou 2002 §4.2.4 argues that a node far from the viewer will not be needed
//! soon and weighs block distance from the current query; this policy asks instead
//! which of the walk's next searches — the cells predicted along the motion, F' = F +
//! k·v of §4.2.5 — would read the node, through the [`Lookahead`] the walk last gave
//! it, and evicts the node needed last.
//!
//! Each entry's next need is the first predicted search that would enter it
//! (`Lookahead::first_need`'s rule, once per entry and lookahead), or the search under
//! way when it has yet to read the node and the held cells do not cover the node's part
//! inside its box. A node the search under way has read already is not read by it
//! again: its next need is the first predicted search that would enter it once that box
//! is held too. At eviction:
//! - the root is never evicted (every search reads it), as in DPLRU;
//! - a node no predicted search reads goes first, the least recently used of them;
//! - otherwise the node whose next need is latest goes, ties to the least recently
//!   used.
//!
//! Without a lookahead (a trace read back from CSV, a walk that predicts nothing) every
//! node is needed by no predicted search, and the policy is LRU that keeps the root.

use std::collections::HashMap;

use super::{Hint, Policy};
use crate::cache::Lookahead;
use crate::geom::{covered, Aabb};

/// Evicts the node the walk's predicted searches need last.
///
/// ```
/// use flaneur::cache::{Hint, Lookahead, PathPolicy, Policy};
/// use flaneur::geom::Aabb;
/// let b = |s: &str| s.parse::<Aabb>().unwrap();
/// let leaf = |mbr| Hint { level: 0, height: 2, mbr, dov: 0.0 };
/// let mut p = PathPolicy::default();
/// p.on_insert(1, &leaf(b("0,0,0,10,10,10"))); // where the viewer is heading
/// p.on_insert(2, &leaf(b("90,0,0,100,10,10"))); // behind it, used since
/// p.on_hit(2, &leaf(b("90,0,0,100,10,10")));
/// p.look_ahead(&Lookahead { cells: vec![b("0,0,0,20,10,10")], held: vec![] });
/// assert_eq!(p.victim(&Aabb::EMPTY), Some(2)); // LRU would evict 1
/// ```
#[derive(Clone, Debug, Default)]
pub struct PathPolicy {
    /// Replaceable entries by key.
    entries: HashMap<u64, Entry>,
    /// Roots: never evicted.
    pinned: Vec<u64>,
    /// The latest prediction, and how many have been given (entries cache their need
    /// under this number).
    ahead: Lookahead,
    generation: u64,
    /// Searches ended so far: an entry stamped with this was read by the search under way.
    searches: u64,
    /// Accesses so far: the recency order.
    tick: u64,
}

#[derive(Clone, Copy, Debug)]
struct Entry {
    mbr: Aabb,
    /// Access number of the last load or use.
    tick: u64,
    /// Search number of the last load or use.
    search: u64,
    /// The first predicted search that would read it (`Lookahead::first_need`), as of
    /// lookahead `generation`.
    first: Option<usize>,
    generation: u64,
}

impl PathPolicy {
    /// Records an access of `key`, moving it between the pinned roots and the
    /// replaceable entries if its role changed (a tree grown by insertion has a new root).
    fn touch(&mut self, key: u64, hint: &Hint) {
        self.tick += 1;
        let pinned_at = self.pinned.iter().position(|k| *k == key);
        if hint.is_root() {
            self.entries.remove(&key);
            if pinned_at.is_none() {
                self.pinned.push(key);
            }
            return;
        }
        if let Some(i) = pinned_at {
            self.pinned.swap_remove(i);
        }
        let generation = self.generation;
        let e = self.entries.entry(key).or_insert(Entry {
            mbr: hint.mbr,
            tick: 0,
            search: 0,
            first: None,
            generation: generation.wrapping_sub(1),
        });
        if e.mbr != hint.mbr {
            e.mbr = hint.mbr;
            e.generation = generation.wrapping_sub(1);
        }
        e.tick = self.tick;
        e.search = self.searches;
    }
}

/// The next need of an entry no search reads.
const NEVER: usize = usize::MAX;

impl PathPolicy {
    /// The entry to evict during a search of `query` (`Aabb::EMPTY` outside one): the
    /// latest next need, ties to the least recently used, then the smaller key (so the
    /// choice does not depend on the map's order).
    ///
    /// Next needs count the search under way as 0 and predicted cell i as i + 1. A node
    /// the search under way has not read yet, whose part inside `query` the held cells
    /// do not cover, is needed by it; a node it has read is needed next by the first
    /// predicted search that would read it once `query` is held as well.
    fn worst(&mut self, query: &Aabb) -> Option<u64> {
        let (generation, searches) = (self.generation, self.searches);
        let after = Lookahead {
            cells: self.ahead.cells.clone(),
            held: self.ahead.held.iter().chain([query]).copied().collect(),
        };
        let mut best: Option<(u64, usize, u64)> = None; // (key, next need, tick)
        for (key, e) in &mut self.entries {
            if e.generation != generation {
                e.first = self.ahead.first_need(&e.mbr);
                e.generation = generation;
            }
            let predicted = |first: Option<usize>| first.map_or(NEVER, |i| i + 1);
            let need = if query.is_empty() {
                predicted(e.first)
            } else if e.search == searches {
                predicted(after.first_need(&e.mbr))
            } else if query
                .intersection(&e.mbr)
                .is_some_and(|inside| !covered(inside, &self.ahead.held))
            {
                0
            } else {
                predicted(e.first)
            };
            let better = best.is_none_or(|(bk, bn, bt)| {
                need > bn || (need == bn && (e.tick < bt || (e.tick == bt && *key < bk)))
            });
            if better {
                best = Some((*key, need, e.tick));
            }
        }
        best.map(|(k, _, _)| k)
    }
}

impl Policy for PathPolicy {
    fn name(&self) -> String {
        "path".into()
    }

    fn on_hit(&mut self, key: u64, hint: &Hint) {
        if self.entries.contains_key(&key) || self.pinned.contains(&key) {
            self.touch(key, hint);
        }
    }

    fn on_insert(&mut self, key: u64, hint: &Hint) {
        self.touch(key, hint);
    }

    fn victim(&mut self, query: &Aabb) -> Option<u64> {
        let key = self.worst(query)?;
        self.entries.remove(&key);
        Some(key)
    }

    fn on_remove(&mut self, key: u64) {
        if self.entries.remove(&key).is_none() {
            if let Some(i) = self.pinned.iter().position(|k| *k == key) {
                self.pinned.swap_remove(i);
            }
        }
    }

    fn end_search(&mut self) {
        self.searches += 1;
    }

    fn look_ahead(&mut self, ahead: &Lookahead) {
        if *ahead != self.ahead {
            self.ahead = ahead.clone();
            self.generation += 1;
        }
    }

    fn len(&self) -> usize {
        self.entries.len() + self.pinned.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cache::{Access, Lru, Trace, TracedLookahead};

    fn b(s: &str) -> Aabb {
        s.parse().unwrap()
    }

    /// A leaf of a two-level tree whose MBR spans x0..x0 + 10.
    fn leaf(x0: f32) -> Hint {
        Hint {
            level: 0,
            height: 2,
            mbr: Aabb::new([x0, 0.0, 0.0], [x0 + 10.0, 10.0, 10.0]).unwrap(),
            dov: 0.0,
        }
    }
    const ROOT: Hint = Hint {
        level: 1,
        height: 2,
        mbr: Aabb::EMPTY,
        dov: 0.0,
    };

    /// Heading east along x: the next searches are at 0..40, then 40..80.
    fn east() -> Lookahead {
        Lookahead {
            cells: vec![b("0,0,0,40,10,10"), b("40,0,0,80,10,10")],
            held: vec![],
        }
    }

    #[test]
    fn keeps_what_the_path_needs_where_lru_evicts_it() {
        let mut path = PathPolicy::default();
        let mut lru = Lru::default();
        // 1 lies ahead (x 50..60), 2 behind the viewer (x −50..−40), used more recently.
        for p in [&mut path as &mut dyn Policy, &mut lru] {
            p.on_insert(1, &leaf(50.0));
            p.on_insert(2, &leaf(-50.0));
            p.look_ahead(&east());
        }
        assert_eq!(lru.victim(&Aabb::EMPTY), Some(1));
        assert_eq!(path.victim(&Aabb::EMPTY), Some(2));
    }

    #[test]
    fn the_node_needed_latest_goes_first_and_the_root_never() {
        let mut p = PathPolicy::default();
        p.on_insert(100, &ROOT);
        p.on_insert(1, &leaf(10.0)); // needed by the first search
        p.on_insert(2, &leaf(60.0)); // by the second
        p.on_insert(3, &leaf(200.0)); // by neither
        p.on_insert(4, &leaf(300.0)); // by neither, used last
        p.end_search();
        p.look_ahead(&east());
        let order: Vec<_> = std::iter::from_fn(|| p.victim(&Aabb::EMPTY)).collect();
        assert_eq!(
            order,
            [3, 4, 2, 1],
            "unneeded (LRU among them), then latest need"
        );
        assert_eq!(p.len(), 1, "only the root is left");
        p.on_remove(100);
        assert!(p.is_empty());
    }

    #[test]
    fn held_cells_hide_what_the_walk_already_has() {
        let mut p = PathPolicy::default();
        p.on_insert(1, &leaf(10.0)); // in the first cell, which the walk holds
        p.on_insert(2, &leaf(60.0)); // in the second
        p.on_insert(3, &leaf(35.0)); // straddles both: the second search reads it
        p.look_ahead(&Lookahead {
            held: vec![b("0,0,0,40,10,10")],
            ..east()
        });
        assert_eq!(
            p.victim(&Aabb::EMPTY),
            Some(1),
            "no predicted search reads 1"
        );
        assert_eq!(p.victim(&Aabb::EMPTY), Some(2), "equal needs: LRU");
        assert_eq!(p.victim(&Aabb::EMPTY), Some(3));
    }

    #[test]
    fn the_search_under_way_needs_what_it_has_not_read_yet() {
        let mut p = PathPolicy::default();
        p.look_ahead(&east());
        p.on_insert(1, &leaf(10.0));
        p.on_insert(2, &leaf(60.0));
        p.on_insert(4, &leaf(0.0));
        p.end_search();
        // A search of 0..40 is under way and has read 4: once it is held, no predicted
        // search reads 4 again, though the first predicted cell holds it; it has yet to
        // read 1, which the second-cell node 2 goes before.
        p.on_hit(4, &leaf(0.0));
        let query = b("0,0,0,40,10,10");
        assert_eq!(p.victim(&query), Some(4));
        assert_eq!(p.victim(&query), Some(2));
        assert_eq!(p.victim(&query), Some(1));
    }

    #[test]
    fn without_a_lookahead_it_is_lru_that_keeps_the_root() {
        let mut p = PathPolicy::default();
        p.on_insert(100, &ROOT);
        for k in [1, 2, 3] {
            p.on_insert(k, &leaf(0.0));
        }
        p.on_hit(1, &leaf(0.0));
        p.on_hit(100, &ROOT);
        p.on_hit(9, &leaf(0.0)); // not resident: ignored
        let order: Vec<_> = std::iter::from_fn(|| p.victim(&Aabb::EMPTY)).collect();
        assert_eq!(order, [2, 3, 1]);
    }

    #[test]
    fn replay_gives_each_lookahead_where_it_came() {
        // Capacity 2 plus the root: pages 1 (ahead) and 2 (behind) are loaded, then the
        // walk predicts east; the miss on 3 must evict 2, so the return to 1 hits.
        let at = |page, hint, search| Access {
            page,
            hint,
            query: Aabb::EMPTY,
            search,
        };
        let t = Trace {
            accesses: vec![
                at(100, ROOT, 0),
                at(1, leaf(50.0), 0),
                at(2, leaf(-50.0), 0),
                at(100, ROOT, 1),
                at(3, leaf(20.0), 1),
                at(100, ROOT, 2),
                at(1, leaf(50.0), 2),
            ],
            lookaheads: vec![TracedLookahead {
                at: 3,
                search: 1,
                ahead: east(),
            }],
        };
        let with = t.replay(Box::new(PathPolicy::default()), 3);
        assert_eq!((with.hits, with.misses), (3, 4));
        let blind = Trace {
            lookaheads: vec![],
            ..t.clone()
        };
        let lru_like = blind.replay(Box::new(PathPolicy::default()), 3);
        assert_eq!((lru_like.hits, lru_like.misses), (2, 5), "1 was evicted");
        assert!(with.hits <= crate::cache::belady_replay(&t, 3).hits);
    }
}
