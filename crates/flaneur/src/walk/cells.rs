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
        return Err(Error::Invalid(format!(
            "disk cell size {size} must be a positive number of metres"
        )));
    }
    if !eye.is_finite() {
        return Err(Error::Invalid(format!(
            "camera position {eye} is not finite"
        )));
    }
    let half = size * 0.5;
    let (lo, hi) = (bounds.min, bounds.max);
    if eye.x < lo.x - half || eye.x > hi.x + half || eye.z < lo.z - half || eye.z > hi.z + half {
        return Err(Error::Invalid(format!(
            "camera at {eye} is outside the city {bounds}"
        )));
    }
    Aabb::new(
        [eye.x - half, bounds.min.y.min(eye.y), eye.z - half],
        [eye.x + half, bounds.max.y.max(eye.y), eye.z + half],
    )
}

/// REVIEW's disk cell (Shou 2002 §4.1, §4.4): the frustum cell `fcell` scaled by `sf` on
/// the ground and centred on `center`, spanning the city's whole height. Cells are
/// compared on the ground only (every object stands between the city's lowest and
/// highest point anyway), and the cell always holds the frustum cell, even when the
/// centre is a prediction elsewhere.
pub fn scaled_cell(bounds: &Aabb, fcell: &Aabb, center: Vec3, sf: f32) -> Aabb {
    let half = fcell.extent() * 0.5 * sf;
    let lo = Vec3::new(center.x - half.x, bounds.min.y, center.z - half.z);
    let hi = Vec3::new(center.x + half.x, bounds.max.y, center.z + half.z);
    let ground = Aabb {
        min: Vec3::new(fcell.min.x, bounds.min.y, fcell.min.z),
        max: Vec3::new(fcell.max.x, bounds.max.y, fcell.max.z),
    };
    Aabb { min: lo, max: hi }.union(&ground)
}

/// The walkable viewcell of `db` whose box holds `p`: its patch of ground, and between
/// its eye heights give or take [`EYE_SLACK`] (an eye above them, over the roofs, sees
/// what the cell's PVS was not computed for). `None` without visibility.
pub(crate) fn viewcell_holding(db: &crate::Database, p: Vec3) -> Result<Option<u32>> {
    let (Some(cell), Some(vis)) = (db.viewcell_at(p)?, db.visibility()?) else {
        return Ok(None);
    };
    let (row, column) = vis.grid.place(cell);
    let b = vis.grid.cell_bounds(row, column);
    Ok((b.min.y - EYE_SLACK..=b.max.y + EYE_SLACK)
        .contains(&p.y)
        .then_some(cell))
}

/// How far, in metres, an eye may be above or below its cell's eye heights and still be
/// in it: a walker's step up a kerb.
pub(crate) const EYE_SLACK: f32 = 0.5;

/// Whether `outer` holds `inner` on the ground plane (x and z).
pub fn contains_ground(outer: &Aabb, inner: &Aabb) -> bool {
    outer.min.x <= inner.min.x
        && outer.min.z <= inner.min.z
        && inner.max.x <= outer.max.x
        && inner.max.z <= outer.max.z
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
