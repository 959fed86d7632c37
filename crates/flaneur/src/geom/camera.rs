//! The viewer: a pinhole camera with the REVIEW defaults of Shou 2002 §4.4 (a frustum
//! 1 km deep, a field of view of 45° × 45°), its view frustum (§4.1, §4.3) and the
//! centre of its far clip plane, the point F that prefetching moves ahead (§4.2.5).
//!
//! Conventions: world y is up, right-handed. `yaw` 0 looks along +x and grows toward +z
//! (so a positive yaw step turns the viewer to the right); `pitch` positive looks up.
//! The thesis gives no near plane; we choose 0.5 m (a viewer's arm's length), which keeps
//! the depth buffer's precision reasonable over a 1 km frustum.

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use glam::{Mat4, Vec3};

use super::frustum::Frustum;
use super::plane::Plane;
use crate::error::{Error, Result};

/// Default horizontal and vertical field of view: 45° (Shou 2002 §4.4).
pub const DEFAULT_FOV: f32 = FRAC_PI_4;
/// Default near clip distance, metres (our choice; the thesis gives none).
pub const DEFAULT_NEAR: f32 = 0.5;
/// Default far clip distance, metres: the thesis's 1 km eyesight (§4.4).
pub const DEFAULT_FAR: f32 = 1000.0;

/// A camera: position, orientation (yaw, pitch; no roll) and a symmetric frustum.
///
/// ```
/// use flaneur::geom::Camera;
/// use glam::Vec3;
/// # fn main() -> flaneur::Result<()> {
/// let cam = Camera::new(Vec3::new(10.0, 1.7, 20.0), 0.0, 0.0)?; // looking along +x
/// assert_eq!(cam.far, 1000.0);
/// assert!((cam.far_center() - Vec3::new(1010.0, 1.7, 20.0)).length() < 1e-3);
/// let frustum = cam.frustum();
/// assert!(frustum.contains_point(Vec3::new(500.0, 1.7, 20.0)));
/// assert!(!frustum.contains_point(Vec3::new(-5.0, 1.7, 20.0))); // behind the viewer
/// let cell = frustum.aabb(); // the frustum cell of §4.1
/// assert!(cell.max.x > 1009.0);
/// // Bad input is an error, not a panic.
/// assert!(Camera::new(Vec3::new(f32::NAN, 0.0, 0.0), 0.0, 0.0).is_err());
/// assert!(Camera::new(Vec3::ZERO, 0.0, 0.0)?.with_clip(5.0, 1.0).is_err());
/// # Ok(()) }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// The eye, world coordinates (metres).
    pub position: Vec3,
    /// Heading in radians: 0 looks along +x, increasing toward +z. Any finite value.
    pub yaw: f32,
    /// Elevation in radians, positive up; strictly inside (−π/2, π/2).
    pub pitch: f32,
    /// Full horizontal field of view, radians, in (0, π).
    pub fov_x: f32,
    /// Full vertical field of view, radians, in (0, π).
    pub fov_y: f32,
    /// Near clip distance, metres, > 0.
    pub near: f32,
    /// Far clip distance, metres, > `near`.
    pub far: f32,
}

/// The horizontal field of view that, with `fov_y`, fills an image of `aspect`
/// (width / height); radians.
pub fn fov_x_for(fov_y: f32, aspect: f32) -> f32 {
    2.0 * ((fov_y * 0.5).tan() * aspect).atan()
}

impl Camera {
    /// A camera at `position` looking along (`yaw`, `pitch`) with the thesis's defaults:
    /// 45° × 45° field of view, near 0.5 m, far 1000 m. Errors on a non-finite input or a
    /// pitch of ±90° or more (looking straight up or down leaves the heading undefined).
    pub fn new(position: Vec3, yaw: f32, pitch: f32) -> Result<Camera> {
        let c = Camera {
            position,
            yaw,
            pitch,
            fov_x: DEFAULT_FOV,
            fov_y: DEFAULT_FOV,
            near: DEFAULT_NEAR,
            far: DEFAULT_FAR,
        };
        c.validate()?;
        Ok(c)
    }

    /// The same camera with another field of view (radians, each in (0, π)).
    pub fn with_fov(self, fov_x: f32, fov_y: f32) -> Result<Camera> {
        let c = Camera {
            fov_x,
            fov_y,
            ..self
        };
        c.validate()?;
        Ok(c)
    }

