//! Cubic projection (Shou 2002, §5.5.2, Fig. 5.10–5.11): the unit sphere of directions
//! around a viewpoint is replaced by the cube around it, each face divided into N×N
//! pixels; a pixel's share of the sphere is its ΔDoV, and one ray through its centre
//! decides which object it shows (the identity buffer).
//!
//! The faces are, in order, +x, −x, +y, −y, +z, −z. On the face of axis `a` with sign
//! `s`, pixel (column `i`, row `j`) looks along `s·e_a + u·e_b + v·e_c`, where
//! `(b, c) = (a + 1, a + 2) mod 3`, `u = −1 + (2i + 1)/N` and `v = −1 + (2j + 1)/N`.
//!
//! ΔDoV is the pixel's exact solid angle over 4π, not eq. 5.11's midpoint value
//! `ΔA / 4π(u² + v² + 1)^{3/2}`: that approximation overcounts (by 0.4 % over the whole
//! cube at N = 8, 4·10⁻⁶ at N = 256), so a viewpoint surrounded by geometry would see
//! DoVs summing to more than 1. The exact pixel solid angle is a difference of four
//! `atan` terms of its corners; it agrees with eq. 5.11 to within 10⁻⁴ of each pixel at
//! N = 256, and the pixels of the cube sum to 1 (to rounding) at every N. The six faces
//! share one table of N² weights, by symmetry.

use std::ops::Range;

use rayon::prelude::*;

use super::raycast::{check_point, RayScene, NO_TRIANGLE};
use crate::error::{Error, Result};

/// Bands of rows a face is cut into for threads: enough to share among cores, few enough
/// that the row above a pixel was mostly cast by the same band (whose first row has no
/// upper neighbour to try).
const BANDS_PER_FACE: usize = 16;

/// The identity-buffer value of a pixel whose ray hits nothing.
pub const SKY: u32 = u32::MAX;

/// The cubic projection of Shou 2002 §5.5.2: the six faces' pixel grids around a
/// viewpoint, and each pixel's ΔDoV (its exact solid angle over 4π).
///
/// ```
/// use flaneur::visibility::CubicProjection;
/// let cube = CubicProjection::new(64).unwrap();
/// assert_eq!(cube.rays_per_point(), 6 * 64 * 64);
/// let total: f64 = (0..64)
///     .flat_map(|j| (0..64).map(move |i| (i, j)))
///     .map(|(i, j)| cube.pixel_dov(i, j).unwrap() as f64)
///     .sum();
/// assert!((6.0 * total - 1.0).abs() < 1e-6); // the whole sphere
/// assert!(CubicProjection::new(0).is_err());
/// ```
#[derive(Clone, Debug)]
pub struct CubicProjection {
    n: u32,
    /// ΔDoV of pixel (i, j) at `j * n + i`, the same on every face.
    weights: Vec<f32>,
    /// The pixel centres' coordinate on a face axis, `−1 + (2k + 1)/n`.
    centres: Vec<f32>,
}

impl Default for CubicProjection {
    fn default() -> Self {
        Self::new(Self::DEFAULT_RESOLUTION).expect("the default resolution is in range")
    }
}

impl CubicProjection {
    /// N = 256: 393,216 rays per viewpoint; a pixel at a face's centre spans 0.45°.
    pub const DEFAULT_RESOLUTION: u32 = 256;
    /// N = 4096 casts 100 million rays per viewpoint, its weight table takes 64 MiB and
    /// its identity buffer 384 MiB: beyond it, a resolution is a mistake.
    pub const MAX_RESOLUTION: u32 = 4096;

    /// Checks a resolution as [`CubicProjection::new`] takes it: `1..=MAX_RESOLUTION`.
    pub fn check(resolution: u32) -> Result<()> {
        if !(1..=Self::MAX_RESOLUTION).contains(&resolution) {
            return Err(Error::BadResolution {
                n: resolution,
                max: Self::MAX_RESOLUTION,
            });
        }
        Ok(())
    }

