//! Drawing one triangle into a face's item buffer: clipping to the face's frustum (its
//! four sides widened by a guard band, and the near plane), then half-space edge
//! functions in fixed point with a top-left fill rule, a row's run of pixels found by
//! solving the three edge functions for it, and a depth test per pixel.
//!
//! Vertices are snapped to 1/256 of a pixel, and the edge functions are exact integers
//! there: two triangles sharing an edge cover each pixel centre along it exactly once
//! (the top-left rule says which), so a closed surface has no cracks: the ray-cast's
//! Möller–Trumbore test is not watertight and may rarely see through such an edge.

use super::buffer::ItemBuffer;
use super::face::{Face, NEAR};

/// Sub-pixel steps per pixel (8 bits): with N ≤ 4096 and the guard band, snapped
/// coordinates stay under 2²¹ and the edge functions' products under 2⁴³.
const SUB: i64 = 256;

/// Triangles spanning fewer pixel columns than this are drawn by testing every pixel of
/// their box (below it, three divisions a row cost more than the tests).
const SCAN: i64 = 16;

/// At most 3 + 5 vertices after clipping a triangle by five planes.
const MAX_CLIPPED: usize = 9;

/// A vertex of an object on a face, transformed once for all the triangles sharing it:
/// its point in the face's frame, its outcode, and (inside the guard band) its snapped
/// pixel coordinates and `w`.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Vertex {
    q: [f32; 3],
    x: i32,
    y: i32,
    w: f32,
    /// Bit k set when it is outside clipping plane k.
    code: u8,
}

impl Vertex {
    /// World point `p` on `face`.
    #[inline(always)]
    pub fn new(face: &Face, p: [f32; 3]) -> Vertex {
        let q = face.frame(p);
        let g = face.guard;
        let code = ((q[0] > g * q[2]) as u8)
            | (((-q[0] > g * q[2]) as u8) << 1)
            | (((q[1] > g * q[2]) as u8) << 2)
            | (((-q[1] > g * q[2]) as u8) << 3)
            | (((q[2] < NEAR) as u8) << 4);
        let (mut x, mut y, mut w) = (0, 0, 0.0);
        if code == 0 {
            let v = vertex(face, q);
            (x, y, w) = (snap(v[0]) as i32, snap(v[1]) as i32, v[2]);
        }
        Vertex { q, x, y, w, code }
    }
}

/// Draws the triangle of vertices `v` for `object`; returns whether any pixel took it.
#[inline]
pub(super) fn draw(face: &Face, buf: &mut ItemBuffer, v: [&Vertex; 3], object: u32) -> bool {
    if v[0].code & v[1].code & v[2].code != 0 {
        return false;
    }
    if v[0].code | v[1].code | v[2].code == 0 {
        // Most triangles of a far object lie between pixel centres: this is `fill`'s
        // first test without its clamping to the face, which only narrows the range.
        let (xs, ys) = (v.map(|v| v.x), v.map(|v| v.y));
        let centres = |c: [i32; 3]| {
            (min3(c) + (SUB / 2 - 1) as i32) >> 8 <= (max3(c) - (SUB / 2) as i32) >> 8
        };
        if !(centres(xs) && centres(ys)) {
            return false;
        }
        return fill(buf, v.map(|v| (v.x as i64, v.y as i64, v.w)), object);
    }
    clipped(face, buf, v.map(|v| v.q), object)
}

/// Draws the triangle `q` (three points in the face's frame, some outside the guard
/// band or the near plane) clipped to the frustum.
#[cold]
fn clipped(face: &Face, buf: &mut ItemBuffer, q: [[f32; 3]; 3], object: u32) -> bool {
    let g = face.guard;
    let mut poly = [[0.0f32; 3]; MAX_CLIPPED];
    poly[..3].copy_from_slice(&q);
    let mut len = 3;
    for plane in 0..5 {
        len = clip(&mut poly, len, |p| match plane {
            0 => g * p[2] - p[0],
            1 => g * p[2] + p[0],
            2 => g * p[2] - p[1],
            3 => g * p[2] + p[1],
            _ => p[2] - NEAR,
        });
        if len < 3 {
            return false;
        }
    }
    let v = poly.map(|p| {
        let v = vertex(face, p);
        (snap(v[0]), snap(v[1]), v[2])
    });
    let mut drew = false;
    for k in 1..len - 1 {
        drew |= fill(buf, [v[0], v[k], v[k + 1]], object);
    }
    drew
}

