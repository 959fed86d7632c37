//! The index cache: a buffer pool of node pages over the store, with replacement
//! policies behind one trait — Shou 2002 §4.2.4 (distance-priority LRU, the index cache
//! of the REVIEW system) and §5.7 (the DoV and DoV-Time node caches of the HDoV-tree).
//!
//! One idea per file:
//! - `pool.rs`: [`BufferPool`], the cache itself, a [`PageSource`](crate::store::PageSource)
//!   the R-tree reads through;
//! - `frames.rs`: the resident set, policy and counts, shared by the pool and a
//!   trace's replay;
//! - `policy/`: the [`Policy`] trait and [`Lru`], [`DpLru`], [`Dov`], [`DovTime`],
//!   [`PathPolicy`];
//! - `lookahead.rs`: [`Lookahead`], a walk's prediction of its next searches, which
//!   the path policy evicts by;
//! - `distance.rs`: [`block_distance`], the DIST of §4.2.4;
//! - `trace.rs`: [`Trace`], recorded accesses, their CSV file and their replay;
//! - `belady.rs`: [`belady_replay`], Belady's optimal offline replacement, the ceiling of
//!   every policy;
//! - `stats.rs`: [`CacheStats`], counted once here and only reported elsewhere.
//!
//! Departures from the thesis, each named in its file: the pool makes room before it
//! admits a page and serves a page uncached when nothing is evictable; DPLRU resets QN
//! on a hit; DoV-Time counts time in searches.
//!
//! ```
//! # fn main() -> flaneur::Result<()> {
//! use flaneur::cache::{belady_replay, policy_by_name, BufferPool};
//! use flaneur::{rtree::History, BuildOptions, Database};
//! let dir = tempfile::tempdir().unwrap();
//! let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
//! citygen::write_city(&citygen::CityConfig { objects: 300, ..Default::default() }, &scene)?;
//! flaneur::build_from_scene(&scene, &path, &BuildOptions { page_size: 1024, ..Default::default() })?;
//! let db = Database::open(&path)?;
//!
//! let pool = BufferPool::new(db.store(), 8 * 1024, policy_by_name("dplru")?)?;
//! pool.set_trace(true);
//! let cell: flaneur::geom::Aabb = "0,0,0,120,50,120".parse()?;
//! let direct = db.range(&cell)?;
//! let cached = db.tree().range(&pool, &cell)?;
//! assert_eq!(cached.ids(), direct.ids());
//! let again = db.tree().range(&pool, &cell)?;
//! assert!(pool.stats().hits > 0);
//! let trace = pool.take_trace();
//! assert!(trace.replay(policy_by_name("dplru")?, 8).hit_rate() <= belady_replay(&trace, 8).hit_rate());
//! # let _ = again; Ok(()) }
//! ```

mod belady;
mod distance;
mod frames;
mod lookahead;
mod policy;
mod pool;
mod stats;
mod trace;

pub use belady::belady_replay;
pub use distance::block_distance;
pub use lookahead::Lookahead;
pub use policy::{
    policy_by_name, Dov, DovTime, DpLru, Hint, Lru, PathPolicy, Policy, DEFAULT_KAPPA, POLICY_NAMES,
};
pub use pool::BufferPool;
pub use stats::CacheStats;
pub use trace::{Access, Trace, TracedLookahead};
