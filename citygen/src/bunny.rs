// The Stanford bunny, shipped in data/ and compiled into the binary, so a city always
// has one real scanned model among its procedural ones and no run needs the network
// or a working directory. It is parsed once per process and kept.

use std::io::{BufReader, Cursor};
use std::sync::OnceLock;

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::layout::Lot;
use crate::mesh::Mesh;

/// The bunny as shipped: `data/bunny.obj` (see `data/README.md`).
const BUNNY_OBJ: &str = include_str!("../../data/bunny.obj");

/// The Stanford bunny as shipped in `data/bunny.obj`: 1,839 vertices, 3,674 triangles,
/// in the scan's units (about 9.7 tall, y up, standing on y ≈ 0), wound outward, with
/// smooth normals computed from the faces.
///
/// ```
/// let bunny = citygen::bunny();
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
        .expect("the bunny compiled into citygen is a valid OBJ");
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

/// The bunny subdivided twice (midpoint 1-to-4): 16 × 3,674 = 58,784 triangles, which
/// puts it in the landmark range.
fn landmark_base() -> &'static Mesh {
    static DETAILED: OnceLock<Mesh> = OnceLock::new();
    DETAILED.get_or_init(|| base().subdivide().subdivide())
}

/// The bunny as a landmark on `lot`: 10–25 m tall (less where the lot is too narrow for
/// that), turned a random quarter, standing on the ground at the lot's centre.
pub(crate) fn bunny_landmark(rng: &mut ChaCha8Rng, lot: &Lot) -> Mesh {
    let mut mesh = landmark_base().clone();
    mesh.rotate_y_quarter(rng.gen_range(0..4));
    let (min, max) = mesh.bounds();
    let centre = [(min[0] + max[0]) / 2.0, (min[2] + max[2]) / 2.0];
    let half_width = ((max[0] - min[0]).max(max[2] - min[2])) / 2.0;
    let tall: f32 = rng.gen_range(10.0..=25.0);
    let scale = (tall / (max[1] - min[1])).min(lot.half / half_width);
    mesh.scale_translate(
        scale,
        [
            lot.center[0] - centre[0] * scale,
            -min[1] * scale,
            lot.center[1] - centre[1] * scale,
        ],
    );
    mesh
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

    #[test]
    fn landmark_bunny_is_subdivided_twice() {
        assert_eq!(landmark_base().triangle_count(), 58_784);
    }
}