/// A frame point's pixel coordinates and `w = 1/z`.
#[inline(always)]
fn vertex(face: &Face, p: [f32; 3]) -> [f32; 3] {
    let [x, y] = face.project(p);
    [x, y, 1.0 / p[2]]
}

/// Pixel coordinate `c` in sub-pixel steps, rounded half away from zero as
/// `(c·SUB).round()` does, without the libm call that `round` is on baseline x86-64:
/// below 2²³ the fraction `y − trunc(y)` is exact, and above it `y` is whole. A
/// coordinate past the range of `i64` (a point projected from almost on the eye's
/// plane) saturates, as `as` does, rather than wrapping round to the other side.
#[inline(always)]
fn snap(c: f32) -> i64 {
    let y = c * SUB as f32;
    let t = y as i64;
    let fraction = y - t as f32;
    t.saturating_add((fraction >= 0.5) as i64)
        .saturating_sub((fraction <= -0.5) as i64)
}

/// Sutherland–Hodgman: the part of the polygon `poly[..len]` where `inside ≥ 0`, in place;
/// returns its length.
fn clip(
    poly: &mut [[f32; 3]; MAX_CLIPPED],
    len: usize,
    inside: impl Fn(&[f32; 3]) -> f32,
) -> usize {
    let src = *poly;
    let mut out = 0;
    for k in 0..len {
        let (a, b) = (src[k], src[(k + 1) % len]);
        let (da, db) = (inside(&a), inside(&b));
        if da >= 0.0 {
            poly[out] = a;
            out += 1;
        }
        if (da >= 0.0) != (db >= 0.0) && out < MAX_CLIPPED {
            let t = da / (da - db);
            poly[out] = std::array::from_fn(|c| a[c] + t * (b[c] - a[c]));
            out += 1;
        }
    }
    out
}

