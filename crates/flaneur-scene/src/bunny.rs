// The Stanford bunny, shipped in data/ and compiled in, so a city always has one real
// scanned model among its procedural ones, the LOD core's tests have a real scan to
// simplify, and no run needs the network or a working directory. It is parsed once per process and kept.

use std::io::{BufReader, Cursor};
use std::sync::OnceLock;

use crate::mesh::Mesh;

/// The bunny as shipped: `data/bunny.obj` (see `data/README.md`).
const BUNNY_OBJ: &str = include_str!("../../../data/bunny.obj");

/// The Stanford bunny as shipped in `data/bunny.obj`: 1,839 vertices, 3,674 triangles,
/// in the scan's units (about 9.7 tall, y up, standing on y ≈ 0), wound outward, with
/// smooth normals computed from the faces.
///
/// ```
/// let bunny = flaneur_scene::bunny();
/// assert_eq!(bunny.triangle_count(), 3674);
/// assert!(bunny.validate().is_ok());
/// ```
pub fn bunny() -> Mesh {
    base().clone()
}

fn base() -> &'static Mesh {
    static BASE: OnceLock<Mesh> = OnceLock::new();
    BASE.get_or_init(|| {
        let options = tobj::LoadOptions {
            single_index: true,
            triangulate: true,
            ..Default::default()
        };
        let (models, _) = tobj::load_obj_buf(
            &mut BufReader::new(Cursor::new(BUNNY_OBJ)),
            &options,
            |_| Err(tobj::LoadError::OpenFileFailed),
        )
        .expect("the bunny compiled into this crate is a valid OBJ");
        let mut mesh = Mesh::default();
        for model in models {
            let positions: Vec<[f32; 3]> = model
                .mesh
                .positions
                .chunks_exact(3)
                .map(|p| [p[0], p[1], p[2]])
                .collect();
            // Placeholder normals; the real ones are computed once the parts are joined.
            let normals = vec![[0.0, 1.0, 0.0]; positions.len()];
            mesh.append(&Mesh {
                positions,
                normals,
                indices: model.mesh.indices,
            });
        }
        if mesh.signed_volume() < 0.0 {
            mesh.flip();
        }
        mesh.compute_smooth_normals();
        mesh
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bunny_is_the_shipped_scan() {
        let b = bunny();
        assert_eq!(b.positions.len(), 1839);
        assert_eq!(b.triangle_count(), 3674);
        b.validate().unwrap();
        assert!(b.signed_volume() > 0.0);
        let (min, max) = b.bounds();
        assert!((max[1] - min[1] - 9.657_897).abs() < 1e-3);
    }
}
