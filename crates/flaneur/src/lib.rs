//! flaneur — an urban walkthrough engine built around disk-resident spatial indexes.
//!
//! A city too large for memory lives in one database file of fixed-size pages. The
//! paged R-tree over the objects' boxes answers range queries (the thesis's BOX) and
//! complement queries (CSearch, Shou 2002 §4.2.2), reading only the pages it needs and
//! counting every one of them.
//!
//! ```
//! # fn main() -> flaneur::Result<()> {
//! use flaneur::{geom::Aabb, BuildOptions, Database};
//! let dir = tempfile::tempdir().unwrap();
//! let (scene, db_path) = (dir.path().join("city.scene"), dir.path().join("city.flaneur"));
//! let city = citygen::CityConfig { objects: 300, ..Default::default() };
//! citygen::write_city(&city, &scene)?;
//! flaneur::build_from_scene(&scene, &db_path, &BuildOptions::default())?;
//!
//! let db = Database::open(&db_path)?;
//! let before: Aabb = "0,0,0,120,50,120".parse()?;
//! let now: Aabb = "40,0,0,160,50,120".parse()?;
//! let seen = db.range(&before)?;
//! let new = db.csearch(&now, &[before])?; // only what `now` adds
//! assert!(new.objects.iter().all(|o| !o.bounds.overlaps(&before)));
//! println!("{} new objects, {} pages read", new.objects.len(), new.pages.len());
//! # assert!(seen.objects.len() > 0);
//! # Ok(()) }
//! ```

// Every type a public signature names must have a public path, so that a user can name
// it: a type of an internal module left out of the re-exports is a warning.
#![warn(unnameable_types)]
// Every public item is documented: the engine is a library first.
#![warn(missing_docs)]

pub mod build;
pub mod cache;
mod catalog;
pub mod check;
pub mod database;
pub mod error;
/// The bodies of the fuzz targets (`fuzz/`), one per decoder of untrusted file bytes,
/// shared with the replay of their corpora. Not part of the API.
#[doc(hidden)]
pub mod fuzzing;
pub mod geom;
pub mod hdov;
pub mod lod;
mod memory;
mod names;
pub mod path;
pub mod prefetch;
pub mod progress;
pub mod rtree;
pub mod scene;
pub mod store;
pub mod visibility;
pub mod walk;
mod write_order;

pub use build::{
    build_from_obj, build_from_obj_with_progress, build_from_scene, build_from_scene_with_progress,
    build_visibility_shard, merge_visibility_shards, model_format, BuildOptions, BuildSummary,
};
pub use database::{BytesPerTriangle, Database, DatabaseInfo, HdovInfo};
pub use error::{Error, Result};
/// The vector math crate of the engine's public types ([`geom::Aabb`], [`geom::Camera`],
/// meshes), re-exported so that a program names the same version the engine was built
/// with: `flaneur::glam::Vec3`, with no `glam` line of its own to keep in step.
pub use glam;
pub use rtree::{History, ObjectEntry, QueryResult};
pub use store::Backend;
pub use write_order::WriteOrder;

/// The README's examples, compiled as doc tests so they stay true.
#[doc = include_str!("../../../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
