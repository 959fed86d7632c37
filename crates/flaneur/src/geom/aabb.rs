//! Axis-aligned bounding boxes: the MBRs of the R-tree and the cells of a walkthrough.
//!
//! Boxes are closed: two boxes that share only a face overlap. This matches the
//! thesis's Overlaps test (Shou 2002, §4.2.2) and makes range results stable for
//! objects that touch a query's boundary.

use glam::Vec3;

use crate::error::{Error, Result};

/// A closed axis-aligned box `[min, max]`.
///
/// ```
/// use flaneur::geom::Aabb;
/// let a = Aabb::new([0.0, 0.0, 0.0], [2.0, 2.0, 2.0]).unwrap();
/// let b = Aabb::new([1.0, 1.0, 1.0], [3.0, 3.0, 3.0]).unwrap();
/// assert!(a.overlaps(&b));
/// assert!(!a.contains(&b));
/// assert!(Aabb::new([1.0, 0.0, 0.0], [0.0, 1.0, 1.0]).is_err()); // min > max
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// The lower corner.
    pub min: Vec3,
    /// The upper corner.
    pub max: Vec3,
}

impl Aabb {
    /// A checked box: every coordinate finite and `min <= max` on each axis.
    /// Zero-sized boxes (a point, a flat facade) are valid.
    pub fn new(min: [f32; 3], max: [f32; 3]) -> Result<Aabb> {
        let b = Aabb {
            min: Vec3::from(min),
            max: Vec3::from(max),
        };
        b.validate()?;
        Ok(b)
    }

    /// Checks a box that came from outside (a file, a command line, a caller).
    pub fn validate(&self) -> Result<()> {
        if !self.min.is_finite() || !self.max.is_finite() {
            return Err(Error::BadBox(format!(
                "{self} has a coordinate that is not finite"
            )));
        }
        if self.min.cmpgt(self.max).any() {
            return Err(Error::BadBox(format!("{self} has min > max on some axis")));
        }
        Ok(())
    }

    /// The empty box: the identity of [`Aabb::union`]. Not valid as a query.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// Whether the box holds no point: `min > max` on some axis, as in [`Aabb::EMPTY`].
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// Smallest box around a set of points; `EMPTY` for none.
    pub fn from_points<I: IntoIterator<Item = Vec3>>(points: I) -> Aabb {
        points.into_iter().fold(Aabb::EMPTY, |b, p| Aabb {
            min: b.min.min(p),
            max: b.max.max(p),
        })
    }

    /// Closed-box intersection test.
    #[inline]
    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.min.cmple(other.max).all() && other.min.cmple(self.max).all()
    }

    /// True when `other` lies completely inside `self` (faces may touch).
    #[inline]
    pub fn contains(&self, other: &Aabb) -> bool {
        self.min.cmple(other.min).all() && other.max.cmple(self.max).all()
    }

    /// Whether `p` lies in the closed box.
    #[inline]
    pub fn contains_point(&self, p: Vec3) -> bool {
        self.min.cmple(p).all() && p.cmple(self.max).all()
    }

    /// The smallest box around both.
    #[inline]
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// The overlap of two boxes, or `None` when they are disjoint.
    pub fn intersection(&self, other: &Aabb) -> Option<Aabb> {
        let b = Aabb {
            min: self.min.max(other.min),
            max: self.max.min(other.max),
        };
        (!b.is_empty()).then_some(b)
    }

    /// The centre point.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// The size along each axis: `max - min`.
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// Volume; zero for flat boxes, zero for `EMPTY`.
    pub fn volume(&self) -> f32 {
        if self.is_empty() {
            0.0
        } else {
            let e = self.extent();
            e.x * e.y * e.z
        }
    }

    /// A box of the given centre and half-size.
    pub fn around(center: Vec3, half: Vec3) -> Aabb {
        Aabb {
            min: center - half,
            max: center + half,
        }
    }

    /// Six little-endian f32s: min then max. The codec every on-disk MBR uses.
    pub fn to_le_bytes(&self) -> [u8; 24] {
        let mut out = [0u8; 24];
        for (i, v) in self
            .min
            .to_array()
            .into_iter()
            .chain(self.max.to_array())
            .enumerate()
        {
            out[i * 4..i * 4 + 4].copy_from_slice(&v.to_le_bytes());
        }
        out
    }

    /// Inverse of [`Aabb::to_le_bytes`]; does not validate.
    pub fn from_le_bytes(b: &[u8; 24]) -> Aabb {
        let f = |i: usize| f32::from_le_bytes(b[i * 4..i * 4 + 4].try_into().unwrap());
        Aabb {
            min: Vec3::new(f(0), f(1), f(2)),
            max: Vec3::new(f(3), f(4), f(5)),
        }
    }
}

impl std::fmt::Display for Aabb {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "[{},{},{} .. {},{},{}]",
            self.min.x, self.min.y, self.min.z, self.max.x, self.max.y, self.max.z
        )
    }
}

impl std::str::FromStr for Aabb {
    type Err = Error;

    /// Parses `x0,y0,z0,x1,y1,z1`, as the CLI takes boxes.
    fn from_str(s: &str) -> Result<Aabb> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        if parts.len() != 6 {
            return Err(Error::BadBox(format!(
                "'{s}': expected six numbers x0,y0,z0,x1,y1,z1"
            )));
        }
        let mut v = [0f32; 6];
        for (slot, p) in v.iter_mut().zip(&parts) {
            *slot = p
                .parse()
                .map_err(|_| Error::BadBox(format!("'{s}': '{p}' is not a number")))?;
        }
        Aabb::new([v[0], v[1], v[2]], [v[3], v[4], v[5]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_and_inverted_boxes_are_errors() {
        assert!(Aabb::new([f32::NAN, 0.0, 0.0], [1.0, 1.0, 1.0]).is_err());
        assert!(Aabb::new([0.0, 0.0, 0.0], [1.0, f32::INFINITY, 1.0]).is_err());
        assert!(Aabb::new([0.0, 2.0, 0.0], [1.0, 1.0, 1.0]).is_err());
        assert!("1,2,3".parse::<Aabb>().is_err());
        assert!("0,0,0,1,1,x".parse::<Aabb>().is_err());
        assert!("0,0,0,nan,1,1".parse::<Aabb>().is_err());
    }

    #[test]
    fn zero_sized_boxes_are_valid_and_closed() {
        let p = Aabb::new([1.0, 1.0, 1.0], [1.0, 1.0, 1.0]).unwrap();
        let b = Aabb::new([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]).unwrap();
        assert!(b.overlaps(&p) && b.contains(&p) && p.volume() == 0.0);
    }

    #[test]
    fn codec_round_trips() {
        let b: Aabb = "-1,2.5,3,4,5,6".parse().unwrap();
        assert_eq!(Aabb::from_le_bytes(&b.to_le_bytes()), b);
    }
}
