// The tower: 20–120 m in one to four setback tiers, each narrower than the one below,
// a ledge at every setback, a plant room and, when tall, a mast. Taller towers stand
// nearer the city centre, so the skyline has a downtown. Every storey reads on the
// facade, within a triangle budget (540–1,800, like the thesis's tower models at
// 540–1,702): a tower whose storeys all fit as punched windows (18 triangles each) gets
// them; a taller one gets a recessed ribbon window round each storey (32 triangles a
// storey, whatever its width) and vertical fins from what budget is left.

use glam::Vec3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::facade::{bays_across, facade, Bay, Wall};
use super::place;
use crate::builder::MeshBuilder;
use crate::layout::Lot;
use flaneur_scene::Mesh;

/// Metres the base tier keeps clear of its lot edge (room for ledges and fins).
const CLEARANCE: f32 = 0.6;
/// Triangles a punched window bay costs (see `facade`).
const WINDOW_TRIS: u32 = 18;
/// Triangles a ribbon storey costs: spandrel, two reveal rings, glass.
const RIBBON_TRIS: u32 = 32;
/// Triangles a tier costs beyond its storeys: parapet, roof, ledge.
const TIER_TRIS: u32 = 8 + 2 + 12;
/// Triangles beyond the tiers: base, plant room, mast, the door's share.
const FIXED_TRIS: u32 = 2 + 12 + 12 + 16;
/// Parapet above a ribbon tier's last storey, in metres.
const PARAPET: f32 = 0.9;
/// How far ribbon glazing is set back, and how far fins stand out, in metres.
const RIBBON_DEPTH: f32 = 0.3;
const FIN_OUT: f32 = 0.3;

struct Tier {
    half: [f32; 2],
    floors: u32,
    /// Bays across the x and z sides.
    cols: [u32; 2],
}

/// A tower for `lot`, built in lot-local space and then placed.
pub(crate) fn tower(rng: &mut ChaCha8Rng, lot: &Lot) -> Mesh {
    let b = lot.half - CLEARANCE;
    let mut half = [b * rng.gen_range(0.7..=1.0), b * rng.gen_range(0.7..=1.0)];
    // Height: the exponent shrinks towards the centre, pulling draws up to 120 m.
    let u: f32 = rng.gen_range(0.0..1.0);
    let height = 20.0 + 100.0 * u.powf(3.0 - 2.5 * lot.centrality);
    let fh = rng.gen_range(3.3..=3.8);
    let floors = ((height / fh) as u32).max(6);
    let n_tiers = (1 + (height / 40.0) as u32 + rng.gen_range(0..=1)).min(4);
    // Budget: taller towers get more detail.
    let budget =
        (540.0 + 1260.0 * (floors as f32 / 34.0).min(1.0) * rng.gen_range(0.7..=1.0)) as u32;

    // Split the storeys among the tiers (the base tier takes the most), setting back.
    let mut tiers = Vec::with_capacity(n_tiers as usize);
    let mut left = floors;
    for t in 0..n_tiers {
        let f = if t + 1 == n_tiers {
            left
        } else {
            ((left as f32 * rng.gen_range(0.4..=0.6)) as u32).clamp(1, left - (n_tiers - t - 1))
        };
        let cols = [0, 1].map(|a| bays_across(2.0 * half[a], 3.0 * lot.scale()).clamp(2, 8));
        tiers.push(Tier {
            half,
            floors: f,
            cols,
        });
        left -= f;
        let shrink = rng.gen_range(0.7..=0.85);
        half = [0, 1].map(|a| (half[a] * shrink).max(2.5).min(half[a]));
    }
    let fixed = FIXED_TRIS + n_tiers * TIER_TRIS;
    let punched: u32 = tiers
        .iter()
        .map(|t| 2 * (t.cols[0] + t.cols[1]) * t.floors * WINDOW_TRIS)
        .sum();
    // Ribbons always fit: the budget grows faster with the storeys than they cost.
    let ribbon = fixed + punched > budget;

    let mut m = MeshBuilder::new();
    let ring = |h: [f32; 2], y: f32| {
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(x, z)| Vec3::new(x * h[0], y, z * h[1]))
    };
    m.quad(ring(tiers[0].half, 0.0), -Vec3::Y);
    // Fins share what the ribbons leave of the budget, evenly over the tiers' sides.
    let spare = budget.saturating_sub(fixed + floors * RIBBON_TRIS);
    let fins_per_side = (spare / (12 * 4 * n_tiers)).min(6);
    let mut base = 0.0;
    for (ti, t) in tiers.iter().enumerate() {
        let h = t.floors as f32 * fh;
        let top = if ribbon {
            ribbon_tier(&mut m, t, base, fh, fins_per_side)
        } else {
            let walls = Wall::box_sides(Vec3::new(0.0, base, 0.0), t.half, h);
            for (i, wall) in walls.iter().enumerate() {
                let n = t.cols[i % 2];
                facade(&mut m, wall, n, t.floors, |col, row| {
                    if ti == 0 && i == 0 && row == 0 && col == n / 2 {
                        Bay::Door
                    } else {
                        Bay::Window { sill: false }
                    }
                });
            }
            base + h
        };
        m.quad(ring(t.half, top), Vec3::Y);
        let e = 0.35;
        m.cuboid(
            Vec3::new(-t.half[0] - e, top - 0.3, -t.half[1] - e),
            Vec3::new(t.half[0] + e, top, t.half[1] + e),
        );
        base = top;
    }
    let last = tiers.last().expect("at least one tier");
    let plant = [last.half[0] * 0.5, last.half[1] * 0.5];
    m.cuboid(
        Vec3::new(-plant[0], base, -plant[1]),
        Vec3::new(plant[0], base + 3.5, plant[1]),
    );
    if height > 60.0 {
        m.cuboid(
            Vec3::new(-0.3, base + 3.5, -0.3),
            Vec3::new(0.3, base + 3.5 + height * 0.12, 0.3),
        );
    }
    place(m.finish(), lot)
}

