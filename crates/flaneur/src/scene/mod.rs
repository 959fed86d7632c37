//! Objects and meshes as the engine reads them: the scene types and the scene file
//! (the `flaneur-scene` crate, shared with the generator), OBJ and glTF import, and the mesh
//! codec of the database.

mod axes;
mod gltf;
mod mesh_codec;
mod obj;

pub use axes::{place, plainly_z_up, ObjAxes, Placed, Up};
pub use flaneur_scene::{
    bunny, write_mesh_obj, Mesh, ObjectKind, RecordPos, SceneError, SceneObject, SceneReader,
    SceneSummary, SceneWriter,
};
pub(crate) use gltf::gltf_from_bytes;
pub use gltf::{load_gltf, GltfObjects};
pub(crate) use mesh_codec::{decode_mesh, encode_mesh};
pub use obj::load_obj;

/// The kind byte of objects that did not come from citygen (OBJ and glTF imports).
pub const KIND_IMPORTED: u8 = 255;
