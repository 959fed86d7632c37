// A facade as a grid of bays, each plain, a recessed window or a recessed door. Windows
// are real holes with reveals and a pane set back into the wall — the detail that makes
// a building's triangle count look like a modelled one (18 triangles a window, 2 a plain
// bay, sills +12) — and the grid closes the wall surface exactly, so a building stays a
// closed solid. All archetypes share it; they differ in how they choose the bays.

use glam::Vec3;

use crate::builder::MeshBuilder;

/// What fills one bay of a facade grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Bay {
    /// Flat wall.
    Plain,
    /// A recessed window; `sill` adds a protruding sill under it.
    Window { sill: bool },
    /// A recessed door reaching the bottom of the bay.
    Door,
}

/// A vertical rectangular wall, seen from outside: `origin` is its bottom-left corner,
/// it runs `width` along `along` and `height` up, and faces `out`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Wall {
    pub origin: Vec3,
    pub along: Vec3,
    pub out: Vec3,
    pub width: f32,
    pub height: f32,
}

impl Wall {
    /// The four walls of the axis-aligned box footprint `center ± half` from `y0` to
    /// `y0 + height`, in order −z (the front), +x, +z, −x.
    pub(crate) fn box_sides(center: Vec3, half: [f32; 2], height: f32) -> [Wall; 4] {
        let side = |out: Vec3, half_out: f32, half_along: f32| {
            let along = Vec3::Y.cross(out);
            Wall {
                origin: center + out * half_out - along * half_along,
                along,
                out,
                width: 2.0 * half_along,
                height,
            }
        };
        [
            side(-Vec3::Z, half[1], half[0]),
            side(Vec3::X, half[0], half[1]),
            side(Vec3::Z, half[1], half[0]),
            side(-Vec3::X, half[0], half[1]),
        ]
    }

    /// A point on or behind the wall: `s` along, `t` up, `depth` into the wall.
    fn at(&self, s: f32, t: f32, depth: f32) -> Vec3 {
        self.origin + self.along * s + Vec3::Y * t - self.out * depth
    }
}

/// How deep openings are set into the wall, in metres.
const RECESS: f32 = 0.18;
/// How far a sill stands out of the wall, and its thickness and overhang, in metres.
const SILL_OUT: f32 = 0.12;
const SILL_THICK: f32 = 0.08;

/// Emits `wall` as `cols` × `rows` equal bays, asking `bay(col, row)` what each holds
/// (row 0 at the bottom, col 0 at the wall's left seen from outside).
pub(crate) fn facade(
    b: &mut MeshBuilder,
    wall: &Wall,
    cols: u32,
    rows: u32,
    mut bay: impl FnMut(u32, u32) -> Bay,
) {
    let (cw, rh) = (wall.width / cols as f32, wall.height / rows as f32);
    for row in 0..rows {
        for col in 0..cols {
            let (s0, t0) = (col as f32 * cw, row as f32 * rh);
            let (s1, t1) = (s0 + cw, t0 + rh);
            match bay(col, row) {
                Bay::Plain => {
                    let p = [
                        wall.at(s0, t0, 0.0),
                        wall.at(s1, t0, 0.0),
                        wall.at(s1, t1, 0.0),
                        wall.at(s0, t1, 0.0),
                    ];
                    b.quad(p, wall.out);
                }
                Bay::Window { sill } => {
                    let w = (cw * 0.55).min(1.8);
                    let h = (rh * 0.5).min(2.2);
                    let a0 = s0 + (cw - w) / 2.0;
                    let b0 = t0 + rh * 0.3;
                    opening(b, wall, [s0, s1, t0, t1], [a0, a0 + w, b0, b0 + h]);
                    if sill {
                        let lo = wall.at(a0 - 0.06, b0 - SILL_THICK, -SILL_OUT);
                        let hi = wall.at(a0 + w + 0.06, b0, 0.0);
                        b.cuboid(lo, hi);
                    }
                }
                Bay::Door => {
                    let w = (cw * 0.6).min(1.4);
                    let h = (rh * 0.8).min(2.4);
                    let a0 = s0 + (cw - w) / 2.0;
                    opening(b, wall, [s0, s1, t0, t1], [a0, a0 + w, t0, t0 + h]);
                }
            }
        }
    }
}

