//! Positions as 16-bit integers over the object's box, normals as 8-bit signed: the
//! vertex formats of glTF's `KHR_mesh_quantization` (gltfpack stores 14-bit positions and
//! 8-bit normals by default), so that meshoptimizer's vertex codec sees small deltas and
//! a later export copies the buffers as they are.
//!
//! A position is stored as `q = round((p - min) / (max - min) · 65535)` per axis and read
//! back as `min + q · (max - min) / 65535`, clamped to the box. The error is at most half
//! a step, `(max - min) / 131070` per axis, plus two ulps of the coordinate (the f32
//! rounding of the arithmetic): 0.76 mm on a 100 m building. Clamping keeps every vertex in
//! the box the R-tree's leaf holds for the object, which `flaneur check` verifies.

use crate::scene::Mesh;

/// Steps of a quantised axis.
const STEPS: f32 = 65535.0;

/// The box a mesh's positions are quantised over: its corners in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Grid {
    pub min: [f32; 3],
    pub max: [f32; 3],
}

/// A stored vertex: position as `[x, y, z, 0]` steps, normal as `[x, y, z, 0]` over 127.
/// Each stream's stride is a multiple of four bytes, as the vertex codec and glTF ask.
pub(crate) type QPosition = [u16; 4];
pub(crate) type QNormal = [i8; 4];

impl Grid {
    /// The box around every position of `meshes` (all of one object's levels).
    pub(crate) fn around<'a>(meshes: impl IntoIterator<Item = &'a Mesh>) -> Grid {
        let mut g = Grid {
            min: [f32::INFINITY; 3],
            max: [f32::NEG_INFINITY; 3],
        };
        for m in meshes {
            let (lo, hi) = m.bounds();
            for k in 0..3 {
                g.min[k] = g.min[k].min(lo[k]);
                g.max[k] = g.max[k].max(hi[k]);
            }
        }
        if g.min.iter().chain(&g.max).any(|c| !c.is_finite()) {
            // No position: any finite box reads back nothing.
            g.min = [0.0; 3];
            g.max = [0.0; 3];
        }
        g
    }

    /// Whether the box is one a reader may trust: finite corners, min <= max, a finite
    /// span (else a step is infinite and a position reads back as NaN).
    pub(crate) fn is_valid(&self) -> bool {
        (0..3).all(|k| {
            self.min[k].is_finite()
                && self.max[k].is_finite()
                && self.min[k] <= self.max[k]
                && (self.max[k] - self.min[k]).is_finite()
        })
    }

    /// The largest distance, per axis, between a position and where it reads back.
    #[cfg(test)]
    pub(crate) fn error_bound(&self) -> [f32; 3] {
        std::array::from_fn(|k| {
            // The multiply and the add round once each, half an ulp at most.
            let ulp = self.min[k].abs().max(self.max[k].abs()) * f32::EPSILON;
            (self.max[k] - self.min[k]) / (2.0 * STEPS) + 2.0 * ulp
        })
    }

    #[inline]
    pub(crate) fn quantize(&self, p: [f32; 3]) -> QPosition {
        let mut q = [0u16; 4];
        for k in 0..3 {
            let span = self.max[k] - self.min[k];
            if span > 0.0 {
                let t = ((p[k] - self.min[k]) / span).clamp(0.0, 1.0);
                q[k] = (t * STEPS).round() as u16;
            }
        }
        q
    }

    #[inline]
    pub(crate) fn dequantize(&self, q: QPosition) -> [f32; 3] {
        std::array::from_fn(|k| {
            let step = (self.max[k] - self.min[k]) / STEPS;
            (self.min[k] + f32::from(q[k]) * step).clamp(self.min[k], self.max[k])
        })
    }
}

#[inline]
pub(crate) fn quantize_normal(n: [f32; 3]) -> QNormal {
    let [x, y, z] = n.map(snorm8);
    [x, y, z, 0]
}

/// `flaneur_scene::quantize_snorm8`, bit for bit, without `f32::round`: on the x86-64
/// baseline that is a call into libm, and a reader giving every triangle its face's
/// normal spent most of its time there. Truncation and the exact fraction round half
/// away from zero as `round` does.
#[inline]
fn snorm8(c: f32) -> i8 {
    let v = c.clamp(-1.0, 1.0) * 127.0;
    let a = v.abs();
    let whole = a as i32;
    // Exact: `a` and its integer part lie within one of each other.
    let r = whole + i32::from(a - whole as f32 >= 0.5);
    (if v < 0.0 { -r } else { r }) as i8
}

