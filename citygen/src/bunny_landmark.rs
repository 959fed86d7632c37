// The Stanford bunny as one of the city's landmarks: the shipped scan (from the engine's
// scene types) subdivided into the landmark range and placed on a lot.

use std::sync::OnceLock;

use flaneur_scene::Mesh;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::layout::Lot;

/// The bunny subdivided twice (midpoint 1-to-4): 16 × 3,674 = 58,784 triangles, which
/// puts it in the landmark range.
fn landmark_base() -> &'static Mesh {
    static DETAILED: OnceLock<Mesh> = OnceLock::new();
    DETAILED.get_or_init(|| flaneur_scene::bunny().subdivide().subdivide())
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
    fn landmark_bunny_is_subdivided_twice() {
        assert_eq!(landmark_base().triangle_count(), 58_784);
    }
}