/// Rasterises a triangle of snapped pixel coordinates and `w`, all inside the guard band.
#[inline(never)]
fn fill(buf: &mut ItemBuffer, mut p: [(i64, i64, f32); 3], object: u32) -> bool {
    let n = buf.n as i64;
    // Pixel k's centre is at k·SUB + SUB/2: the first and last centres inside [lo, hi].
    let first_centre = |lo: i64| (lo - SUB / 2 + SUB - 1).div_euclid(SUB).max(0);
    let last_centre = |hi: i64| (hi - SUB / 2).div_euclid(SUB).min(n - 1);
    let (xs, ys) = (p.map(|p| p.0), p.map(|p| p.1));
    let (col0, col1) = (first_centre(min3(xs)), last_centre(max3(xs)));
    let (row0, row1) = (first_centre(min3(ys)), last_centre(max3(ys)));
    // Most triangles of a far object fall between pixel centres: rejected before the
    // rest of the setup.
    if col0 > col1 || row0 > row1 {
        return false;
    }
    // A triangle behind every tile it reaches takes no pixel: rejected before its
    // setup, which changes nothing in the buffers (its `w` is clamped to its vertices').
    if buf.hides_rect(
        (col0 as u32, col1 as u32),
        (row0 as u32, row1 as u32),
        max3(p.map(|p| p.2)),
    ) {
        return false;
    }
    let area = (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1);
    if area == 0 {
        return false;
    }
    // No back-face culling: either winding is drawn, turned counter-clockwise.
    if area < 0 {
        p.swap(1, 2);
    }
    // w is affine in pixel coordinates: its plane through the snapped vertices.
    let f = p.map(|(x, y, w)| (x as f64 / SUB as f64, y as f64 / SUB as f64, w as f64));
    let (dx1, dy1, dw1) = (f[1].0 - f[0].0, f[1].1 - f[0].1, f[1].2 - f[0].2);
    let (dx2, dy2, dw2) = (f[2].0 - f[0].0, f[2].1 - f[0].1, f[2].2 - f[0].2);
    let det = dx1 * dy2 - dx2 * dy1;
    let (wx, wy) = ((dw1 * dy2 - dw2 * dy1) / det, (dx1 * dw2 - dx2 * dw1) / det);
    let (wmin, wmax) = (min3(p.map(|p| p.2)), max3(p.map(|p| p.2)));
    // Edge a→b: E(x, y) = (xb − xa)(y − ya) − (yb − ya)(x − xa), ≥ 0 inside. A pixel centre
    // exactly on an edge belongs to it if the edge is a "top-left" one (going up, or
    // level going left): of two triangles sharing the edge, exactly one has it so.
    let edges = [0, 1, 2].map(|k| {
        let (a, b) = (p[k], p[(k + 1) % 3]);
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let top_left = dy > 0 || (dy == 0 && dx < 0);
        (a.0, a.1, dx, dy, if top_left { 0 } else { 1 })
    });
    let n = n as usize;
    let mut drew = false;
    if col1 - col0 < SCAN {
        // A narrow triangle: each pixel of its box tested against the three edges,
        // stepped by additions, rather than each row's run solved by three divisions.
        let (slopes, biases) = (edges.map(|e| -e.3 * SUB), edges.map(|e| e.4));
        let mut row_start = edges.map(|(xa, ya, dx, dy, _)| {
            dx * (row0 * SUB + SUB / 2 - ya) - dy * (col0 * SUB + SUB / 2 - xa)
        });
        for j in row0..=row1 {
            let base = f[0].2 + wx * (0.5 - f[0].0) + wy * (j as f64 + 0.5 - f[0].1);
            let (base, step) = (base as f32, wx as f32);
            let row = j as usize * n;
            let mut e = row_start;
            let (mut lo, mut hi) = (i64::MAX, -1);
            for i in col0..=col1 {
                if e[0] >= biases[0] && e[1] >= biases[1] && e[2] >= biases[2] {
                    let w = (base + step * i as i32 as f32).clamp(wmin, wmax);
                    let k = row + i as usize;
                    if w > buf.depth[k] {
                        buf.depth[k] = w;
                        buf.ids[k] = object;
                    }
                    (lo, hi) = (lo.min(i), i);
                }
                for (e, s) in e.iter_mut().zip(slopes) {
                    *e += s;
                }
            }
            if lo <= hi {
                buf.touch(j as u32, lo as u32, hi as u32);
                drew = true;
            }
            for (r, e) in row_start.iter_mut().zip(&edges) {
                *r += e.2 * SUB;
            }
        }
        return drew;
    }
    for j in row0..=row1 {
        let py = j * SUB + SUB / 2;
        let (mut lo, mut hi) = (col0, col1);
        for &(xa, ya, dx, dy, bias) in &edges {
            // E at column i is A·i + B; the columns where A·i + B ≥ bias.
            let a = -dy * SUB;
            let b = dx * (py - ya) - dy * (SUB / 2 - xa);
            if a > 0 {
                lo = lo.max((bias - b + a - 1).div_euclid(a));
            } else if a < 0 {
                hi = hi.min((b - bias).div_euclid(-a));
            } else if b < bias {
                hi = -1;
            }
        }
        if lo > hi {
            continue;
        }
        let row = j as usize * n;
        let base = f[0].2 + wx * (0.5 - f[0].0) + wy * (j as f64 + 0.5 - f[0].1);
        let (base, step) = (base as f32, wx as f32);
        let (lo, hi) = (lo as usize, hi as usize);
        let depth = &mut buf.depth[row + lo..=row + hi];
        let ids = &mut buf.ids[row + lo..=row + hi];
        for (k, (d, id)) in depth.iter_mut().zip(ids.iter_mut()).enumerate() {
            let w = (base + step * (lo + k) as i32 as f32).clamp(wmin, wmax);
            let nearer = w > *d;
            *d = if nearer { w } else { *d };
            *id = if nearer { object } else { *id };
        }
        buf.touch(j as u32, lo as u32, hi as u32);
        drew = true;
    }
    drew
}

fn min3<T: PartialOrd + Copy>(v: [T; 3]) -> T {
    let m = if v[1] < v[0] { v[1] } else { v[0] };
    if v[2] < m {
        v[2]
    } else {
        m
    }
}

fn max3<T: PartialOrd + Copy>(v: [T; 3]) -> T {
    let m = if v[1] > v[0] { v[1] } else { v[0] };
    if v[2] > m {
        v[2]
    } else {
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rounding half away from zero in sub-pixel steps, and a coordinate beyond `i64`
    /// held at its end rather than wrapped to the other side of the face.
    #[test]
    fn snap_rounds_and_saturates() {
        let step = 1.0 / SUB as f32;
        assert_eq!(snap(3.0), 3 * SUB as i64);
        assert_eq!(snap(2.5 * step), 3);
        assert_eq!(snap(-2.5 * step), -3);
        assert_eq!(snap(2.4 * step), 2);
        assert_eq!(snap(f32::INFINITY), i64::MAX);
        assert_eq!(snap(1e30), i64::MAX);
        assert_eq!(snap(f32::NEG_INFINITY), i64::MIN);
        assert_eq!(snap(-1e30), i64::MIN);
    }
}