    /// A projection of `resolution`×`resolution` pixels per face, `1..=MAX_RESOLUTION`.
    pub fn new(resolution: u32) -> Result<CubicProjection> {
        CubicProjection::check(resolution)?;
        let n = resolution as usize;
        let edge = |k: usize| -1.0 + 2.0 * k as f64 / n as f64;
        // The solid angle of the face rectangle [0, x] × [0, y] at distance 1 is
        // atan(xy / √(x² + y² + 1)); a pixel's is the signed sum over its four corners.
        let corner = |x: f64, y: f64| (x * y).atan2((x * x + y * y + 1.0).sqrt());
        let mut weights = Vec::with_capacity(n * n);
        let mut below: Vec<f64> = (0..=n).map(|k| corner(edge(k), edge(0))).collect();
        for j in 0..n {
            let above: Vec<f64> = (0..=n).map(|k| corner(edge(k), edge(j + 1))).collect();
            weights.extend((0..n).map(|i| {
                let omega = above[i + 1] - above[i] - below[i + 1] + below[i];
                (omega / (4.0 * std::f64::consts::PI)) as f32
            }));
            below = above;
        }
        let centres = (0..n)
            .map(|k| (-1.0 + (2 * k + 1) as f64 / n as f64) as f32)
            .collect();
        Ok(CubicProjection {
            n: resolution,
            weights,
            centres,
        })
    }

    /// N, the pixels along a face's side.
    pub fn resolution(&self) -> u32 {
        self.n
    }

    /// Rays cast per viewpoint: 6N².
    pub fn rays_per_point(&self) -> u64 {
        6 * (self.n as u64) * (self.n as u64)
    }

    /// ΔDoV of pixel (`column`, `row`) of any face: its solid angle over 4π; `None` past
    /// the face (`column` or `row` ≥ N).
    pub fn pixel_dov(&self, column: u32, row: u32) -> Option<f32> {
        (column < self.n && row < self.n).then(|| self.weights[(row * self.n + column) as usize])
    }

    /// Eq. 5.11's midpoint ΔDoV of the same pixel, `ΔA / 4π(u² + v² + 1)^{3/2}`, for
    /// comparison with [`pixel_dov`](Self::pixel_dov); `None` past the face.
    pub fn pixel_dov_midpoint(&self, column: u32, row: u32) -> Option<f64> {
        let u = *self.centres.get(column as usize)? as f64;
        let v = *self.centres.get(row as usize)? as f64;
        let area = (2.0 / self.n as f64).powi(2);
        Some(area / (4.0 * std::f64::consts::PI * (u * u + v * v + 1.0).powf(1.5)))
    }

    /// The smallest ΔDoV of any pixel (a face's corner pixel): the DoV_s the thesis gives
    /// visible zero-DoV objects, those that the conservative visibility test keeps but no
    /// corner's projection shows (§5.5.2).
    pub fn zero_dov_floor(&self) -> f32 {
        self.weights.iter().copied().fold(f32::INFINITY, f32::min)
    }

    /// The (unnormalised) direction of pixel (`column`, `row`) of face `face` (0..6, in
    /// the order +x, −x, +y, −y, +z, −z); `None` past the cube.
    pub fn direction(&self, face: usize, column: u32, row: u32) -> Option<[f32; 3]> {
        let u = *self.centres.get(column as usize)?;
        let v = *self.centres.get(row as usize)?;
        (face < 6).then(|| face_direction(face, u, v))
    }

    /// The identity buffer of viewpoint `point`: for every pixel of every face, the index
    /// of the object its ray meets first, or [`SKY`]. Pixel (`i`, `j`) of face `f` is at
    /// `(f·N + j)·N + i`.
    pub fn identity_buffer(&self, scene: &RayScene, point: [f32; 3]) -> Result<Vec<u32>> {
        check_point("viewpoint", point)?;
        let n = self.n as usize;
        let mut buffer = vec![SKY; 6 * n * n];
        let band = self.band();
        buffer
            .par_chunks_mut(n * n)
            .enumerate()
            .for_each(|(face, ids)| {
                ids.par_chunks_mut(band * n)
                    .enumerate()
                    .for_each(|(b, ids)| {
                        let rows = b * band..((b + 1) * band).min(n);
                        self.cast_rows(scene, point, face, rows, |pixel, id| ids[pixel] = id);
                    });
            });
        Ok(buffer)
    }

    /// Rows per band: a face is cast in bands of rows, [`BANDS_PER_FACE`] of them (fewer
    /// when N is small), each band on one thread.
    pub(crate) fn band(&self) -> usize {
        (self.n as usize).div_ceil(BANDS_PER_FACE)
    }

    /// Bands over the whole cube.
    pub(crate) fn bands(&self) -> usize {
        6 * (self.n as usize).div_ceil(self.band())
    }