    /// The same camera with its vertical field of view kept and its horizontal one
    /// fitted to an image of `aspect` (width / height): what a picture of that shape
    /// shows.
    ///
    /// ```
    /// # fn main() -> flaneur::Result<()> {
    /// let camera = flaneur::geom::Camera::new(glam::Vec3::ZERO, 0.0, 0.0)?;
    /// let wide = camera.fitted_to(16.0 / 9.0)?;
    /// assert_eq!(wide.fov_y, camera.fov_y);
    /// assert!(wide.fov_x > camera.fov_x);
    /// # Ok(()) }
    /// ```
    pub fn fitted_to(self, aspect: f32) -> Result<Camera> {
        self.with_fov(fov_x_for(self.fov_y, aspect), self.fov_y)
    }

    /// The same camera with other clip distances (`0 < near < far`, metres).
    pub fn with_clip(self, near: f32, far: f32) -> Result<Camera> {
        let c = Camera { near, far, ..self };
        c.validate()?;
        Ok(c)
    }

    /// Checks every field; the fields are public, so a camera built by hand should be
    /// validated before its frustum is trusted ([`Camera::frustum`] does not check).
    pub fn validate(&self) -> Result<()> {
        let bad = |what: String| Err(Error::Invalid(format!("camera: {what}")));
        if !self.position.is_finite() {
            return bad(format!("position {} is not finite", self.position));
        }
        if !self.yaw.is_finite() {
            return bad(format!("yaw {} is not finite", self.yaw));
        }
        if !(self.pitch.is_finite() && self.pitch.abs() < FRAC_PI_2) {
            return bad(format!(
                "pitch {} must be finite and strictly between -pi/2 and pi/2",
                self.pitch
            ));
        }
        for (name, fov) in [("fov_x", self.fov_x), ("fov_y", self.fov_y)] {
            if !(fov > 0.0 && fov < PI) {
                return bad(format!("{name} {fov} must be in (0, pi) radians"));
            }
        }
        if !(self.near > 0.0 && self.near < self.far && self.far.is_finite()) {
            return bad(format!(
                "clip distances near {} / far {} must satisfy 0 < near < far < inf",
                self.near, self.far
            ));
        }
        Ok(())
    }

    /// Unit view direction.
    pub fn forward(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(cy * cp, sp, sy * cp)
    }

    /// Unit vector to the viewer's right (horizontal: the camera has no roll).
    pub fn right(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        Vec3::new(-sy, 0.0, cy)
    }

    /// Unit vector up in the image: `right × forward`.
    pub fn up(&self) -> Vec3 {
        self.right().cross(self.forward())
    }

    /// The view frustum: six inward planes, eight corners.
    pub fn frustum(&self) -> Frustum {
        let (p, f, r, u) = (self.position, self.forward(), self.right(), self.up());
        let (hx, hy) = (self.fov_x * 0.5, self.fov_y * 0.5);
        let (sx, cx) = hx.sin_cos();
        let (sy, cy) = hy.sin_cos();
        // Unit normals by construction (f, r, u orthonormal); no validation needed.
        let through = |n: Vec3, q: Vec3| Plane {
            normal: n,
            d: -n.dot(q),
        };
        let planes = [
            through(f, p + f * self.near),
            through(-f, p + f * self.far),
            through(r * cx + f * sx, p),
            through(-r * cx + f * sx, p),
            through(u * cy + f * sy, p),
            through(-u * cy + f * sy, p),
        ];
        let (tx, ty) = (hx.tan(), hy.tan());
        let corners = std::array::from_fn(|i| {
            let dist = if i & 4 != 0 { self.far } else { self.near };
            let sx = if i & 1 != 0 { 1.0 } else { -1.0 };
            let sy = if i & 2 != 0 { 1.0 } else { -1.0 };
            p + f * dist + r * (sx * dist * tx) + u * (sy * dist * ty)
        });
        let scale = self.far.max(self.position.abs().max_element()).max(1.0);
        Frustum::from_parts(planes, corners, scale)
    }

    /// F of §4.2.5: the centre of the far clip plane, `far` metres along [`forward`](Self::forward).
    pub fn far_center(&self) -> Vec3 {
        self.position + self.forward() * self.far
    }

    /// Width over height of an image that shows exactly this camera's frustum:
    /// `tan(fov_x / 2) / tan(fov_y / 2)` (1 for the default 45° × 45°).
    pub fn aspect(&self) -> f32 {
        (self.fov_x * 0.5).tan() / (self.fov_y * 0.5).tan()
    }

