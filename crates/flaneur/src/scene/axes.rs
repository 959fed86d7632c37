//! The axes and units of imported OBJ files. flaneur is y-up in metres, as OBJ files from
//! games and most viewers are; GIS and many CAD exports are z-up, some in centimetres or
//! feet. An import is scaled (`--scale`) and turned z-up to y-up (`--up z`) before it is
//! built. Not told, it looks at the files' bounds: a city plainly z-up (much wider than
//! tall when z is up, and not when y is) is turned, and the build says so.

use glam::Vec3;

use crate::error::{Error, Result};
use crate::scene::Mesh;

/// Which axis of an OBJ import points up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum Up {
    /// y, unless the bounds plainly say z ([`plainly_z_up`]).
    #[default]
    Auto,
    /// y, as flaneur: nothing turned.
    Y,
    /// z: turned so that z points up (x stays, y becomes −z).
    Z,
}

impl std::str::FromStr for Up {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Up, String> {
        match s {
            "auto" => Ok(Up::Auto),
            "y" => Ok(Up::Y),
            "z" => Ok(Up::Z),
            other => Err(format!("'{other}': the up axis is y, z or auto")),
        }
    }
}

/// How an OBJ import is placed: its up axis and a scale to metres.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ObjAxes {
    /// The axis that points up in the files.
    pub up: Up,
    /// Metres per unit of the files (0.01 for centimetres, 0.3048 for feet).
    pub scale: f32,
}

impl Default for ObjAxes {
    fn default() -> ObjAxes {
        ObjAxes {
            up: Up::Auto,
            scale: 1.0,
        }
    }
}

impl ObjAxes {
    /// The scale must be a finite number above 0.
    pub fn validate(&self) -> Result<()> {
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(Error::Invalid(format!(
                "scale {} must be a finite number of metres per unit above 0",
                self.scale
            )));
        }
        Ok(())
    }
}

/// How an import was placed, for the build's summary.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Placed {
    /// The files were taken as z-up and turned.
    pub turned: bool,
    /// That was the bounds' verdict, not the user's word ([`Up::Auto`]).
    pub detected: bool,
    /// Metres per unit applied.
    pub scale: f32,
    /// The files' extent before anything was done (x, y, z), in their units.
    pub extent: [f32; 3],
}

/// Whether `meshes` are plainly a z-up city. Two things must say so. The buildings
/// stand on the ground: at least 80 % of them have their lowest point within 1 % of the
/// city's extent of the lowest z, while under half do of the lowest y (read y-up, their
/// bases would be scattered). And the city is wider than tall: z up, both of its sides
/// are at least twice its height. A single row of buildings, whose fronts line up, or
/// a city as tall as it is wide, is not plain, and is left as it is.
pub fn plainly_z_up(meshes: &[Mesh]) -> bool {
    let bounds: Vec<(Vec3, Vec3)> = meshes
        .iter()
        .filter(|m| !m.positions.is_empty())
        .map(|m| {
            let (lo, hi) = m.bounds();
            (Vec3::from(lo), Vec3::from(hi))
        })
        .collect();
    if bounds.len() < 2 {
        return false;
    }
    let lo = bounds.iter().fold(Vec3::INFINITY, |a, b| a.min(b.0));
    let hi = bounds.iter().fold(Vec3::NEG_INFINITY, |a, b| a.max(b.1));
    let e = hi - lo;
    let on_ground = |axis: usize| {
        let tolerance = 0.01 * e.max_element();
        let standing = bounds
            .iter()
            .filter(|b| b.0[axis] - lo[axis] <= tolerance)
            .count();
        standing as f64 / bounds.len() as f64
    };
    let wide = e.x.min(e.y) >= 2.0 * e.z;
    wide && on_ground(2) >= 0.8 && on_ground(1) < 0.5
}

