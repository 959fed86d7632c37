//! glTF 2.0 import (the `gltf` crate): `.gltf` with its buffers beside it or in data
//! URIs, and `.glb`. The nodes of the file's scene are walked with their transforms;
//! each node with a mesh becomes one object (or, by [`GltfObjects::PerMesh`], every
//! placement of one mesh does), its primitives' triangles in world coordinates. glTF is
//! y-up in metres, as the engine is, so nothing is turned or scaled.
//!
//! Only triangle lists are taken: a primitive of points, lines, strips or fans is an
//! error naming it, as is a sparse accessor, a buffer shorter than the file says, an
//! accessor reaching past its buffer view, an index past its vertices, or a position
//! that is not a finite number. Materials, textures, skins and animations are not read.

use std::collections::HashMap;
use std::path::Path;

use base64::Engine;
use glam::{Mat3, Mat4, Vec3};
use gltf::accessor::{Accessor, DataType, Dimensions};
use gltf::mesh::Mode;

use super::obj::vertex_normals;
use crate::error::{Error, Result};
use crate::scene::Mesh;

/// What one object of a glTF file is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum GltfObjects {
    /// Each node with a mesh (one placement of it).
    #[default]
    PerNode,
    /// Each mesh, every node that places it together.
    PerMesh,
}

impl std::str::FromStr for GltfObjects {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<GltfObjects, String> {
        match s {
            "node" => Ok(GltfObjects::PerNode),
            "mesh" => Ok(GltfObjects::PerMesh),
            other => Err(format!(
                "'{other}': a glTF object is per 'node' or per 'mesh'"
            )),
        }
    }
}

/// Loads the objects of a glTF file (`.gltf` or `.glb`) as `(name, mesh)` pairs, in the
/// order the scene's nodes are first met. A file without a triangle, or any malformed
/// content, is an error naming it.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("one.gltf");
/// // One triangle, its buffer in a data URI, placed 10 m up by its node.
/// let mut bytes = Vec::new();
/// for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0] {
///     bytes.extend(v.to_le_bytes());
/// }
/// use base64::Engine;
/// let data = base64::engine::general_purpose::STANDARD.encode(&bytes);
/// let json = format!(r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
///   "nodes":[{{"name":"tri","mesh":0,"translation":[0,10,0]}}],
///   "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
///   "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",
///     "min":[0,0,0],"max":[1,0,1]}}],
///   "bufferViews":[{{"buffer":0,"byteLength":36}}],
///   "buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{data}"}}]}}"#);
/// std::fs::write(&path, json).unwrap();
/// let objects = flaneur::scene::load_gltf(&path, flaneur::scene::GltfObjects::PerNode)?;
/// assert_eq!(objects.len(), 1);
/// assert_eq!(objects[0].0, "tri");
/// assert_eq!(objects[0].1.positions[1], [1.0, 10.0, 0.0]);
/// # Ok(()) }
/// ```
pub fn load_gltf(path: &Path, objects: GltfObjects) -> Result<Vec<(String, Mesh)>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    gltf_from_bytes(&bytes, path.parent(), objects).map_err(|what| Error::BadInput {
        path: path.to_path_buf(),
        what,
    })
}

