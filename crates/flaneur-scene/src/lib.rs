//! The scene as flaneur's engine and its generator share it: the triangle [`Mesh`], the
//! [`SceneObject`] (an id, a kind and a mesh), and the scene file that carries a city from
//! a generator or an importer to `flaneur build`, streamed and checksummed record by
//! record ([`SceneWriter`], [`SceneReader`]).
//!
//! It is a crate of its own so that the generator (`citygen`) and the engine (`flaneur`,
//! which re-exports it as `flaneur::scene`) depend on one set of types without depending
//! on each other: the engine's tests generate cities, and the generator needs nothing of
//! the engine but these types.
//!
//! ```
//! use flaneur_scene::{bunny, Mesh};
//! let mut two = Mesh::default();
//! two.append(&bunny());
//! two.append(&bunny());
//! assert_eq!(two.triangle_count(), 2 * 3674);
//! ```

mod bunny;
mod error;
mod mesh;
mod obj_write;
mod object;
mod scene_file;

pub use bunny::bunny;
pub use error::SceneError;
pub use mesh::Mesh;
pub use obj_write::write_mesh_obj;
pub use object::{ObjectKind, SceneObject};
pub use scene_file::{
    dequantize_normal, quantize_snorm8, RecordPos, SceneReader, SceneSummary, SceneWriter,
    MAX_INDICES, MAX_VERTICES,
};