    /// Band `k`'s face and rows.
    pub(crate) fn band_rows(&self, k: usize) -> (usize, Range<usize>) {
        let n = self.n as usize;
        let per_face = n.div_ceil(self.band());
        let start = (k % per_face) * self.band();
        (k / per_face, start..(start + self.band()).min(n))
    }

    /// Casts the rays of `rows` of face `face` in order, row by row, calling
    /// `visit(pixel, object or SKY)` for each, `pixel` counted from the first row's start.
    /// Each pixel first tries the triangles its left and upper neighbours hit: mostly the
    /// same, and once one is hit the BVH search only has to look nearer than it.
    pub(crate) fn cast_rows(
        &self,
        scene: &RayScene,
        point: [f32; 3],
        face: usize,
        rows: Range<usize>,
        mut visit: impl FnMut(usize, u32),
    ) {
        let n = self.n as usize;
        let mut above = vec![NO_TRIANGLE; n];
        let mut pixel = 0;
        for &v in &self.centres[rows] {
            let mut left = NO_TRIANGLE;
            for (&u, up) in self.centres.iter().zip(&mut above) {
                let hit = scene.cast_near(point, face_direction(face, u, v), [left, *up]);
                left = hit.map_or(NO_TRIANGLE, |h| h.0);
                *up = left;
                visit(pixel, hit.map_or(SKY, |h| scene.object_of(h.0)));
                pixel += 1;
            }
        }
    }

    /// The weight table, row-major, shared by all faces.
    pub(crate) fn weights(&self) -> &[f32] {
        &self.weights
    }
}

#[inline(always)]
fn face_direction(face: usize, u: f32, v: f32) -> [f32; 3] {
    let axis = face / 2;
    let mut d = [0.0; 3];
    d[axis] = if face.is_multiple_of(2) { 1.0 } else { -1.0 };
    d[(axis + 1) % 3] = u;
    d[(axis + 2) % 3] = v;
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cube_is_the_whole_sphere_at_every_resolution() {
        for n in [1, 2, 3, 8, 255, 256, 1000] {
            let cube = CubicProjection::new(n).unwrap();
            let face: f64 = cube.weights().iter().map(|&w| w as f64).sum();
            assert!((6.0 * face - 1.0).abs() < 1e-6, "N = {n}: {}", 6.0 * face);
        }
    }

    #[test]
    fn pixels_agree_with_eq_5_11_as_they_shrink() {
        let cube = CubicProjection::new(256).unwrap();
        let mut worst = 0.0f64;
        let mut midpoint_total = 0.0;
        for j in 0..256 {
            for i in 0..256 {
                let exact = cube.pixel_dov(i, j).unwrap() as f64;
                let mid = cube.pixel_dov_midpoint(i, j).unwrap();
                worst = worst.max((mid / exact - 1.0).abs());
                midpoint_total += mid;
            }
        }
        assert!(worst < 1e-4, "worst relative difference {worst}");
        // Eq. 5.11 overcounts the sphere slightly; the exact weights do not.
        assert!(6.0 * midpoint_total > 1.0 && 6.0 * midpoint_total < 1.0 + 1e-5);
        // A face's centre pixel is its largest, a corner pixel its smallest.
        assert!(cube.pixel_dov(128, 128) > cube.pixel_dov(0, 0));
        let floor = cube.zero_dov_floor();
        assert!(floor > 0.0 && (floor / cube.pixel_dov(255, 255).unwrap() - 1.0).abs() < 1e-6);
        assert_eq!(cube.pixel_dov(256, 0), None);
        assert_eq!(cube.pixel_dov_midpoint(0, 256), None);
    }

    #[test]
    fn faces_cover_every_axis_direction() {
        let cube = CubicProjection::new(3).unwrap();
        let centres: Vec<[f32; 3]> = (0..6).map(|f| cube.direction(f, 1, 1).unwrap()).collect();
        assert_eq!(cube.direction(6, 1, 1), None);
        assert_eq!(cube.direction(0, 3, 1), None);
        assert_eq!(
            centres,
            [
                [1.0, 0.0, 0.0],
                [-1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, -1.0, 0.0],
                [0.0, 0.0, 1.0],
                [0.0, 0.0, -1.0]
            ]
        );
    }

    #[test]
    fn resolutions_out_of_range_are_errors() {
        for n in [0, CubicProjection::MAX_RESOLUTION + 1, u32::MAX] {
            let err = CubicProjection::new(n).unwrap_err();
            assert!(matches!(err, Error::BadResolution { .. }));
            assert!(err.to_string().contains(&n.to_string()), "{err}");
        }
    }
}