/// [`load_gltf`] of the file's bytes; `dir` is where its external buffers are (none:
/// refused). The error says what is wrong.
pub(crate) fn gltf_from_bytes(
    bytes: &[u8],
    dir: Option<&Path>,
    objects: GltfObjects,
) -> std::result::Result<Vec<(String, Mesh)>, String> {
    let malformed = |e: gltf::Error| format!("malformed glTF: {e}");
    // gltf 1.4 takes 12 from a GLB's length before it compares (an overflow, found by
    // the gltf fuzz target): a length under the header's own is refused first.
    if let Some(len) = bytes.strip_prefix(b"glTF").and_then(|b| b.get(4..8)) {
        let len = u32::from_le_bytes([len[0], len[1], len[2], len[3]]);
        if len < 12 {
            return Err(format!(
                "malformed glTF: a GLB of {len} bytes, less than its 12-byte header"
            ));
        }
    }
    let file = gltf::Gltf::from_slice_without_validation(bytes).map_err(malformed)?;
    // gltf-json 1.4's validation indexes the accessors by each POSITION attribute before
    // it checks the index (a panic, found by the gltf fuzz target): checked first here.
    check_position_indices(file.document.as_json())?;
    let document = gltf::Document::from_json(file.document.into_json()).map_err(malformed)?;
    let buffers = buffers(&document, file.blob, dir)?;
    let doc = &document;
    let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => return Err("no scene to import".into()),
    };
    let mut out: Vec<(String, Mesh)> = Vec::new();
    let mut slot: HashMap<usize, usize> = HashMap::new();
    // A walk of the node tree; the validator refuses cycles, and the bound stops one
    // whatever it missed.
    let mut stack: Vec<(gltf::Node, Mat4)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, Mat4::IDENTITY))
        .collect();
    let mut visits = 0usize;
    while let Some((node, parent)) = stack.pop() {
        visits += 1;
        if visits > doc.nodes().len() * 4 + 16 {
            return Err("the node tree loops or shares nodes beyond reason".into());
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            let (key, name) = match objects {
                GltfObjects::PerNode => (node.index(), name_of(node.name(), "node", node.index())),
                GltfObjects::PerMesh => (mesh.index(), name_of(mesh.name(), "mesh", mesh.index())),
            };
            let at = *slot.entry(key).or_insert_with(|| {
                out.push((name, Mesh::default()));
                out.len() - 1
            });
            for primitive in mesh.primitives() {
                add_primitive(&mut out[at].1, &primitive, world, &buffers).map_err(|e| {
                    format!(
                        "mesh {} primitive {}: {e}",
                        name_of(mesh.name(), "", mesh.index()),
                        primitive.index()
                    )
                })?;
            }
        }
        for child in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child, world));
        }
    }
    out.retain(|(_, m)| !m.indices.is_empty());
    if out.is_empty() {
        return Err("no triangles in its scene".into());
    }
    for (_, mesh) in &mut out {
        if mesh.normals.len() != mesh.positions.len() {
            mesh.normals = vertex_normals(&mesh.positions, &mesh.indices);
        }
    }
    Ok(out)
}

fn name_of(name: Option<&str>, kind: &str, index: usize) -> String {
    match (name, kind) {
        (Some(n), _) if !n.is_empty() => n.to_string(),
        (_, "") => format!("{index}"),
        _ => format!("{kind} {index}"),
    }
}

/// That every primitive's POSITION attribute names an accessor the file has.
fn check_position_indices(json: &gltf::json::Root) -> std::result::Result<(), String> {
    use gltf::json::validation::Checked;
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = Checked::Valid(gltf::json::mesh::Semantic::Positions);
            if let Some(a) = primitive.attributes.get(&position) {
                if a.value() >= json.accessors.len() {
                    return Err(format!(
                        "malformed glTF: mesh {m} primitive {p}: POSITION is accessor {}, of {}",
                        a.value(),
                        json.accessors.len()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Every buffer's bytes: the GLB's binary chunk (`blob`), a data URI's, or a file beside
/// the glTF.
fn buffers(
    doc: &gltf::Document,
    blob: Option<Vec<u8>>,
    dir: Option<&Path>,
) -> std::result::Result<Vec<Vec<u8>>, String> {
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => blob.clone().ok_or(format!(
                "buffer {i} is the GLB's binary chunk, which it lacks"
            ))?,
            gltf::buffer::Source::Uri(uri) => {
                read_uri(uri, dir).map_err(|e| format!("buffer {i}: {e}"))?
            }
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {i} holds {} bytes, the file says {}",
                data.len(),
                buffer.length()
            ));
        }
        out.push(data);
    }
    Ok(out)
}

fn read_uri(uri: &str, dir: Option<&Path>) -> std::result::Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, data) = rest
            .split_once(";base64,")
            .ok_or("a data URI that is not base64")?;
        return base64::engine::general_purpose::STANDARD
            .decode(data)
            .map_err(|e| format!("a data URI's base64: {e}"));
    }
    if uri.contains("://") || uri.starts_with('/') {
        return Err(format!("'{uri}' is not a path relative to the file"));
    }
    let name = percent_encoding::percent_decode_str(uri)
        .decode_utf8()
        .map_err(|e| format!("'{uri}': {e}"))?;
    let dir = dir.ok_or(format!("'{uri}': no folder to find it in"))?;
    let path = dir.join(name.as_ref());
    std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))
}

