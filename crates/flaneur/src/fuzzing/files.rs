//! Whole files: a scene file, an OBJ file, a glTF file, a database. Each input but the
//! glTF (decoded from memory, as its import does once it has read the file) is written
//! to a scratch file and opened as the engine opens one.

use super::{with_file, MAX_ITEMS};
use crate::geom::Aabb;
use crate::scene::{load_obj, SceneReader};
use crate::store::{page, Header};
use crate::{Backend, Database};

/// A scene file, streamed through `SceneReader`: its objects in order, then the first
/// one again by its position.
pub fn scene_file(data: &[u8]) {
    with_file("fuzz.scene", data, |path| {
        let Ok(mut reader) = SceneReader::open(path) else {
            return;
        };
        let _ = reader.object_count();
        let first = reader.position();
        for object in reader.by_ref().take(MAX_ITEMS) {
            if object.is_err() {
                break;
            }
        }
        let _ = reader.read_at(first);
    });
}

/// An OBJ file through `load_obj`.
pub fn obj(data: &[u8]) {
    with_file("fuzz.obj", data, |path| {
        let _ = load_obj(path);
    });
}

/// A glTF file (JSON or GLB) through the import, as one object per node and per mesh:
/// no buffer beside it, so an external one is an error like any other.
pub fn gltf(data: &[u8]) {
    use crate::scene::GltfObjects;
    for objects in [GltfObjects::PerNode, GltfObjects::PerMesh] {
        let _ = crate::scene::gltf_from_bytes(data, None, objects);
    }
}

/// An OpenStreetMap PBF extract through the import: its three passes, the rings, the
/// heights and the extrusion of every building found.
pub fn osm_pbf(data: &[u8]) {
    // The import turns a panic inside the PBF reader into an error; the fuzzer's hook
    // would abort on it first and call the caught panic a finding.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let _ = crate::scene::osm_from_bytes(data, &crate::scene::OsmOptions::default());
    std::panic::set_hook(hook);
}

/// A whole database file, opened with each local backend (memory map, pread): its
/// info, a range query over its bounds and over half of them, every object found with
/// its mesh, LOD levels and progressive mesh, the coarsest levels of them all, a few
/// viewcells' PVSs, and the HDoV searches from a few cells with what they find.
///
/// Then the same with every checksum of the file's pages rewritten to match (the
/// header's, every data page's), so that mutated bytes reach the checks behind them.
pub fn database(data: &[u8]) {
    for bytes in [data.to_vec(), resealed(data)] {
        with_file("fuzz.flaneur", &bytes, |path| {
            for backend in [Backend::Mmap, Backend::Pread { direct: false }] {
                if let Ok(db) = Database::open_with(path, backend) {
                    walk(&db);
                }
            }
        });
    }
}

/// `data` with the checksum of its header page and of every whole data page after it
/// rewritten to match, in the page size the header names (as it is, without one).
fn resealed(data: &[u8]) -> Vec<u8> {
    let mut b = data.to_vec();
    if let Ok(Some(page_size)) = Header::check_prefix(&b) {
        let mut pages = b.chunks_exact_mut(page_size);
        if let Some(first) = pages.next() {
            Header::reseal(first);
        }
        pages.for_each(page::reseal);
    }
    b
}

fn walk(db: &Database) {
    let _ = db.info();
    let bounds = db.bounds();
    let Ok(found) = db.range(&bounds) else {
        return;
    };
    let half = Aabb {
        min: bounds.min,
        max: (bounds.min + bounds.max) * 0.5,
    };
    let _ = db.csearch(&bounds, &[half]);
    let objects = &found.objects[..found.objects.len().min(MAX_ITEMS)];
    for o in objects {
        let _ = db.mesh(o);
        if let Ok(Some(levels)) = db.lod_levels(o.id) {
            for l in levels.iter().take(MAX_ITEMS) {
                let _ = db.lod_mesh(o.id, l.level);
            }
        }
        let _ = db.progressive(o.id);
        let _ = db.object_name(o.id);
    }
    let _ = db.coarsest_meshes(objects);
    if let Ok(Some(table)) = db.visibility() {
        let cells: Vec<u32> = table.cells.iter().take(MAX_ITEMS).map(|c| c.id).collect();
        for cell in cells {
            let _ = db.pvs(cell);
        }
    }
    if let Ok(Some(tree)) = db.hdov() {
        let cells: Vec<u32> = tree.cells.iter().take(4).copied().collect();
        for cell in cells {
            for eta in [0.0, 0.01] {
                let Ok(result) = db.hdov_search(cell, eta) else {
                    continue;
                };
                for f in result.found.iter().take(MAX_ITEMS) {
                    let _ = db.hdov_load(f);
                }
            }
        }
    }
}
