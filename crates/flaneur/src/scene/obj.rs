//! OBJ import (tobj): every object or group of a file becomes one object of the
//! database. Faces are triangulated; missing normals are computed per vertex from
//! the area-weighted normals of the faces around it.
//!
//! Before tobj parses it, the file is read once to name the line of what tobj would
//! report without one (text that is not UTF-8) or pass over in silence (a face of
//! fewer than three vertices, which tobj takes for a point or a line and drops), and of
//! an index tobj would overflow on (`check_indices`).

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
    let text = check_lines(&bytes).map_err(&bad)?;
    check_indices(text).map_err(&bad)?;
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
/// is not UTF-8 text, or holds a face of fewer than three vertices. The text, when it
/// is whole.
fn check_lines(bytes: &[u8]) -> std::result::Result<&str, String> {
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
    Ok(text)
}

/// Checks every index of the file's faces and lines (`f`, `l`) against the elements it
/// names, before tobj reads them: a positive index at most the file's count of its kind
/// (positions, texture coordinates, normals), a relative (negative) one reaching no
/// further back than the elements before it. tobj 4 computes an element's place from an
/// index without a check for overflow: a texture or normal index past 2^62, or a
/// relative one before the first, panicked with overflow checks and without them read
/// another element (`f 1//1 2//1 3//6148914691236517207` took the first normal's z and
/// the second's x and y). An index that does not parse is left to tobj, which refuses it.
fn check_indices(text: &str) -> std::result::Result<(), String> {
    const KINDS: [(&str, &str); 3] = [
        ("v", "position"),
        ("vt", "texture coordinate"),
        ("vn", "normal"),
    ];
    let lines = || text.split('\n');
    let kind_of = |word: Option<&str>| KINDS.iter().position(|(k, _)| word == Some(*k));
    let mut total = [0usize; 3];
    for line in lines() {
        if let Some(k) = kind_of(line.split_whitespace().next()) {
            total[k] += 1;
        }
    }
    let mut before = [0usize; 3];
    for (n, line) in lines().enumerate() {
        let mut words = line.split_whitespace();
        let first = words.next();
        if let Some(k) = kind_of(first) {
            before[k] += 1;
            continue;
        }
        if !matches!(first, Some("f" | "l")) {
            continue;
        }
        for word in words {
            for (k, part) in word.split('/').enumerate().take(3) {
                let Ok(x) = part.parse::<isize>() else {
                    continue;
                };
                let name = KINDS[k].1;
                if x > 0 && x.unsigned_abs() > total[k] {
                    return Err(format!(
                        "line {}: index {x} names no {name} (the file has {})",
                        n + 1,
                        total[k]
                    ));
                }
                if x < 0 && x.unsigned_abs() > before[k] {
                    return Err(format!(
                        "line {}: relative index {x} reaches before the first {name} ({} before it)",
                        n + 1,
                        before[k]
                    ));
                }
            }
        }
    }
    Ok(())
}

pub(super) fn vertex_normals(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn load(text: &str) -> Result<Vec<(String, Mesh)>> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.obj");
        std::fs::write(&path, text).unwrap();
        load_obj(&path)
    }

    const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 1 0 0\n";

    #[test]
    fn a_triangle_loads() {
        let objects = load(&format!("{TRIANGLE}f 1//1 2//1 -1//-2\n")).unwrap();
        assert_eq!(objects[0].1.normals, [[0.0, 0.0, 1.0]; 3]);
    }

    /// An index tobj would overflow on is refused by name (found by the fuzz target
    /// `obj`): this one panicked with overflow checks and without them loaded a normal
    /// made of two others.
    #[test]
    fn an_index_past_the_elements_is_refused() {
        for face in [
            "f 1//1 2//1 3//6148914691236517207",
            "f 1/9223372036854775807 2/1 3/1",
            "f 1//1 2//1 3//-3",
            "l 1 4",
        ] {
            let e = load(&format!("{TRIANGLE}{face}\n"))
                .unwrap_err()
                .to_string();
            assert!(e.contains("line 6") && e.contains("index"), "{face}: {e}");
        }
    }
}
