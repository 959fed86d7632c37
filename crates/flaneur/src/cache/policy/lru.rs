//! Least recently used — the baseline of Shou 2002 §4.4 (Fig. 4.18) and §5.8
//! (Fig. 5.15–5.20). A thin wrapper over the `lru` crate's list, used unbounded: the
//! pool decides when to evict, the list only keeps the order. Hints are ignored.

use ::lru::LruCache;

use super::{Hint, Policy};
use crate::geom::Aabb;

/// Evicts the entry whose last access is oldest.
pub struct Lru {
    order: LruCache<u64, ()>,
}

impl Default for Lru {
    fn default() -> Lru {
        Lru {
            order: LruCache::unbounded(),
        }
    }
}

impl std::fmt::Debug for Lru {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Lru")
            .field("len", &self.order.len())
            .finish()
    }
}

impl Policy for Lru {
    fn name(&self) -> String {
        "lru".into()
    }

    fn on_hit(&mut self, key: u64, _hint: &Hint) {
        self.order.promote(&key);
    }

    fn on_insert(&mut self, key: u64, _hint: &Hint) {
        self.order.put(key, ());
    }

    fn victim(&mut self, _query: &Aabb) -> Option<u64> {
        self.order.pop_lru().map(|(k, ())| k)
    }

    fn on_remove(&mut self, key: u64) {
        self.order.pop(&key);
    }

    fn len(&self) -> usize {
        self.order.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evicts_in_order_of_last_use() {
        let mut p = Lru::default();
        let h = Hint::UNKNOWN;
        for k in [1, 2, 3, 4] {
            p.on_insert(k, &h);
        }
        p.on_hit(2, &h);
        p.on_hit(1, &h);
        p.on_remove(3);
        p.on_hit(99, &h); // not resident: ignored
        assert_eq!(p.len(), 3);
        let order: Vec<_> = std::iter::from_fn(|| p.victim(&Aabb::EMPTY)).collect();
        assert_eq!(order, [4, 2, 1]);
        assert!(p.is_empty());
    }
}
