//! Our screen rule beside η: the screen-space test from a viewcell, and the factor τ is
//! stretched by for a faint object.

use crate::database::Database;
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::hdov::ScreenTest;
use crate::walk::settings::check_screen_tau;

/// The factor LOD selection stretches τ by for an object found with DoV `dov` under the
/// threshold `eta`, by our screen rule with stretch `stretch` ([`VisualConfig::faint_tau`](super::VisualConfig::faint_tau)):
/// `stretch` where the DoV is at most η, 1 above it. An object found has a DoV above 0
/// (a DoV of 0 prunes it), so under η = 0 none is stretched.
///
/// ```
/// use flaneur::walk::visual::faint_tau_scale;
/// assert_eq!(faint_tau_scale(0.0005, 0.001, 2.5), 2.5);
/// assert_eq!(faint_tau_scale(0.001, 0.001, 2.5), 2.5);
/// assert_eq!(faint_tau_scale(0.002, 0.001, 2.5), 1.0);
/// assert_eq!(faint_tau_scale(0.0005, 0.0, 2.5), 1.0);
/// ```
pub fn faint_tau_scale(dov: f32, eta: f32, stretch: f32) -> f32 {
    if dov > 0.0 && dov <= eta {
        stretch
    } else {
        1.0
    }
}

/// The screen-space test of the screen rule from viewcell `cell` of `db` under `tau` for
/// a vertical field of view `fov_y` (radians): from the cell's box, its eye heights
/// widened by the step an eye may take and stay in it
/// ([`viewcell_holding`](crate::walk::cells)), so that what passes it passes from every eye
/// the cell's finds are drawn for. An error for a database without visibility, or a τ
/// outside [0, 1).
pub fn screen_test(db: &Database, cell: u32, tau: f32, fov_y: f32) -> Result<ScreenTest> {
    check_screen_tau(tau)?;
    let vis = db.visibility()?.ok_or_else(|| {
        Error::Invalid(format!(
            "{} has no visibility: build it with --visibility",
            db.store().path().display()
        ))
    })?;
    let (row, column) = vis.grid.place(cell);
    let b = vis.grid.cell_bounds(row, column);
    let slack = glam::Vec3::new(0.0, crate::walk::cells::EYE_SLACK, 0.0);
    Ok(ScreenTest {
        from: Aabb {
            min: b.min - slack,
            max: b.max + slack,
        },
        fov_y,
        tau,
    })
}