    /// Projection × view for a renderer: right-handed, y up, depth mapped to [0, 1]
    /// (the wgpu / Vulkan / D3D convention), vertical field of view `fov_y`, the given
    /// image `aspect` (width / height). With `aspect = self.aspect()` the clip volume is
    /// exactly [`Camera::frustum`]. Errors on an invalid camera or a non-positive aspect.
    pub fn view_proj(&self, aspect: f32) -> Result<Mat4> {
        self.validate()?;
        if !(aspect.is_finite() && aspect > 0.0) {
            return Err(Error::Invalid(format!(
                "aspect {aspect} must be a positive number"
            )));
        }
        let proj =
            glam::camera::rh::proj::directx::perspective(self.fov_y, aspect, self.near, self.far);
        let view = glam::camera::rh::view::look_to_mat4(self.position, self.forward(), Vec3::Y);
        Ok(proj * view)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(yaw: f32, pitch: f32) -> Camera {
        Camera::new(Vec3::new(3.0, 1.7, -4.0), yaw, pitch).unwrap()
    }

    #[test]
    fn axes_follow_the_conventions() {
        let c = cam(0.0, 0.0);
        assert!((c.forward() - Vec3::X).length() < 1e-6);
        assert!((c.right() - Vec3::Z).length() < 1e-6);
        assert!((c.up() - Vec3::Y).length() < 1e-6);
        let c = cam(FRAC_PI_2, 0.0);
        assert!((c.forward() - Vec3::Z).length() < 1e-6);
        assert!(cam(0.0, 0.3).forward().y > 0.0);
        for (yaw, pitch) in [(0.3, 0.2), (-2.0, -1.0), (5.0, 1.2)] {
            let c = cam(yaw, pitch);
            let (f, r, u) = (c.forward(), c.right(), c.up());
            assert!((f.length() - 1.0).abs() < 1e-5 && (u.length() - 1.0).abs() < 1e-5);
            assert!(f.dot(r).abs() < 1e-5 && f.dot(u).abs() < 1e-5 && r.dot(u).abs() < 1e-5);
            assert!(u.y > 0.0);
        }
    }

    #[test]
    fn far_center_is_far_along_forward() {
        let c = cam(1.1, -0.2);
        let f = c.far_center();
        assert!(((f - c.position).length() - c.far).abs() < 1e-2);
        assert!((f - c.position).normalize().dot(c.forward()) > 0.99999);
    }

    #[test]
    fn bad_cameras_are_errors() {
        let p = Vec3::ZERO;
        assert!(Camera::new(Vec3::new(0.0, f32::INFINITY, 0.0), 0.0, 0.0).is_err());
        assert!(Camera::new(p, f32::NAN, 0.0).is_err());
        assert!(Camera::new(p, 0.0, f32::NAN).is_err());
        assert!(Camera::new(p, 0.0, FRAC_PI_2).is_err());
        let c = Camera::new(p, 0.0, 0.0).unwrap();
        assert!(c.with_fov(0.0, 0.5).is_err());
        assert!(c.with_fov(0.5, PI).is_err());
        assert!(c.with_fov(f32::NAN, 0.5).is_err());
        assert!(c.with_clip(0.0, 10.0).is_err());
        assert!(c.with_clip(10.0, 10.0).is_err());
        assert!(c.with_clip(1.0, f32::INFINITY).is_err());
        assert!(c.with_clip(1.0, 10.0).is_ok());
        assert!(c.view_proj(0.0).is_err());
        assert!(c.view_proj(f32::NAN).is_err());
    }

    #[test]
    fn view_proj_maps_the_frustum_to_the_clip_volume() {
        let c = cam(0.7, 0.1).with_fov(1.0, 0.6).unwrap();
        let m = c.view_proj(c.aspect()).unwrap();
        // Points just inside the frustum land in the clip volume, just outside do not.
        let f = c.frustum();
        let centre = f.corners().iter().copied().sum::<Vec3>() / 8.0;
        for &k in f.corners() {
            for (t, inside) in [(0.99, true), (1.01, false)] {
                let p = centre + (k - centre) * t;
                let q = m.project_point3(p);
                let ndc = q.x.abs() <= 1.0 && q.y.abs() <= 1.0 && (0.0..=1.0).contains(&q.z);
                assert_eq!(ndc, inside, "corner {k} scaled {t}: ndc {q}");
                assert_eq!(f.contains_point(p), inside);
            }
        }
    }
}
