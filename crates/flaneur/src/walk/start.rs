//! Where a viewer starts: on the city's busiest street.
//!
//! The database holds buildings, not streets, so "busiest street" is found from them: on
//! a grid of points at eye height over the city, a point is on a street when no object
//! box comes within [`CLEARANCE`] of it, and its street's direction is the axis along which the view runs
//! farthest before meeting a box. A point's business is the number of objects whose
//! boxes lie within [`NEIGHBOURHOOD`] metres of it; the busiest free point wins, ties to
//! the one nearest the city's centre, looking down its street. Range queries only: the
//! pages they read are the start's, before any walk begins.

use glam::Vec3;

use crate::database::Database;
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::path::Pose;
use crate::path::EYE_HEIGHT;

/// The half-side of the box around a point whose objects count as its neighbours, metres.
const NEIGHBOURHOOD: f32 = 60.0;
/// How far a point on a street is from every object, metres (citygen's streets are
/// 14 m wide by default).
const CLEARANCE: f32 = 3.0;
/// Grid points per side.
const GRID: usize = 48;
/// How far the view along a street is probed, metres.
const PROBE: f32 = 120.0;

/// A pose at eye height on the busiest street of `db`'s city, looking along it: where a
/// viewer starts.
///
/// Found from the buildings, the database holding no streets: of a 48 × 48 grid of
/// points at eye height over the city, those no object box comes within 3 m of are on a
/// street; the one with the most objects within 60 m wins (ties to the one nearest the
/// city's centre), looking along the axis on which the view runs farthest before it
/// meets a box. Range queries only, their pages read before any walk begins. An error
/// when no point is clear of every object.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # let city = citygen::CityConfig { objects: 60, landmarks: 0.0, ..Default::default() };
/// # citygen::write_city(&city, &scene)?;
/// # let opts = flaneur::BuildOptions { lod: None, ..Default::default() };
/// # flaneur::build_from_scene(&scene, &path, &opts)?;
/// let db = flaneur::Database::open(&path)?;
/// let start = flaneur::walk::busiest_street(&db)?;
/// let around = glam::Vec3::new(2.9, 0.5, 2.9);
/// let near = db.range(&flaneur::geom::Aabb::around(start.position, around))?;
/// assert!(near.objects.is_empty(), "a street, clear of every building");
/// # Ok(()) }
/// ```
pub fn busiest_street(db: &Database) -> Result<Pose> {
    let b = db.bounds();
    let y = b.min.y + EYE_HEIGHT;
    let mut best: Option<(usize, f32, Vec3)> = None;
    for i in 0..GRID {
        for j in 0..GRID {
            let t = |k: usize| (k as f32 + 0.5) / GRID as f32;
            let p = Vec3::new(
                b.min.x + t(i) * (b.max.x - b.min.x),
                y,
                b.min.z + t(j) * (b.max.z - b.min.z),
            );
            let near = db.range(&Aabb::around(
                p,
                Vec3::new(NEIGHBOURHOOD, b.max.y - b.min.y + 1.0, NEIGHBOURHOOD),
            ))?;
            // A street, not a gap between two lots: nothing within a few metres.
            let clear = Aabb::around(p, Vec3::new(CLEARANCE, 0.5, CLEARANCE));
            if near.objects.iter().any(|o| o.bounds.overlaps(&clear)) {
                continue;
            }
            let from_centre = (p - b.center()).length();
            let better = match best {
                None => true,
                Some((n, d, _)) => {
                    near.objects.len() > n || (near.objects.len() == n && from_centre < d)
                }
            };
            if better {
                best = Some((near.objects.len(), from_centre, p));
            }
        }
    }
    let (_, _, p) = best.ok_or_else(|| {
        Error::Invalid(format!(
            "{}: no point at eye height is outside every object; nowhere to stand",
            db.store().path().display()
        ))
    })?;
    // Look along the axis the view runs farthest on before a box stops it.
    let near = db.range(&Aabb::around(p, Vec3::new(PROBE, 1.0, PROBE)))?;
    let yaws = [
        0.0,
        std::f32::consts::FRAC_PI_2,
        std::f32::consts::PI,
        3.0 * std::f32::consts::FRAC_PI_2,
    ];
    let clear = |yaw: f32| {
        let d = Vec3::new(yaw.cos(), 0.0, yaw.sin());
        near.objects
            .iter()
            .filter_map(|o| ray_box(p, d, &o.bounds))
            .fold(PROBE, f32::min)
    };
    let yaw = yaws
        .into_iter()
        .max_by(|&a, &b| clear(a).total_cmp(&clear(b)))
        .unwrap_or(0.0);
    Ok(Pose {
        time: 0.0,
        position: p,
        yaw,
        pitch: 0.0,
    })
}

/// The distance along the ray from `o` in direction `d` to box `b`, if it meets it
/// ahead (slab test).
fn ray_box(o: Vec3, d: Vec3, b: &Aabb) -> Option<f32> {
    let (mut near, mut far) = (0f32, f32::INFINITY);
    for k in 0..3 {
        if d[k].abs() < 1e-9 {
            if o[k] < b.min[k] || o[k] > b.max[k] {
                return None;
            }
            continue;
        }
        let (t1, t2) = ((b.min[k] - o[k]) / d[k], (b.max[k] - o[k]) / d[k]);
        near = near.max(t1.min(t2));
        far = far.min(t1.max(t2));
    }
    (near <= far).then_some(near)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ray_meets_a_box_ahead_only() {
        let b = Aabb::new([5.0, 0.0, -1.0], [6.0, 10.0, 1.0]).unwrap();
        assert_eq!(ray_box(Vec3::new(0.0, 1.0, 0.0), Vec3::X, &b), Some(5.0));
        assert_eq!(ray_box(Vec3::new(0.0, 1.0, 0.0), -Vec3::X, &b), None);
        assert_eq!(ray_box(Vec3::new(0.0, 1.0, 3.0), Vec3::X, &b), None);
    }
}
