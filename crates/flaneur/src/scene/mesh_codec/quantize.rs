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
        Grid::around_points(meshes.into_iter().flat_map(|m| {
            let (lo, hi) = m.bounds();
            [lo, hi]
        }))
    }

    /// The box around `points` (a progressive mesh's, every vertex it ever has).
    pub(crate) fn around_points(points: impl IntoIterator<Item = [f32; 3]>) -> Grid {
        let mut g = Grid {
            min: [f32::INFINITY; 3],
            max: [f32::NEG_INFINITY; 3],
        };
        for p in points {
            for k in 0..3 {
                g.min[k] = g.min[k].min(p[k]);
                g.max[k] = g.max[k].max(p[k]);
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
        Dequantizer::of(self).position(q)
    }

    /// Every position of `qs`, dequantised onto the end of `out`.
    pub(crate) fn dequantize_into(&self, qs: &[QPosition], out: &mut Vec<[f32; 3]>) {
        let d = Dequantizer::of(self);
        out.reserve(qs.len());
        out.extend(qs.iter().map(|&q| d.position(q)));
    }
}

/// A grid's steps worked out once: a reader dequantises every position of a mesh, and
/// the division a step costs dominated its loop.
#[derive(Clone, Copy)]
struct Dequantizer {
    min: [f32; 3],
    max: [f32; 3],
    step: [f32; 3],
}

impl Dequantizer {
    #[inline]
    fn of(g: &Grid) -> Dequantizer {
        Dequantizer {
            min: g.min,
            max: g.max,
            step: [0, 1, 2].map(|k| (g.max[k] - g.min[k]) / STEPS),
        }
    }

    /// `min + q · step` clamped to the box, written out per axis (an array's `map` does
    /// not always inline in a hot loop). The comparisons are `f32::clamp`'s, so that a
    /// signed zero comes out as it did, without its check that `min <= max` (a grid
    /// that is read is valid).
    #[inline(always)]
    fn position(&self, q: QPosition) -> [f32; 3] {
        #[inline(always)]
        fn axis(min: f32, max: f32, step: f32, q: u16) -> f32 {
            let mut x = min + f32::from(q) * step;
            if x < min {
                x = min;
            }
            if x > max {
                x = max;
            }
            x
        }
        let (lo, hi, s) = (&self.min, &self.max, &self.step);
        [
            axis(lo[0], hi[0], s[0], q[0]),
            axis(lo[1], hi[1], s[1], q[1]),
            axis(lo[2], hi[2], s[2], q[2]),
        ]
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

/// Normals worked out side by side.
const LANES: usize = 8;

/// [`dequantize_normal`] of each of `qs` (whose bytes `bytes` gives), bit for bit: eight
/// at a time, so that the divisions and square root run on vectors (one normal after
/// another they were a reader's largest cost after the codecs').
pub(crate) fn dequantize_normals<T: Copy>(
    qs: &[T],
    bytes: impl Fn(T) -> [i8; 3] + Copy,
) -> Vec<[f32; 3]> {
    let mut out = Vec::with_capacity(qs.len());
    let mut chunks = qs.chunks_exact(LANES);
    for c in &mut chunks {
        out.extend_from_slice(&normal_lanes(c, bytes));
    }
    let rest = chunks.remainder();
    if !rest.is_empty() {
        out.extend_from_slice(&normal_lanes(rest, bytes)[..rest.len()]);
    }
    out
}

/// `flaneur_scene::dequantize_normal` of up to [`LANES`] normals, operation for operation:
/// glam's `Vec3 / 127.0`, `length_recip` and `try_normalize`, else +Y (IEEE's square root
/// and division round the same in a vector lane). Missing lanes are zero, and unused.
#[inline(always)]
fn normal_lanes<T: Copy>(qs: &[T], bytes: impl Fn(T) -> [i8; 3]) -> [[f32; 3]; LANES] {
    let mut c = [[0f32; LANES]; 3];
    for (l, &q) in qs.iter().take(LANES).enumerate() {
        let [x, y, z] = bytes(q);
        c[0][l] = OVER_127[x as u8 as usize];
        c[1][l] = OVER_127[y as u8 as usize];
        c[2][l] = OVER_127[z as u8 as usize];
    }
    let mut out = [[0f32; 3]; LANES];
    for l in 0..LANES {
        let (x, y, z) = (c[0][l], c[1][l], c[2][l]);
        let rcp = 1.0 / (x * x + y * y + z * z).sqrt();
        out[l] = if rcp > 0.0 && rcp < f32::INFINITY {
            [x * rcp, y * rcp, z * rcp]
        } else {
            [0.0, 1.0, 0.0]
        };
    }
    out
}

/// [`dequantize_normal`] of each [`normal_word`], for normals that repeat: a flat-shaded
/// mesh's vertices turn the few ways its faces do, so each normal is worked out once
/// and remembered (direct-mapped on its three bytes) where [`dequantize_normals`] would
/// work out every vertex's.
pub(crate) fn dequantize_repeating(words: &[u32]) -> Vec<[f32; 3]> {
    const SLOTS: usize = 256;
    // No key is this: a key keeps three bytes.
    let mut keys = [u32::MAX; SLOTS];
    let mut values = [[0f32; 3]; SLOTS];
    words
        .iter()
        .map(|&w| {
            let key = w & 0x00ff_ffff;
            let slot = (key.wrapping_mul(0x9e37_79b1) >> 24) as usize % SLOTS;
            if keys[slot] != key {
                let [x, y, z] = word_bytes(key);
                keys[slot] = key;
                values[slot] = dequantize_normal([x, y, z, 0]);
            }
            values[slot]
        })
        .collect()
}

/// Each byte of a normal (as `i8`, indexed by its bits) over 127, as glam divides it:
/// a table, where three divisions a normal were half a normal's cost.
static OVER_127: [f32; 256] = {
    let mut t = [0f32; 256];
    let mut b = 0;
    while b < 256 {
        t[b] = (b as u8 as i8) as f32 / 127.0;
        b += 1;
    }
    t
};

/// [`snorm8`] of each lane, sign-extended (its low byte is the stored byte), for finite
/// `c`: the same rounding in float arithmetic that runs on vectors, where `as i32`
/// converted one lane at a time. Adding 1.5 · 2^23 rounds a float of magnitude under 2^22
/// to an integer, exactly, and leaves that integer in its low mantissa bits.
#[inline(always)]
pub(crate) fn snorm8_lanes<const N: usize>(c: [f32; N]) -> [u32; N] {
    const MAGIC: f32 = 12_582_912.0;
    let mut out = [0u32; N];
    for l in 0..N {
        let v = c[l].clamp(-1.0, 1.0) * 127.0;
        let a = v.abs();
        // `a as f32` truncated: the nearest integer, less one where that is above.
        let near = (a + MAGIC) - MAGIC;
        let whole = if near > a { near - 1.0 } else { near };
        let r = if a - whole >= 0.5 { whole + 1.0 } else { whole };
        let signed = if v < 0.0 { -r } else { r };
        out[l] = (signed + MAGIC).to_bits().wrapping_sub(MAGIC.to_bits());
    }
    out
}

/// A normal's four bytes as one word, the first the lowest: what a reader compares.
#[inline(always)]
pub(crate) fn normal_word(n: QNormal) -> u32 {
    u32::from_le_bytes([n[0] as u8, n[1] as u8, n[2] as u8, n[3] as u8])
}

/// The bytes [`dequantize_normal`] reads of a [`normal_word`].
#[inline(always)]
pub(crate) fn word_bytes(w: u32) -> [i8; 3] {
    let [x, y, z, _] = w.to_le_bytes();
    [x as i8, y as i8, z as i8]
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
    fn normals_side_by_side_are_normals_one_at_a_time() {
        let mut qs = Vec::new();
        for x in i8::MIN..=i8::MAX {
            for y in i8::MIN..=i8::MAX {
                for z in [-128, -127, -90, -1, 0, 1, 5, 90, 127] {
                    qs.push([x, y, z, 0]);
                }
            }
        }
        for len in [qs.len(), qs.len() - 3, 5, 0] {
            let batch = dequantize_normals(&qs[..len], |q| [q[0], q[1], q[2]]);
            let words: Vec<u32> = qs[..len].iter().map(|&q| normal_word(q)).collect();
            let repeating = dequantize_repeating(&words);
            assert_eq!(batch.len(), len);
            for (k, &q) in qs[..len].iter().enumerate() {
                let want = dequantize_normal(q).map(f32::to_bits);
                assert_eq!(batch[k].map(f32::to_bits), want, "{q:?}");
                assert_eq!(repeating[k].map(f32::to_bits), want, "{q:?}");
            }
        }
    }

    #[test]
    fn rounding_side_by_side_is_rounding_one_at_a_time() {
        let mut xs = Vec::new();
        let mut c = -1.1f32;
        while c < 1.1 {
            xs.extend([c, c.next_up(), c.next_down()]);
            c += 1.0 / 4096.0;
        }
        for k in -127..127 {
            let half = (k as f32 + 0.5) / 127.0;
            xs.extend([half, half.next_up(), half.next_down()]);
        }
        xs.extend([0.0, -0.0, 1.0, -1.0, f32::MAX, f32::MIN, f32::MIN_POSITIVE]);
        for chunk in xs.chunks(8) {
            let mut lanes = [0f32; 8];
            lanes[..chunk.len()].copy_from_slice(chunk);
            let got = snorm8_lanes(lanes);
            for (l, &x) in chunk.iter().enumerate() {
                assert_eq!(got[l] as u8, snorm8(x) as u8, "{x}");
            }
        }
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