pub(crate) fn dequantize_normal(q: QNormal) -> [f32; 3] {
    flaneur_scene::dequantize_normal([q[0], q[1], q[2]])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_read_back_within_the_bound_and_inside_the_box() {
        let mesh = crate::lod::fixtures::building();
        let g = Grid::around([&mesh]);
        let bound = g.error_bound();
        for p in &mesh.positions {
            let back = g.dequantize(g.quantize(*p));
            for k in 0..3 {
                assert!(
                    (back[k] - p[k]).abs() <= bound[k],
                    "{p:?} came back as {back:?}"
                );
                assert!(back[k] >= g.min[k] && back[k] <= g.max[k]);
            }
        }
        // The corners are exact.
        assert_eq!(g.dequantize(g.quantize(g.min)), g.min);
        assert_eq!(g.dequantize(g.quantize(g.max)), g.max);
    }

    #[test]
    fn far_from_the_origin_the_bound_counts_the_float_rounding() {
        // A building 3 km out: its coordinates' own ulps are ~0.24 mm.
        let g = Grid {
            min: [3000.0, 0.0, -3000.0],
            max: [3012.5, 40.0, -2987.0],
        };
        let bound = g.error_bound();
        let mut worst = [0f32; 3];
        for i in 0..=1000 {
            let t = i as f32 / 1000.0;
            let p: [f32; 3] = std::array::from_fn(|k| g.min[k] + t * (g.max[k] - g.min[k]) * 0.999);
            let back = g.dequantize(g.quantize(p));
            for k in 0..3 {
                worst[k] = worst[k].max((back[k] - p[k]).abs());
                assert!(back[k] >= g.min[k] && back[k] <= g.max[k]);
            }
        }
        for k in 0..3 {
            assert!(
                worst[k] <= bound[k],
                "axis {k}: {} over {}",
                worst[k],
                bound[k]
            );
        }
        assert!(
            bound[0] < 0.001,
            "sub-millimetre on a 12.5 m box: {}",
            bound[0]
        );
    }

    #[test]
    fn a_box_whose_span_overflows_is_refused() {
        // Finite corners whose difference overflows: a step of infinity would read every
        // position back as NaN (0 × inf), which no mesh may hold.
        let wide = Grid {
            min: [-3e38, 0.0, 0.0],
            max: [3e38, 1.0, 1.0],
        };
        assert!(!wide.is_valid());
        assert!(Grid {
            min: [-1e38, 0.0, 0.0],
            max: [1e38, 1.0, 1.0],
        }
        .is_valid());
    }

    #[test]
    fn normals_round_as_the_scene_file_does() {
        let mut c = -1.1f32;
        while c < 1.1 {
            for x in [c, c.next_up(), c.next_down()] {
                assert_eq!(snorm8(x), flaneur_scene::quantize_snorm8(x), "{x}");
            }
            c += 1.0 / 2048.0;
        }
        // Halfway between two steps, and just either side of it.
        for k in -127..127 {
            let half = (k as f32 + 0.5) / 127.0;
            for x in [half, half.next_up(), half.next_down()] {
                assert_eq!(snorm8(x), flaneur_scene::quantize_snorm8(x), "{x}");
            }
        }
        for x in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.0, -0.0] {
            assert_eq!(snorm8(x), flaneur_scene::quantize_snorm8(x), "{x}");
        }
    }

    #[test]
    fn flat_and_empty_boxes() {
        let g = Grid {
            min: [1.0, 2.0, 3.0],
            max: [1.0, 5.0, 3.0],
        };
        assert_eq!(g.dequantize(g.quantize([1.0, 5.0, 3.0])), [1.0, 5.0, 3.0]);
        let empty = Grid::around(std::iter::empty::<&Mesh>());
        assert!(empty.is_valid());
        assert!(!Grid {
            min: [f32::NAN; 3],
            max: [0.0; 3]
        }
        .is_valid());
    }
}
