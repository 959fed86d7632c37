//! The DoV and DoV-Time (DT) replacement policies — Shou 2002, §5.7.1 and §5.7.2.
//!
//! DoV (§5.7.1): entries are kept sorted by their degree of visibility and the one
//! with the smallest DoV is replaced. DT (§5.7.2): the key is f(DoV, T) = DoV + κ·T,
//! "T is the latest time at which the node was accessed", κ = 0.001 in the thesis's
//! experiments; the smallest f is replaced, so entries not accessed for a long time
//! lose their place however visible they once were.
//!
//! Our readings, where the thesis leaves it open:
//! - time T is counted in searches (visibility queries) since the policy was made: the
//!   thesis's experiments advance one query per step, and with κ = 0.001 an age of 1000
//!   queries then weighs as much as a DoV of 1;
//! - an entry's DoV is the one its latest access carried (the DoV of the node for the
//!   current cell), so both keys are refreshed on every hit;
//! - ties (equal keys) go to the least recently accessed entry.
//!
//! DoV is DT with κ = 0. With R-tree node pages, whose hints carry no DoV (0), both
//! degenerate to exactly LRU (equal DoVs, then recency decides).

use std::cmp::Ordering;
use std::collections::{BTreeSet, HashMap};

use super::{Hint, Policy};
use crate::error::{Error, Result};
use crate::geom::Aabb;

/// κ of the thesis's experiments (§5.7.2).
pub const DEFAULT_KAPPA: f64 = 0.001;

/// The sorted (key value, recency, page) list both policies keep.
#[derive(Clone, Debug, Default)]
struct Ranked {
    kappa: f64,
    order: BTreeSet<Rank>,
    rank: HashMap<u64, Rank>,
    searches: u64,
    tick: u64,
}

#[derive(Clone, Copy, Debug)]
struct Rank {
    f: f64,
    tick: u64,
    key: u64,
}

impl PartialEq for Rank {
    fn eq(&self, o: &Rank) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Rank {}
impl PartialOrd for Rank {
    fn partial_cmp(&self, o: &Rank) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Rank {
    fn cmp(&self, o: &Rank) -> Ordering {
        self.f
            .total_cmp(&o.f)
            .then(self.tick.cmp(&o.tick))
            .then(self.key.cmp(&o.key))
    }
}

impl Ranked {
    fn new(kappa: f64) -> Ranked {
        Ranked {
            kappa,
            ..Default::default()
        }
    }

    fn touch(&mut self, key: u64, hint: &Hint) {
        self.tick += 1;
        // A DoV that is not a number counts as unknown (0).
        let dov = if hint.dov.is_nan() {
            0.0
        } else {
            f64::from(hint.dov)
        };
        let r = Rank {
            f: dov + self.kappa * self.searches as f64,
            tick: self.tick,
            key,
        };
        if let Some(old) = self.rank.insert(key, r) {
            self.order.remove(&old);
        }
        self.order.insert(r);
    }

    fn hit(&mut self, key: u64, hint: &Hint) {
        if self.rank.contains_key(&key) {
            self.touch(key, hint);
        }
    }

    fn victim(&mut self) -> Option<u64> {
        let r = self.order.pop_first()?;
        self.rank.remove(&r.key);
        Some(r.key)
    }

    fn remove(&mut self, key: u64) {
        if let Some(r) = self.rank.remove(&key) {
            self.order.remove(&r);
        }
    }
}

/// Evicts the entry of smallest DoV (Shou 2002 §5.7.1).
///
/// ```
/// use flaneur::cache::{Dov, Hint, Policy};
/// use flaneur::geom::Aabb;
/// let mut p = Dov::default();
/// p.on_insert(1, &Hint { dov: 0.2, ..Hint::UNKNOWN });
/// p.on_insert(2, &Hint { dov: 0.01, ..Hint::UNKNOWN });
/// assert_eq!(p.victim(&Aabb::EMPTY), Some(2));
/// ```
#[derive(Clone, Debug)]
pub struct Dov(Ranked);

impl Default for Dov {
    fn default() -> Dov {
        Dov(Ranked::new(0.0))
    }
}

/// Evicts the entry of smallest DoV + κ·T, T the search number of its latest access
/// (Shou 2002 §5.7.2).
///
/// ```
/// use flaneur::cache::{DovTime, Hint, Policy};
/// use flaneur::geom::Aabb;
/// let mut p = DovTime::new(0.01).unwrap();
/// p.on_insert(1, &Hint { dov: 0.05, ..Hint::UNKNOWN }); // f = 0.05
/// for _ in 0..10 { p.end_search(); }
/// p.on_insert(2, &Hint { dov: 0.0, ..Hint::UNKNOWN }); // f = 0 + 0.01·10
/// assert_eq!(p.victim(&Aabb::EMPTY), Some(1)); // visible once, idle since
/// ```
#[derive(Clone, Debug)]
pub struct DovTime(Ranked);

impl Default for DovTime {
    fn default() -> DovTime {
        DovTime(Ranked::new(DEFAULT_KAPPA))
    }
}

impl DovTime {
    /// DT with weight κ per search of age; κ must be a finite number ≥ 0.
    pub fn new(kappa: f64) -> Result<DovTime> {
        if !(kappa.is_finite() && kappa >= 0.0) {
            return Err(Error::Invalid(format!(
                "DoV-Time κ = {kappa} must be a finite number ≥ 0"
            )));
        }
        Ok(DovTime(Ranked::new(kappa)))
    }

