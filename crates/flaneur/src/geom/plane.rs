//! Oriented planes: the faces of a view frustum (Shou 2002 §4.3).
//!
//! A plane is `normal · p + d = 0`. Its **positive side** (`normal · p + d >= 0`) is the
//! inside of the convex shape whose face it is. The thesis's Fig. 4.14 draws the face
//! normals pointing *out* of the frustum cell and calls their side "positive"; we keep the
//! normals pointing *in*, so "outside the face" in the thesis is `signed_distance < 0` here.

use glam::Vec3;

use crate::error::{Error, Result};

/// An oriented plane `normal · p + d = 0` with a unit normal pointing to its inside.
///
/// ```
/// use flaneur::geom::Plane;
/// use glam::Vec3;
/// // The ground, inside above it.
/// let ground = Plane::from_point_normal(Vec3::ZERO, Vec3::Y).unwrap();
/// assert_eq!(ground.signed_distance(Vec3::new(3.0, 2.0, -1.0)), 2.0);
/// assert!(ground.is_inside(Vec3::new(0.0, 0.0, 5.0))); // on the plane counts as inside
/// assert!(Plane::from_point_normal(Vec3::ZERO, Vec3::ZERO).is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Unit normal, pointing to the inside (positive side).
    pub normal: Vec3,
    /// Offset: `-normal · p` for any point `p` on the plane.
    pub d: f32,
}

impl Plane {
    /// A plane from a normal of any non-zero length and an offset; both are scaled so
    /// the normal has unit length. Errors on a zero or non-finite normal or offset.
    pub fn new(normal: Vec3, d: f32) -> Result<Plane> {
        let len = normal.length();
        if !(normal.is_finite() && d.is_finite() && len.is_finite() && len > 0.0) {
            return Err(Error::Invalid(format!(
                "plane normal {normal} / offset {d} must be finite and non-zero"
            )));
        }
        Ok(Plane {
            normal: normal / len,
            d: d / len,
        })
    }

    /// The plane through `point` whose inside is where `normal` points.
    pub fn from_point_normal(point: Vec3, normal: Vec3) -> Result<Plane> {
        if !point.is_finite() {
            return Err(Error::Invalid(format!("plane point {point} is not finite")));
        }
        let n = normal.try_normalize().ok_or_else(|| {
            Error::Invalid(format!("plane normal {normal} must be finite and non-zero"))
        })?;
        Ok(Plane {
            normal: n,
            d: -n.dot(point),
        })
    }

    /// Signed distance of `p` from the plane: positive inside, negative outside
    /// (in metres when the normal has unit length, as every constructor ensures).
    #[inline]
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        self.normal.dot(p) + self.d
    }

    /// True when `p` is on the plane or on its positive (inside) side.
    #[inline]
    pub fn is_inside(&self, p: Vec3) -> bool {
        self.signed_distance(p) >= 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalises_and_measures() {
        let p = Plane::new(Vec3::new(0.0, 0.0, 2.0), -4.0).unwrap();
        assert_eq!(p.normal, Vec3::Z);
        assert_eq!(p.d, -2.0);
        assert_eq!(p.signed_distance(Vec3::new(9.0, 9.0, 5.0)), 3.0);
        assert!(!p.is_inside(Vec3::new(0.0, 0.0, 1.0)));
        let q =
            Plane::from_point_normal(Vec3::new(1.0, 1.0, 1.0), Vec3::new(-1.0, 0.0, 0.0)).unwrap();
        assert!(q.signed_distance(Vec3::new(0.0, 5.0, 5.0)) > 0.0);
        assert_eq!(q.signed_distance(Vec3::new(1.0, -3.0, 8.0)), 0.0);
    }

    #[test]
    fn bad_planes_are_errors() {
        assert!(Plane::new(Vec3::ZERO, 1.0).is_err());
        assert!(Plane::new(Vec3::new(f32::NAN, 0.0, 1.0), 1.0).is_err());
        assert!(Plane::new(Vec3::X, f32::INFINITY).is_err());
        assert!(Plane::from_point_normal(Vec3::splat(f32::NAN), Vec3::X).is_err());
        assert!(Plane::from_point_normal(Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0)).is_err());
    }
}
