// The detached house: one to three storeys of windowed walls on a plinth, string courses
// between storeys, a gable or hipped roof with overhanging eaves, often a chimney. It is
// the city's low-detail staple (a few hundred triangles, like the thesis's house base
// models at 240–1,812), so most of the city's bytes are spent here: keep it lean.

use glam::Vec3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::facade::{bays_across, facade, Bay, Wall};
use super::{place, roof, RoofStyle};
use crate::builder::MeshBuilder;
use crate::layout::Lot;
use flaneur_scene::Mesh;

/// Metres a house's body keeps clear of its lot edge (room for eaves and sills).
const CLEARANCE: f32 = 0.5;
/// About how wide one facade bay is, in metres, on a lot of the default 20 m pitch. Bays
/// scale with the lot, so a house's detail does not depend on the city's spacing.
const BAY: f32 = 4.4;

/// A house for `lot`, built in lot-local space and then placed.
pub(crate) fn house(rng: &mut ChaCha8Rng, lot: &Lot) -> Mesh {
    let b = lot.half - CLEARANCE;
    let hx = b * rng.gen_range(0.6..=1.0);
    let hz = b * rng.gen_range(0.55..=0.9);
    let floors: u32 = match rng.gen_range(0..20) {
        0..=4 => 1,
        5..=16 => 2,
        _ => 3,
    };
    let fh = rng.gen_range(2.8..=3.2);
    let wall_h = floors as f32 * fh;
    // A bungalow gets a window in every bay, with sills, to stay above ~250 triangles.
    let window_odds = if floors == 1 {
        1.0
    } else {
        rng.gen_range(0.55..=0.85)
    };
    let sills = floors == 1 || rng.gen_bool(0.5);
    let bay = BAY * lot.scale();

    let mut m = MeshBuilder::new();
    // Plinth and floor.
    m.cuboid(
        Vec3::new(-hx - 0.08, 0.0, -hz - 0.08),
        Vec3::new(hx + 0.08, 0.35, hz + 0.08),
    );
    for (i, wall) in Wall::box_sides(Vec3::ZERO, [hx, hz], wall_h)
        .iter()
        .enumerate()
    {
        let cols = bays_across(wall.width, bay).max(2);
        let door_col = cols / 2;
        facade(&mut m, wall, cols, floors, |col, row| {
            if i == 0 && row == 0 && col == door_col {
                Bay::Door
            } else if i == 0 || rng.gen_bool(window_odds) {
                Bay::Window { sill: sills }
            } else {
                Bay::Plain
            }
        });
    }
    // Door canopy over the front door.
    let door_w = 1.6_f32.min(2.0 * hx / 3.0);
    m.cuboid(
        Vec3::new(-door_w / 2.0, 2.5, -hz - 0.5),
        Vec3::new(door_w / 2.0, 2.62, -hz),
    );
    // String courses between storeys.
    for k in 1..floors {
        let y = k as f32 * fh;
        m.cuboid(
            Vec3::new(-hx - 0.1, y - 0.12, -hz - 0.1),
            Vec3::new(hx + 0.1, y + 0.05, hz + 0.1),
        );
    }
    let style = if rng.gen_bool(0.65) {
        RoofStyle::Gable
    } else {
        RoofStyle::Hip
    };
    let pitch = rng.gen_range(0.55_f32..=1.0); // rise over run
    let o = 0.3;
    let top = roof(&mut m, style, [hx + o, hz + o], wall_h, pitch);
    if rng.gen_bool(0.6) {
        let cx = hx * rng.gen_range(-0.6..=0.6);
        let cz = hz * 0.45;
        m.cuboid(
            Vec3::new(cx - 0.35, wall_h, cz - 0.35),
            Vec3::new(cx + 0.35, top + 0.6, cz + 0.35),
        );
    }
    place(m.finish(), lot)
}