    /// κ, the weight given to each search of age.
    pub fn kappa(&self) -> f64 {
        self.0.kappa
    }
}

impl Dov {
    fn label(&self) -> String {
        "dov".into()
    }
}

impl DovTime {
    fn label(&self) -> String {
        if self.0.kappa == DEFAULT_KAPPA {
            "dovtime".into()
        } else {
            format!("dovtime({})", self.0.kappa)
        }
    }
}

macro_rules! ranked_policy {
    ($t:ty) => {
        impl Policy for $t {
            fn name(&self) -> String {
                self.label()
            }
            fn on_hit(&mut self, key: u64, hint: &Hint) {
                self.0.hit(key, hint)
            }
            fn on_insert(&mut self, key: u64, hint: &Hint) {
                self.0.touch(key, hint)
            }
            fn victim(&mut self, _query: &Aabb) -> Option<u64> {
                self.0.victim()
            }
            fn on_remove(&mut self, key: u64) {
                self.0.remove(key)
            }
            fn end_search(&mut self) {
                self.0.searches += 1;
            }
            fn len(&self) -> usize {
                self.0.rank.len()
            }
        }
    };
}

ranked_policy!(Dov);
ranked_policy!(DovTime);

#[cfg(test)]
mod tests {
    use super::*;

    fn dov(d: f32) -> Hint {
        Hint {
            dov: d,
            ..Hint::UNKNOWN
        }
    }

    #[test]
    fn dov_evicts_the_least_visible_then_the_oldest() {
        let mut p = Dov::default();
        p.on_insert(1, &dov(0.3));
        p.on_insert(2, &dov(0.1));
        p.on_insert(3, &dov(0.1));
        p.on_insert(4, &dov(0.5));
        p.on_hit(2, &dov(0.1)); // now newer than 3
        p.on_hit(4, &dov(0.05)); // its DoV for the new cell is small
        p.on_remove(1);
        let order: Vec<_> = std::iter::from_fn(|| p.victim(&Aabb::EMPTY)).collect();
        assert_eq!(order, [4, 3, 2]);
        assert!(p.is_empty());
    }

    #[test]
    fn dovtime_ages_entries_that_are_not_used() {
        let mut p = DovTime::new(0.1).unwrap();
        p.on_insert(1, &dov(0.5)); // f = 0.5
        p.on_insert(2, &dov(0.2)); // f = 0.2
        for _ in 0..4 {
            p.end_search();
        }
        p.on_hit(2, &dov(0.2)); // f = 0.2 + 0.4 = 0.6
        assert_eq!(p.victim(&Aabb::EMPTY), Some(1));
        // With κ = 0 it is the DoV policy.
        let mut p = DovTime::new(0.0).unwrap();
        p.on_insert(1, &dov(0.5));
        p.on_insert(2, &dov(0.2));
        p.end_search();
        p.on_hit(2, &dov(0.2));
        assert_eq!(p.victim(&Aabb::EMPTY), Some(2));
    }

    #[test]
    fn bad_kappa_and_nan_dov() {
        assert!(DovTime::new(-1.0).is_err());
        assert!(DovTime::new(f64::NAN).is_err());
        assert_eq!(DovTime::default().name(), "dovtime");
        assert_eq!(DovTime::new(0.5).unwrap().name(), "dovtime(0.5)");
        let mut p = Dov::default();
        p.on_insert(1, &dov(f32::NAN));
        p.on_insert(2, &dov(0.1));
        assert_eq!(p.victim(&Aabb::EMPTY), Some(1));
    }
}
