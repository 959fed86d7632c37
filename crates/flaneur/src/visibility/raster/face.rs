//! One face of the cube around a viewpoint, as the rasteriser sees it: world points in
//! the face's frame (`x`, `y` across it, `z` along its axis, the ray parameter of the
//! cast), the pixel a direction falls in, and a box's footprint on the face.
//!
//! The frame follows `cube.rs`: on the face of axis `a` with sign `s`, `x` lies along
//! `e_{a+1}`, `y` along `e_{a+2}`, `z = s·(p_a − eye_a)`; the point `(x, y, z)` is at
//! pixel coordinates `((x/z + 1)·N/2, (y/z + 1)·N/2)`, whose pixel (`i`, `j`) has its
//! centre at `(i + ½, j + ½)`: the ray-cast's pixel centres.

/// Surfaces nearer than this to the viewpoint along a face's axis (metres) are clipped
/// away: a vertex at the viewpoint itself has no projection. What this drops is drawn by
/// the "through the viewpoint" rule (`scene.rs`).
pub(super) const NEAR: f32 = 1e-4;

/// Pixels beyond each side of the face that clipping keeps: the edges clipping makes lie
/// outside every pixel centre, so they can never decide a pixel.
pub(super) const GUARD_PIXELS: f32 = 1.0;

/// Pixels a box's footprint is widened by: a triangle's vertices are snapped to
/// 1/256 of a pixel, so it may reach past its box by 1/512 of one.
const FOOTPRINT_SLACK: f32 = 1.0 / 64.0;

/// A face of the cube around `eye`, at N pixels a side.
#[derive(Clone, Copy, Debug)]
pub(super) struct Face {
    axis: usize,
    sign: f32,
    eye: [f32; 3],
    n: u32,
    /// `|x/z|` and `|y/z|` kept by clipping: the face plus [`GUARD_PIXELS`].
    pub guard: f32,
}

/// The pixels a box may cover on a face, and how near it comes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Footprint {
    /// First and last column, inclusive.
    pub cols: (u32, u32),
    /// First and last row, inclusive.
    pub rows: (u32, u32),
    /// `1/z` of the box's nearest point along the axis; infinite when the box reaches the
    /// near plane (nothing can hide it then).
    pub near_w: f32,
    /// The squared distance from the viewpoint to the box, to visit boxes nearest first.
    pub distance2: f32,
}

impl Face {
    /// Face `face` (0..6: +x, −x, +y, −y, +z, −z) around `eye`.
    pub fn new(face: usize, eye: [f32; 3], n: u32) -> Face {
        Face {
            axis: face / 2,
            sign: if face.is_multiple_of(2) { 1.0 } else { -1.0 },
            eye,
            n,
            guard: 1.0 + 2.0 * GUARD_PIXELS / n as f32,
        }
    }

    /// `p` in the face's frame: `[x, y, z]`.
    #[inline(always)]
    pub fn frame(&self, p: [f32; 3]) -> [f32; 3] {
        let (a, b, c) = (self.axis, (self.axis + 1) % 3, (self.axis + 2) % 3);
        [
            p[b] - self.eye[b],
            p[c] - self.eye[c],
            self.sign * (p[a] - self.eye[a]),
        ]
    }

    /// The pixel coordinates of a point of the frame with `z > 0`.
    #[inline(always)]
    pub fn project(&self, q: [f32; 3]) -> [f32; 2] {
        let half = self.n as f32 * 0.5;
        [(q[0] / q[2] + 1.0) * half, (q[1] / q[2] + 1.0) * half]
    }

    /// The direction of pixel (`i`, `j`) in world axes, as `cube.rs` casts it.
    pub fn direction(&self, i: u32, j: u32) -> [f32; 3] {
        let centre = |k: u32| -1.0 + (2 * k + 1) as f32 / self.n as f32;
        let mut d = [0.0; 3];
        d[self.axis] = self.sign;
        d[(self.axis + 1) % 3] = centre(i);
        d[(self.axis + 2) % 3] = centre(j);
        d
    }

    /// The squared distance from the viewpoint to the box `lo`–`hi` (world).
    pub fn distance2(&self, lo: [f32; 3], hi: [f32; 3]) -> f32 {
        (0..3)
            .map(|k| {
                (lo[k] - self.eye[k])
                    .max(self.eye[k] - hi[k])
                    .max(0.0)
                    .powi(2)
            })
            .sum()
    }

