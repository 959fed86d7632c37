//! The replacement-policy trait of the index cache, and the hint every access carries.
//!
//! A policy keeps only keys and what the hints told it; the pool (`pool.rs`) keeps the
//! bytes. Every access passes its own hint (level, tree height, MBR, DoV), so no policy
//! needs global knowledge of the tree or of the visibility data. The policies:
//! - [`Lru`] (`lru.rs`): least recently used, the baseline of Shou 2002 §4.4 and §5.8;
//! - [`DpLru`] (`dplru.rs`): distance-priority LRU, Shou 2002 §4.2.4;
//! - [`Dov`], [`DovTime`] (`dov.rs`): the DoV and DoV-Time policies, Shou 2002 §5.7;
//! - [`PathPolicy`] (`path.rs`, ours): evicts the node the walk's predicted next
//!   searches need last, from the [`Lookahead`] the walk gives it.
//!
//! Belady's offline optimum is not a `Policy` (it needs the future): see `belady.rs`.

mod dov;
mod dplru;
mod lru;
mod path;

pub use dov::{Dov, DovTime, DEFAULT_KAPPA};
pub use dplru::DpLru;
pub use lru::Lru;
pub use path::PathPolicy;

use super::Lookahead;
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::store::NodeHint;

/// What the requester knows about a page when it asks for it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hint {
    /// Level in the R-tree: 0 for a leaf, `height - 1` for the root.
    pub level: u16,
    /// Levels of the tree; 0 when unknown (then no page counts as the root).
    pub height: u32,
    /// The page's MBR; `Aabb::EMPTY` when unknown (then its block distance is 0).
    pub mbr: Aabb,
    /// The page's degree of visibility for the current cell; 0 when unknown.
    pub dov: f32,
}

impl Hint {
    /// A hint that says nothing: a leaf-level page of unknown tree, MBR and DoV.
    pub const UNKNOWN: Hint = Hint {
        level: 0,
        height: 0,
        mbr: Aabb::EMPTY,
        dov: 0.0,
    };

    /// The hint of an R-tree node as the traversal describes it (DoV unknown).
    pub fn node(h: &NodeHint) -> Hint {
        Hint {
            level: h.level,
            height: h.height,
            mbr: h.mbr,
            dov: 0.0,
        }
    }

    /// True for the root of its tree (`level == height - 1`).
    pub fn is_root(&self) -> bool {
        self.height > 0 && u32::from(self.level) + 1 == self.height
    }
}

/// A replacement policy over page keys. The pool calls `on_hit` for every access that
/// finds its page resident, `on_insert` after a missed page was loaded and admitted,
/// `victim` when it needs room, `on_remove` when it drops an entry itself (`clear`),
/// `end_search` after each search, and `look_ahead` whenever the walk predicts its next
/// searches. `victim` forgets the key it returns.
///
/// A policy keeps only keys and what the hints told it; the pool keeps the bytes. Every
/// access passes its own [`Hint`] (level, tree height, MBR, DoV), so no policy needs
/// global knowledge of the tree or of the visibility data. Belady's offline optimum is
/// not a `Policy`, since it needs the future: see [`belady_replay`](super::belady_replay).
///
/// ```
/// use flaneur::cache::{Hint, Lru, Policy};
/// use flaneur::geom::Aabb;
/// let mut p = Lru::default();
/// p.on_insert(1, &Hint::UNKNOWN);
/// p.on_insert(2, &Hint::UNKNOWN);
/// p.on_hit(1, &Hint::UNKNOWN);
/// assert_eq!(p.victim(&Aabb::EMPTY), Some(2));
/// assert_eq!(p.len(), 1);
/// ```
pub trait Policy: Send {
    /// A short name for reports: the name [`policy_by_name`] takes, with any
    /// non-default parameters.
    fn name(&self) -> String;
    /// `key` was requested and is resident.
    fn on_hit(&mut self, key: u64, hint: &Hint);
    /// `key` was loaded after a miss and is now resident.
    fn on_insert(&mut self, key: u64, hint: &Hint);
    /// Chooses an entry to evict, for a search of `query` (`Aabb::EMPTY` outside a
    /// search), and forgets it. `None` when nothing may be evicted.
    fn victim(&mut self, query: &Aabb) -> Option<u64>;
    /// `key` was dropped by the pool for a reason of its own.
    fn on_remove(&mut self, key: u64);
    /// A search is over.
    fn end_search(&mut self) {}
    /// The walk's prediction of its next searches, replacing the one before; a policy
    /// that does not look ahead ignores it (the default).
    fn look_ahead(&mut self, _ahead: &Lookahead) {}
    /// Entries the policy tracks (resident pages).
    fn len(&self) -> usize;
    /// Whether the policy tracks no entry.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl std::fmt::Debug for dyn Policy + '_ {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({} entries)", self.name(), self.len())
    }
}

/// The online policies by name, with their defaults: `"lru"`, `"dplru"` (α = β = γ =
/// 1/3), `"dov"`, `"dovtime"` (κ = [`DEFAULT_KAPPA`]), `"path"` ([`PathPolicy`]).
///
/// ```
/// let p = flaneur::cache::policy_by_name("dplru").unwrap();
/// assert_eq!(p.name(), "dplru");
/// assert!(flaneur::cache::policy_by_name("fifo").is_err());
/// ```
pub fn policy_by_name(name: &str) -> Result<Box<dyn Policy>> {
    match name {
        "lru" => Ok(Box::new(Lru::default())),
        "dplru" => Ok(Box::new(DpLru::default())),
        "dov" => Ok(Box::new(Dov::default())),
        "dovtime" => Ok(Box::new(DovTime::default())),
        "path" => Ok(Box::new(PathPolicy::default())),
        other => Err(Error::Invalid(format!(
            "unknown cache policy {other:?} (expected one of: {})",
            POLICY_NAMES.join(", ")
        ))),
    }
}

/// Every name [`policy_by_name`] accepts.
pub const POLICY_NAMES: [&str; 5] = ["lru", "dplru", "dov", "dovtime", "path"];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_makes_its_policy() {
        for n in POLICY_NAMES {
            let p = policy_by_name(n).unwrap();
            assert_eq!(p.name(), n);
            assert!(p.is_empty());
        }
        let e = policy_by_name("LRU2").unwrap_err().to_string();
        assert!(e.contains("LRU2") && e.contains("dplru"), "{e}");
    }

    #[test]
    fn root_detection() {
        let h = |level, height| Hint {
            level,
            height,
            ..Hint::UNKNOWN
        };
        assert!(h(2, 3).is_root());
        assert!(!h(1, 3).is_root());
        assert!(!h(0, 0).is_root(), "unknown height: no root");
        assert!(h(0, 1).is_root(), "a one-level tree's leaf is its root");
    }
}
