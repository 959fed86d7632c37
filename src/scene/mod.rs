//! Objects and meshes as the engine reads them: the scene file (citygen's stream of
//! objects), OBJ import, and the mesh codec of the database.

mod mesh_codec;
mod obj;

pub use citygen::{Mesh, ObjectKind, SceneObject, SceneReader};
pub use mesh_codec::{decode_mesh, encode_mesh};
pub use obj::load_obj;

/// The kind byte of objects that did not come from citygen (OBJ imports).
pub const KIND_IMPORTED: u8 = 255;