/// Adds `primitive`'s triangles, placed by `world`, to `mesh`.
fn add_primitive(
    mesh: &mut Mesh,
    primitive: &gltf::Primitive,
    world: Mat4,
    buffers: &[Vec<u8>],
) -> std::result::Result<(), String> {
    if primitive.mode() != Mode::Triangles {
        return Err(format!(
            "{:?} primitives are not imported: only triangle lists",
            primitive.mode()
        ));
    }
    let position = primitive
        .get(&gltf::Semantic::Positions)
        .ok_or("no POSITION attribute")?;
    check_accessor(&position, buffers, Dimensions::Vec3, &[DataType::F32])?;
    let normal = primitive.get(&gltf::Semantic::Normals);
    if let Some(n) = &normal {
        check_accessor(n, buffers, Dimensions::Vec3, &[DataType::F32])?;
    }
    if let Some(i) = primitive.indices() {
        check_accessor(
            &i,
            buffers,
            Dimensions::Scalar,
            &[DataType::U8, DataType::U16, DataType::U32],
        )?;
    }
    let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let positions: Vec<[f32; 3]> = reader
        .read_positions()
        .ok_or("POSITION cannot be read")?
        .map(|p| world.transform_point3(Vec3::from(p)).to_array())
        .collect();
    if let Some(k) = positions
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite()))
    {
        return Err(format!("vertex {k} is not a finite point once placed"));
    }
    let count = positions.len() as u32;
    let indices: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..count).collect(),
    };
    if !indices.len().is_multiple_of(3) {
        return Err(format!("{} indices, not whole triangles", indices.len()));
    }
    if let Some(&i) = indices.iter().find(|&&i| i >= count) {
        return Err(format!("index {i}, past its {count} vertices"));
    }
    let base = mesh.positions.len() as u32;
    // A mirroring placement turns the triangles inside out: wind them back.
    let mirrored = world.determinant() < 0.0;
    for t in indices.chunks_exact(3) {
        let t = if mirrored {
            [t[0], t[2], t[1]]
        } else {
            [t[0], t[1], t[2]]
        };
        mesh.indices.extend(t.map(|i| base + i));
    }
    // Normals only where every primitive of the object has them.
    let normals: Option<Vec<[f32; 3]>> = normal.and_then(|_| reader.read_normals()).map(|n| {
        let turn = Mat3::from_mat4(world).inverse().transpose();
        n.map(|v| (turn * Vec3::from(v)).normalize_or_zero().to_array())
            .collect()
    });
    let whole = mesh.normals.len() == mesh.positions.len();
    match normals {
        Some(n) if whole && n.len() == positions.len() => mesh.normals.extend(n),
        _ => mesh.normals.clear(),
    }
    mesh.positions.extend(positions);
    Ok(())
}

/// Checks that `a` is what it must be (its shape and a component type of `types`), not
/// sparse, and that its bytes lie inside its buffer view and the view inside its buffer.
fn check_accessor(
    a: &Accessor,
    buffers: &[Vec<u8>],
    dims: Dimensions,
    types: &[DataType],
) -> std::result::Result<(), String> {
    let what = format!("accessor {}", a.index());
    if a.dimensions() != dims || !types.contains(&a.data_type()) {
        return Err(format!(
            "{what} is {:?} of {:?}, not {dims:?} of {types:?}",
            a.dimensions(),
            a.data_type()
        ));
    }
    if a.sparse().is_some() {
        return Err(format!("{what} is sparse, which is not imported"));
    }
    let view = a.view().ok_or(format!("{what} has no buffer view"))?;
    let buffer = buffers
        .get(view.buffer().index())
        .ok_or(format!("{what}: no buffer {}", view.buffer().index()))?;
    let view_end = view.offset().checked_add(view.length());
    if view_end.is_none_or(|end| end > buffer.len()) {
        return Err(format!(
            "{what}: its buffer view {} reaches past its buffer",
            view.index()
        ));
    }
    let size = a.size();
    let stride = view.stride().unwrap_or(size);
    if a.count() == 0 || stride < size {
        return Err(format!(
            "{what}: {} elements {stride} bytes apart",
            a.count()
        ));
    }
    let end = (a.count() - 1)
        .checked_mul(stride)
        .and_then(|s| s.checked_add(a.offset()))
        .and_then(|s| s.checked_add(size));
    if end.is_none_or(|end| end > view.length()) {
        return Err(format!(
            "{what} reaches past its buffer view {}",
            view.index()
        ));
    }
    Ok(())
}