    /// The footprint of the box `lo`–`hi` (world): `None` when it lies wholly behind the
    /// near plane or covers no pixel centre of the face.
    pub fn footprint(&self, lo: [f32; 3], hi: [f32; 3]) -> Option<Footprint> {
        let rel = |k: usize| (lo[k] - self.eye[k], hi[k] - self.eye[k]);
        let (a, b, c) = (self.axis, (self.axis + 1) % 3, (self.axis + 2) % 3);
        let (za, zb) = rel(a);
        let (zmin, zmax) = if self.sign > 0.0 {
            (za, zb)
        } else {
            (-zb, -za)
        };
        if zmax < NEAR {
            return None;
        }
        let gap = |(l, h): (f32, f32)| {
            if l > 0.0 {
                l
            } else if h < 0.0 {
                -h
            } else {
                0.0
            }
        };
        let (x, y) = (rel(b), rel(c));
        let distance2 = gap(x).powi(2) + gap(y).powi(2) + zmin.max(0.0).powi(2);
        let last = self.n - 1;
        // A box reaching the near plane: only its part beyond it is drawn, and that part
        // may still lie off the face (a building beside the viewpoint, on the up face).
        let (near_w, zmin) = if zmin < NEAR {
            (f32::INFINITY, NEAR)
        } else {
            (1.0 / zmin, zmin)
        };
        // x/z over the box: its least at the nearest z when x < 0, at the farthest when not.
        let span = |(l, h): (f32, f32)| {
            let low = if l < 0.0 { l / zmin } else { l / zmax };
            let high = if h > 0.0 { h / zmin } else { h / zmax };
            (low, high)
        };
        let half = self.n as f32 * 0.5;
        // Pixel k's centre is at k + ½: the first and last centres inside [p, q].
        let pixels = |(l, h): (f32, f32)| {
            let p = (l + 1.0) * half - FOOTPRINT_SLACK;
            let q = (h + 1.0) * half + FOOTPRINT_SLACK;
            let first = (p - 0.5).ceil().max(0.0);
            let end = (q - 0.5).floor().min(last as f32);
            (first <= end).then_some((first as u32, end as u32))
        };
        Some(Footprint {
            cols: pixels(span(x))?,
            rows: pixels(span(y))?,
            near_w,
            distance2,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_lands_in_the_pixel_whose_ray_passes_through_it() {
        let n = 16;
        for face in 0..6 {
            let f = Face::new(face, [1.0, 2.0, 3.0], n);
            for (i, j) in [(0, 0), (3, 11), (15, 15)] {
                let d = f.direction(i, j);
                let p = [1.0 + 7.0 * d[0], 2.0 + 7.0 * d[1], 3.0 + 7.0 * d[2]];
                let q = f.frame(p);
                assert!((q[2] - 7.0).abs() < 1e-5, "z is the ray parameter");
                let [x, y] = f.project(q);
                assert!((x - (i as f32 + 0.5)).abs() < 1e-4 && (y - (j as f32 + 0.5)).abs() < 1e-4);
            }
        }
    }

    #[test]
    fn footprints_cover_what_the_box_shows() {
        let f = Face::new(4, [0.0; 3], 8); // +z
        assert_eq!(
            f.footprint([-1.0, -1.0, -3.0], [1.0, 1.0, -1.0]),
            None,
            "behind"
        );
        let whole = f.footprint([-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]).unwrap();
        assert_eq!(
            (whole.cols, whole.rows, whole.near_w),
            ((0, 7), (0, 7), f32::INFINITY)
        );
        // The box [0, 1]² at z 2..4 spans x/z in [0, ½]: pixels 4 and 5 (centres 4.5, 5.5).
        let b = f.footprint([0.0, 0.0, 2.0], [1.0, 1.0, 4.0]).unwrap();
        assert_eq!((b.cols, b.rows, b.near_w), ((4, 5), (4, 5), 0.5));
        // A box between two pixel centres covers none.
        assert_eq!(f.footprint([0.05, 0.05, 2.0], [0.1, 0.1, 2.0]), None);
    }
}