/// A bay `[s0, s1, t0, t1]` with a rectangular hole `[a0, a1, b0, b1]` recessed `RECESS`:
/// the wall round the hole, four reveals and the pane at the back.
fn opening(b: &mut MeshBuilder, wall: &Wall, bay: [f32; 4], hole: [f32; 4]) {
    let [s0, s1, t0, t1] = bay;
    let [a0, a1, b0, b1] = hole;
    let p = |s, t, d| wall.at(s, t, d);
    let out = wall.out;
    if b0 > t0 {
        // A window: the wall round the hole as one ring.
        let outer = [
            p(s0, t0, 0.0),
            p(s1, t0, 0.0),
            p(s1, t1, 0.0),
            p(s0, t1, 0.0),
        ];
        let inner = [
            p(a0, b0, 0.0),
            p(a1, b0, 0.0),
            p(a1, b1, 0.0),
            p(a0, b1, 0.0),
        ];
        b.frame(outer, inner, out);
    } else {
        // A door: the wall above, left and right of it.
        b.quad(
            [
                p(s0, b1, 0.0),
                p(s1, b1, 0.0),
                p(s1, t1, 0.0),
                p(s0, t1, 0.0),
            ],
            out,
        );
        b.quad(
            [
                p(s0, b0, 0.0),
                p(a0, b0, 0.0),
                p(a0, b1, 0.0),
                p(s0, b1, 0.0),
            ],
            out,
        );
        b.quad(
            [
                p(a1, b0, 0.0),
                p(s1, b0, 0.0),
                p(s1, b1, 0.0),
                p(a1, b1, 0.0),
            ],
            out,
        );
    }
    // Reveals: the sill faces up, the head down, the jambs face into the opening.
    let d = RECESS;
    b.quad(
        [p(a0, b0, 0.0), p(a1, b0, 0.0), p(a1, b0, d), p(a0, b0, d)],
        Vec3::Y,
    );
    b.quad(
        [p(a0, b1, 0.0), p(a1, b1, 0.0), p(a1, b1, d), p(a0, b1, d)],
        -Vec3::Y,
    );
    b.quad(
        [p(a0, b0, 0.0), p(a0, b1, 0.0), p(a0, b1, d), p(a0, b0, d)],
        wall.along,
    );
    b.quad(
        [p(a1, b0, 0.0), p(a1, b1, 0.0), p(a1, b1, d), p(a1, b0, d)],
        -wall.along,
    );
    // The pane.
    b.quad(
        [p(a0, b0, d), p(a1, b0, d), p(a1, b1, d), p(a0, b1, d)],
        out,
    );
}

/// Most bays a wall of `width` metres gets at about `bay` metres each (at least one).
pub(crate) fn bays_across(width: f32, bay: f32) -> u32 {
    ((width / bay).round() as u32).max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn walled_box_with_openings_is_closed() {
        let mut b = MeshBuilder::new();
        let walls = Wall::box_sides(Vec3::ZERO, [4.0, 3.0], 6.0);
        for (i, w) in walls.iter().enumerate() {
            facade(&mut b, w, 3, 2, |c, r| match (i, c, r) {
                (0, 1, 0) => Bay::Door,
                (_, _, 1) => Bay::Window { sill: false },
                _ => Bay::Plain,
            });
        }
        // Close top and bottom.
        let c = [(-4.0, -3.0), (4.0, -3.0), (4.0, 3.0), (-4.0, 3.0)];
        b.quad(c.map(|(x, z)| Vec3::new(x, 0.0, z)), -Vec3::Y);
        b.quad(c.map(|(x, z)| Vec3::new(x, 6.0, z)), Vec3::Y);
        let m = b.finish();
        m.validate().unwrap();
        // Volume of the box less the recesses: a little under 8 × 6 × 6.
        let v = m.signed_volume();
        assert!(v < 288.0 && v > 280.0, "volume {v}");
        // 4 walls × 6 bays: one door (door has no strip below: 16 tris), 12 windows (18), 11 plain (2).
        assert_eq!(m.triangle_count(), 16 + 12 * 18 + 11 * 2 + 4);
    }
}