/// One tier of ribbon storeys from `base`: per storey a solid spandrel, then a glazed
/// band set back `RIBBON_DEPTH` all round; a parapet on top; `fins` fins a side.
/// Returns the height of the tier's top.
fn ribbon_tier(m: &mut MeshBuilder, t: &Tier, base: f32, fh: f32, fins: u32) -> f32 {
    let ring = |h: [f32; 2], y: f32| {
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(x, z)| Vec3::new(x * h[0], y, z * h[1]))
    };
    let inset = [t.half[0] - RIBBON_DEPTH, t.half[1] - RIBBON_DEPTH];
    // The four vertical sides of the box `half` between y0 and y1.
    let sides = |m: &mut MeshBuilder, half: [f32; 2], y0: f32, y1: f32| {
        for wall in Wall::box_sides(Vec3::new(0.0, y0, 0.0), half, y1 - y0) {
            facade(m, &wall, 1, 1, |_, _| Bay::Plain);
        }
    };
    let spandrel = fh * 0.4;
    for f in 0..t.floors {
        let y0 = base + f as f32 * fh;
        let (y1, y2) = (y0 + spandrel, y0 + fh);
        sides(m, t.half, y0, y1);
        m.frame(ring(t.half, y1), ring(inset, y1), Vec3::Y);
        sides(m, inset, y1, y2);
        m.frame(ring(t.half, y2), ring(inset, y2), -Vec3::Y);
    }
    let top = base + t.floors as f32 * fh + PARAPET;
    sides(m, t.half, top - PARAPET, top);
    for wall in Wall::box_sides(Vec3::new(0.0, base, 0.0), t.half, top - base) {
        for k in 1..=fins {
            let s = wall.width * k as f32 / (fins + 1) as f32;
            let c = wall.origin + wall.along * s;
            m.cuboid(
                c - wall.along * 0.15,
                c + wall.along * 0.15 + wall.out * FIN_OUT + Vec3::Y * (top - base),
            );
        }
    }
    top
}
