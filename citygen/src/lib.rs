//! citygen — a deterministic procedural city generator for flaneur.
//!
//! The engine's experiments need cities of any size, up to a million objects and more,
//! that are the same on every machine and every run; this crate makes them. A city is a
//! street grid of square blocks of building lots. Each lot holds a building — a house, a
//! terrace or a setback tower with recessed windows, ledges and roofs (a few hundred to
//! about 2,000 triangles, like the base models of Shou's thesis) — or, for a small share
//! of lots, a high-detail landmark (a procedural sculpture or the Stanford bunny,
//! 50,000–200,000 triangles).
//!
//! Every object is a pure function of the [`CityConfig`] and its id ([`object`]), so
//! [`generate`] streams a city in bounded memory on all cores, and [`write_city`] stores
//! it in a checksummed scene file that [`SceneReader`] streams back.
//!
//! ```
//! let config = citygen::CityConfig { objects: 16, seed: 3, landmarks: 0.0, ..Default::default() };
//! let mut triangles = 0;
//! citygen::generate(&config, |o| {
//!     triangles += o.mesh.triangle_count();
//!     Ok::<(), citygen::SceneError>(())
//! })
//! .unwrap();
//! assert!(triangles > 16 * 200);
//! ```

mod archetypes;
mod builder;
mod bunny_landmark;
mod config;
mod generate;
mod layout;
mod obj_export;
mod recipe;
mod sculpture;

pub use config::{CityConfig, MAX_OBJECTS};
pub use generate::{generate, write_city, write_city_with_progress};
pub use obj_export::export_obj;
pub use recipe::{object, sample_building};
// The scene types are the engine's (`flaneur-scene`); they are named here too so that a
// generator user has one crate to import.
pub use flaneur_scene::{
    bunny, dequantize_normal, quantize_snorm8, write_mesh_obj, Mesh, ObjectKind, SceneError,
    SceneObject, SceneReader, SceneSummary, SceneWriter, MAX_INDICES, MAX_VERTICES,
};
