//! The model files a database is built from besides a scene file (OBJ, glTF,
//! OpenStreetMap), loaded together: their objects named and in input order, the OBJ
//! ones placed by the bounds of them all.

use std::path::{Path, PathBuf};

use super::BuildOptions;
use crate::error::{Error, Result};
use crate::scene::{load_gltf, load_obj, load_osm, place, Mesh, OsmReport, Placed};

/// Every object of a build's model files.
pub(super) struct Models {
    /// Meshes, object `i` at index `i`.
    pub meshes: Vec<Mesh>,
    /// Their names in the files (empty where a file gives none).
    pub names: Vec<String>,
    /// How OBJ inputs were placed; `None` without any.
    pub obj_placed: Option<Placed>,
    /// What the OpenStreetMap import made of its extract; `None` without one.
    pub osm: Option<OsmReport>,
}

/// Loads `files`: at least one, at most one OpenStreetMap extract (each is projected
/// about its own centre).
pub(super) fn load_models(files: &[PathBuf], opts: &BuildOptions) -> Result<Models> {
    if files.is_empty() {
        return Err(Error::Invalid(
            "no OBJ, glTF or OpenStreetMap file to build from".into(),
        ));
    }
    let extracts = files
        .iter()
        .filter(|f| model_format(f) == Some(ModelFormat::Osm));
    if extracts.count() > 1 {
        return Err(Error::Invalid(
            "more than one OpenStreetMap extract: each is projected about its own centre, so build one at a time".into(),
        ));
    }
    // OBJ meshes are placed together, by the bounds of them all; the others need nothing.
    let (mut meshes, mut names, mut obj) = (Vec::new(), Vec::new(), Vec::new());
    let mut osm = None;
    for f in files {
        let loaded = load_model(f, opts)?;
        osm = osm.or(loaded.osm);
        let start = meshes.len();
        for (name, mesh) in loaded.objects {
            names.push(name);
            meshes.push(mesh);
        }
        if model_format(f) == Some(ModelFormat::Obj) {
            obj.extend(start..meshes.len());
        }
    }
    let obj_placed = if obj.is_empty() {
        None
    } else {
        let mut objs: Vec<Mesh> = obj
            .iter()
            .map(|&i| std::mem::take(&mut meshes[i]))
            .collect();
        let placed = place(&mut objs, &opts.obj_axes)?;
        // The files' coordinates are finite (the loader checks them): one that is not
        // now is the scale's doing.
        if let Some(k) = objs
            .iter()
            .position(|m| m.positions.iter().flatten().any(|c| !c.is_finite()))
        {
            return Err(Error::Invalid(format!(
                "scale {} m a unit (--scale) puts OBJ object {} beyond the largest coordinate \
                 there is ({:e} m): the files are {:.1} × {:.1} × {:.1} units",
                crate::visibility::shown(opts.obj_axes.scale),
                obj[k],
                f32::MAX,
                placed.extent[0],
                placed.extent[1],
                placed.extent[2]
            )));
        }
        for (&i, m) in obj.iter().zip(objs) {
            meshes[i] = m;
        }
        Some(placed)
    };
    Ok(Models {
        meshes,
        names,
        obj_placed,
        osm,
    })
}

/// The objects of one model file, named, and the OpenStreetMap import's report.
struct Loaded {
    objects: Vec<(String, Mesh)>,
    osm: Option<OsmReport>,
}

/// The objects of an OBJ, glTF or OpenStreetMap file, by its extension.
fn load_model(path: &Path, opts: &BuildOptions) -> Result<Loaded> {
    let objects = match model_format(path) {
        Some(ModelFormat::Obj) => load_obj(path)?,
        Some(ModelFormat::Gltf) => load_gltf(path, opts.gltf_objects)?,
        Some(ModelFormat::Osm) => {
            let city = load_osm(path, &opts.osm)?;
            return Ok(Loaded {
                objects: city.objects,
                osm: Some(city.report),
            });
        }
        None => {
            return Err(Error::BadInput {
                path: path.to_path_buf(),
                what: "not an OBJ (.obj), glTF (.gltf, .glb) or OpenStreetMap (.osm.pbf) file, by its name".into(),
            })
        }
    };
    Ok(Loaded { objects, osm: None })
}

/// The kinds of model file a database is built from besides a scene file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelFormat {
    /// Wavefront OBJ (`.obj`).
    Obj,
    /// glTF 2.0 (`.gltf`, `.glb`).
    Gltf,
    /// An OpenStreetMap extract in the PBF format (`.osm.pbf`, `.pbf`).
    Osm,
}

/// The model format `path`'s extension names, if any.
pub fn model_format(path: &Path) -> Option<ModelFormat> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    match ext.as_str() {
        "obj" => Some(ModelFormat::Obj),
        "gltf" | "glb" => Some(ModelFormat::Gltf),
        "pbf" => Some(ModelFormat::Osm),
        _ => None,
    }
}