/// Scales `meshes` and turns them z-up to y-up as `axes` says (by their bounds, for
/// [`Up::Auto`]). An error for a bad scale.
pub fn place(meshes: &mut [Mesh], axes: &ObjAxes) -> Result<Placed> {
    axes.validate()?;
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for m in meshes.iter() {
        for &p in &m.positions {
            lo = lo.min(Vec3::from(p));
            hi = hi.max(Vec3::from(p));
        }
    }
    let extent = if lo.x <= hi.x { hi - lo } else { Vec3::ZERO };
    let (turned, detected) = match axes.up {
        Up::Y => (false, false),
        Up::Z => (true, false),
        Up::Auto => {
            let z = plainly_z_up(meshes);
            (z, z)
        }
    };
    let s = axes.scale;
    for m in meshes.iter_mut() {
        for p in &mut m.positions {
            *p = if turned {
                [p[0] * s, p[2] * s, -p[1] * s]
            } else {
                [p[0] * s, p[1] * s, p[2] * s]
            };
        }
        if turned {
            for n in &mut m.normals {
                *n = [n[0], n[2], -n[1]];
            }
        }
    }
    Ok(Placed {
        turned,
        detected,
        scale: s,
        extent: extent.to_array(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box `w` wide and `h` tall standing on z = 0 at (x, y), z up.
    fn block(x: f32, y: f32, w: f32, h: f32) -> Mesh {
        let mut positions = Vec::new();
        for k in 0..8 {
            let bit = |b: usize| ((k >> b) & 1) as f32;
            positions.push([x + w * bit(0), y + w * bit(1), h * bit(2)]);
        }
        Mesh {
            normals: vec![[0.0, 0.0, 1.0]; 8],
            // Its base and its top, enough for bounds and a turn.
            indices: vec![0, 1, 3, 0, 3, 2, 4, 5, 7, 4, 7, 6],
            positions,
        }
    }

    /// A 4 × 4 grid of blocks 40 m apart, `h` tall, z up.
    fn z_up_city(h: f32) -> Vec<Mesh> {
        (0..16)
            .map(|i| block((i % 4) as f32 * 40.0, (i / 4) as f32 * 40.0, 20.0, h))
            .collect()
    }

    /// `meshes` written y up: (x, y, z) as (x, z, -y).
    fn as_y_up(mut meshes: Vec<Mesh>) -> Vec<Mesh> {
        for m in &mut meshes {
            for p in &mut m.positions {
                *p = [p[0], p[2], -p[1]];
            }
        }
        meshes
    }

    #[test]
    fn a_z_up_city_is_turned_y_up_and_keeps_its_handedness() {
        let mut m = z_up_city(30.0);
        let placed = place(
            &mut m,
            &ObjAxes {
                up: Up::Z,
                scale: 1.0,
            },
        )
        .unwrap();
        assert!(placed.turned && !placed.detected);
        // x stays, z becomes y (up), y becomes -z.
        assert_eq!(m[5].positions[7], [60.0, 30.0, -60.0]);
        assert_eq!(m[0].normals[0], [0.0, 1.0, 0.0]);
        // A turn, not a mirror: the top's normal turns with its points, to +y.
        let p = |i: usize| Vec3::from(m[0].positions[m[0].indices[i] as usize]);
        let n = (p(7) - p(6)).cross(p(8) - p(6)).normalize();
        assert!((n - Vec3::Y).length() < 1e-6, "{n}");
    }

    #[test]
    fn only_a_plainly_z_up_city_is_turned_unasked() {
        let mut city = z_up_city(30.0);
        let placed = place(&mut city, &ObjAxes::default()).unwrap();
        assert!(placed.turned && placed.detected, "{placed:?}");
        // The same city y up is left as it is.
        assert!(!plainly_z_up(&as_y_up(z_up_city(30.0))));
        // Taller than it is wide: nothing plain about it.
        assert!(!plainly_z_up(&z_up_city(100.0)));
        // One row of blocks, y up, 30 m tall and 20 m deep, fronts in line: its bases
        // line up on z as well as on y; left as it is.
        let row: Vec<Mesh> = (0..10)
            .map(|i| block(i as f32 * 40.0, 0.0, 20.0, 30.0))
            .collect();
        assert!(!plainly_z_up(&as_y_up(row)));
        // Told y, a z-up city stays as it is.
        let mut told = z_up_city(30.0);
        let placed = place(
            &mut told,
            &ObjAxes {
                up: Up::Y,
                scale: 1.0,
            },
        )
        .unwrap();
        assert!(!placed.turned && told[0].positions[7] == [20.0, 20.0, 30.0]);
    }

    #[test]
    fn the_scale_is_applied_and_checked() {
        let mut m = z_up_city(30.0);
        place(
            &mut m,
            &ObjAxes {
                up: Up::Y,
                scale: 0.01,
            },
        )
        .unwrap();
        let top = Vec3::from(m[0].positions[7]);
        assert!((top - Vec3::new(0.2, 0.2, 0.3)).length() < 1e-6, "{top}");
        for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            let e = place(
                &mut m,
                &ObjAxes {
                    up: Up::Y,
                    scale: bad,
                },
            )
            .unwrap_err();
            assert!(e.to_string().contains("scale"), "{e}");
        }
    }
}
