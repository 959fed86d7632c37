//! Objects and meshes as the engine reads them: the scene types and the scene file
//! (the `flaneur-scene` crate, shared with the generator), OBJ, glTF and OpenStreetMap import, and the mesh
//! codec of the database.

mod axes;
mod gltf;
pub(crate) mod mesh_codec;
mod obj;
mod osm;

pub use axes::{place, plainly_z_up, ObjAxes, Placed, Up};
pub use flaneur_scene::{
    bunny, write_mesh_obj, Mesh, ObjectKind, RecordPos, SceneError, SceneObject, SceneReader,
    SceneSummary, SceneWriter,
};
pub(crate) use gltf::gltf_from_bytes;
pub use gltf::{load_gltf, GltfObjects};
pub(crate) use mesh_codec::{
    decode_level_v2, decode_mesh, encode_levels_v2, encode_mesh, expand_frame, is_frame, squeeze,
    DictionaryUse, Framing,
};
pub use mesh_codec::{Dictionaries, MeshCodec, DEFAULT_ZSTD_LEVEL};
pub use obj::load_obj;
#[cfg(test)]
pub(crate) use osm::extruded;
pub(crate) use osm::osm_from_bytes;
pub use osm::{load_osm, OsmImport, OsmOptions, OsmReport, Repair, Skip};

/// The kind byte of objects that did not come from citygen (OBJ, glTF and OpenStreetMap imports).
pub const KIND_IMPORTED: u8 = 255;
