// The terrace: a row of two to six narrow units under one continuous roof, each with its
// own door, pilasters between units and chimneys on the party walls. It fills its lot
// across the street front and carries more windows than a house, which puts it in the
// middle of the city's detail range.

use glam::Vec3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::facade::{bays_across, facade, Bay, Wall};
use super::{place, roof, RoofStyle};
use crate::builder::MeshBuilder;
use crate::layout::Lot;
use flaneur_scene::Mesh;

/// Metres the body keeps clear of its lot edge (room for eaves and pilasters).
const CLEARANCE: f32 = 0.5;

/// A terrace for `lot`, built in lot-local space and then placed.
pub(crate) fn terrace(rng: &mut ChaCha8Rng, lot: &Lot) -> Mesh {
    let b = lot.half - CLEARANCE;
    let hx = b;
    let hz = b * rng.gen_range(0.5..=0.8);
    let units = ((2.0 * hx / (rng.gen_range(4.5_f32..=6.5) * lot.scale())) as u32).clamp(2, 6);
    let floors = rng.gen_range(2..=4_u32);
    let fh = rng.gen_range(2.8..=3.1);
    let wall_h = floors as f32 * fh;
    let back_odds = rng.gen_range(0.4..=0.7);
    let unit_w = 2.0 * hx / units as f32;

    let mut m = MeshBuilder::new();
    m.cuboid(
        Vec3::new(-hx - 0.05, 0.0, -hz - 0.05),
        Vec3::new(hx + 0.05, 0.3, hz + 0.05),
    );
    for (i, wall) in Wall::box_sides(Vec3::ZERO, [hx, hz], wall_h)
        .iter()
        .enumerate()
    {
        match i {
            // Front: two bays a unit, the door in each unit's first bay.
            0 => facade(&mut m, wall, 2 * units, floors, |col, row| {
                if row == 0 && col % 2 == 0 {
                    Bay::Door
                } else {
                    Bay::Window { sill: false }
                }
            }),
            // Back: two bays a unit, windows here and there.
            2 => facade(&mut m, wall, 2 * units, floors, |_, _| {
                if rng.gen_bool(back_odds) {
                    Bay::Window { sill: false }
                } else {
                    Bay::Plain
                }
            }),
            // Ends: mostly blank party walls.
            _ => facade(
                &mut m,
                wall,
                bays_across(wall.width, 4.0 * lot.scale()),
                floors,
                |_, row| {
                    if row > 0 && rng.gen_bool(0.3) {
                        Bay::Window { sill: false }
                    } else {
                        Bay::Plain
                    }
                },
            ),
        }
    }
    // Pilasters on the front between units, a cornice along the eaves line.
    for k in 1..units {
        let x = -hx + k as f32 * unit_w;
        m.cuboid(
            Vec3::new(x - 0.15, 0.3, -hz - 0.2),
            Vec3::new(x + 0.15, wall_h, -hz),
        );
    }
    m.cuboid(
        Vec3::new(-hx - 0.15, wall_h - 0.25, -hz - 0.25),
        Vec3::new(hx + 0.15, wall_h, hz + 0.15),
    );
    let style = if rng.gen_bool(0.7) {
        RoofStyle::Gable
    } else {
        RoofStyle::Hip
    };
    let top = roof(
        &mut m,
        style,
        [hx + 0.3, hz + 0.3],
        wall_h,
        rng.gen_range(0.5..=0.8),
    );
    // Chimneys on the party walls, astride the ridge.
    for k in 1..units {
        let x = -hx + k as f32 * unit_w;
        m.cuboid(
            Vec3::new(x - 0.4, wall_h, -0.3),
            Vec3::new(x + 0.4, top + 0.7, 0.3),
        );
    }
    place(m.finish(), lot)
}
