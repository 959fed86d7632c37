//! Disk cells (Shou 2002 §4.1): the axis-aligned box around the viewer whose objects
//! are kept in memory. A new disk cell is queried when the viewer leaves the old
//! one's inner margin; consecutive disk cells overlap, which is what CSearch exploits.

use glam::Vec3;

use crate::error::{Error, Result};
use crate::geom::Aabb;

/// The disk cell of side `size` (metres, on the ground plane) centred on `eye`,
/// spanning the whole height of the city `bounds` so tall objects are not cut.
pub fn disk_cell(eye: Vec3, size: f32, bounds: &Aabb) -> Result<Aabb> {
    if !(size.is_finite() && size > 0.0) {
        return Err(Error::Invalid(format!("disk cell size {size} must be a positive number of metres")));
    }
    if !eye.is_finite() {
        return Err(Error::Invalid(format!("camera position {eye} is not finite")));
    }
    let half = size * 0.5;
    let (lo, hi) = (bounds.min, bounds.max);
    if eye.x < lo.x - half || eye.x > hi.x + half || eye.z < lo.z - half || eye.z > hi.z + half {
        return Err(Error::Invalid(format!("camera at {eye} is outside the city {bounds}")));
    }
    Aabb::new(
        [eye.x - half, bounds.min.y.min(eye.y), eye.z - half],
        [eye.x + half, bounds.max.y.max(eye.y), eye.z + half],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outside_and_nan_are_errors() {
        let city = Aabb::new([0.0, 0.0, 0.0], [100.0, 30.0, 100.0]).unwrap();
        assert!(disk_cell(Vec3::new(50.0, 2.0, 50.0), 40.0, &city).is_ok());
        assert!(disk_cell(Vec3::new(500.0, 2.0, 50.0), 40.0, &city).is_err());
        assert!(disk_cell(Vec3::new(f32::NAN, 2.0, 50.0), 40.0, &city).is_err());
        assert!(disk_cell(Vec3::new(50.0, 2.0, 50.0), 0.0, &city).is_err());
    }
}
