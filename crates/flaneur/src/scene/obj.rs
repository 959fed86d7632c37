//! OBJ import (tobj): every object or group of a file becomes one object of the
//! database. Faces are triangulated; missing normals are computed per vertex from
//! the area-weighted normals of the faces around it.
//!
//! Before tobj parses it, the file is read once to name the line of what tobj would
//! report without one (text that is not UTF-8) or pass over in silence (a face of
//! fewer than three vertices, which tobj takes for a point or a line and drops).

use std::path::Path;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::scene::Mesh;

/// Loads the objects of an OBJ file as `(name, mesh)` pairs. Groups without faces are
/// skipped; a file with none at all, or any malformed content, is an error naming it.
pub fn load_obj(path: &Path) -> Result<Vec<(String, Mesh)>> {
    let bad = |what: String| Error::BadInput {
        path: path.to_path_buf(),
        what,
    };
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    check_lines(&bytes).map_err(&bad)?;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _) = tobj::load_obj(path, &options).map_err(|e| match e {
        tobj::LoadError::OpenFileFailed => bad("cannot open the file".into()),
        e => bad(format!("malformed OBJ: {e}")),
    })?;
    let mut out = Vec::new();
    for model in models {
        let m = &model.mesh;
        if m.indices.is_empty() {
            continue;
        }
        if m.positions.len() % 3 != 0 {
            return Err(bad(format!("object '{}' has a partial vertex", model.name)));
        }
        let positions: Vec<[f32; 3]> = m
            .positions
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        let normals = if m.normals.len() == m.positions.len() {
            m.normals
                .chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2]).normalize_or_zero().to_array())
                .collect()
        } else {
            vertex_normals(&positions, &m.indices)
        };
        let mesh = Mesh {
            positions,
            normals,
            indices: m.indices.clone(),
        };
        mesh.validate()
            .map_err(|w| bad(format!("object '{}': {w}", model.name)))?;
        out.push((model.name, mesh));
    }
    if out.is_empty() {
        return Err(bad("no faces: the file holds no object to import".into()));
    }
    Ok(out)
}

/// What tobj would report without a line, or drop without a word: the first line that
/// is not UTF-8 text, or holds a face of fewer than three vertices.
fn check_lines(bytes: &[u8]) -> std::result::Result<(), String> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let before = &bytes[..e.valid_up_to()];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        let column = before.len()
            - before
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(0, |i| i + 1)
            + 1;
        format!(
            "line {line}: not UTF-8 text (byte {:#04x} at column {column})",
            bytes[e.valid_up_to()]
        )
    })?;
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if words.next() != Some("f") {
            continue;
        }
        let n = words.count();
        if n < 3 {
            return Err(format!(
                "line {}: a face of {n} {}: a face needs three or more",
                i + 1,
                if n == 1 { "vertex" } else { "vertices" }
            ));
        }
    }
    Ok(())
}

fn vertex_normals(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
    let mut acc = vec![Vec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| {
            positions
                .get(i as usize)
                .map_or(Vec3::ZERO, |p| Vec3::from(*p))
        });
        let n = (b - a).cross(c - a);
        for &i in t {
            if let Some(slot) = acc.get_mut(i as usize) {
                *slot += n;
            }
        }
    }
    acc.into_iter()
        .map(|n| n.normalize_or_zero().to_array())
        .collect()
}
