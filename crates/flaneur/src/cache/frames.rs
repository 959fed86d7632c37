//! The cache's bookkeeping without its bytes: which pages are resident, the policy that
//! picks victims, and the counts (Shou 2002 §4.2.4). The live pool (`pool.rs`) keeps
//! payloads in it and a trace replay (`trace.rs`) keeps nothing, so both count hits,
//! misses and evictions by the same code.

use std::collections::HashMap;

use super::policy::{Hint, Policy};
use super::stats::CacheStats;
use super::Lookahead;
use crate::geom::Aabb;

/// Resident entries, their policy and counts: the pool's logic, with values `V`
/// (payloads in the pool, nothing in a replay).
pub(super) struct Frames<V> {
    policy: Box<dyn Policy>,
    capacity: usize,
    map: HashMap<u64, V>,
    stats: CacheStats,
    /// The box of the current search (DIST is measured against it).
    query: Aabb,
    /// Searches ended so far.
    searches: u64,
}

impl<V> Frames<V> {
    pub(super) fn new(policy: Box<dyn Policy>, capacity: usize) -> Frames<V> {
        Frames {
            policy,
            capacity,
            map: HashMap::with_capacity(capacity.min(1 << 16)),
            stats: CacheStats::default(),
            query: Aabb::EMPTY,
            searches: 0,
        }
    }

    pub(super) fn peek(&self, key: u64) -> Option<&V> {
        self.map.get(&key)
    }

    /// An access served from the cache.
    pub(super) fn hit(&mut self, key: u64, hint: &Hint) {
        self.stats.hits += 1;
        self.policy.on_hit(key, hint);
    }

    /// An access that was loaded from below: makes room, then admits the page with
    /// the value `make` builds (from an evicted value, to reuse its allocation).
    pub(super) fn install(&mut self, key: u64, hint: &Hint, make: impl FnOnce(Option<V>) -> V) {
        self.stats.misses += 1;
        if self.map.contains_key(&key) {
            // Another thread loaded it meanwhile.
            self.policy.on_hit(key, hint);
            return;
        }
        let mut spare = None;
        // A policy that names keys the pool does not hold gets as many tries as there
        // are entries; then the page is served uncached rather than looping.
        let mut tries = self.map.len() + 1;
        while self.map.len() >= self.capacity {
            if tries == 0 {
                return;
            }
            tries -= 1;
            let Some(victim) = self.policy.victim(&self.query) else {
                return;
            };
            if let Some(v) = self.map.remove(&victim) {
                self.stats.evictions += 1;
                spare = Some(v);
            }
        }
        self.map.insert(key, make(spare));
        self.policy.on_insert(key, hint);
    }

    pub(super) fn begin_search(&mut self, query: &Aabb) {
        self.query = *query;
    }

    pub(super) fn end_search(&mut self) {
        self.searches += 1;
        self.policy.end_search();
    }

    pub(super) fn look_ahead(&mut self, ahead: &Lookahead) {
        self.policy.look_ahead(ahead);
    }

    pub(super) fn searches(&self) -> u64 {
        self.searches
    }

    pub(super) fn query(&self) -> Aabb {
        self.query
    }

    pub(super) fn stats(&self) -> CacheStats {
        self.stats
    }

    pub(super) fn reset_stats(&mut self) {
        self.stats = CacheStats::default();
    }

    pub(super) fn policy_name(&self) -> String {
        self.policy.name()
    }

    pub(super) fn len(&self) -> usize {
        self.map.len()
    }

    pub(super) fn clear(&mut self) {
        for key in self.map.keys() {
            self.policy.on_remove(*key);
        }
        self.map.clear();
    }
}
