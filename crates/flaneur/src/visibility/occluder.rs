//! An object's occluder: a box inside its solid, for the conservative from-region test
//! (Shou 2002 §5.5.1), which assumes large convex occluders.
//!
//! A building with setbacks, recessed windows and a pitched roof is not convex, so the
//! test uses a convex part of it, as paper-notes advise: the largest box found inside
//! the solid that stands on its footprint. Whatever lies behind that box from a whole
//! viewcell lies behind the building too, so the PVS stays conservative.
//!
//! Choices made here:
//! - A building is often a stack of shells (a plinth, storeys as open tubes of wall, a
//!   slab between them, a roof) whose faces do not make one consistently oriented
//!   solid; what matters for occlusion is only that a sight line into the box must
//!   cross a face. So the box must lie where the faces enclose: a point is enclosed
//!   when a ray from it in each of the six axis directions (tilted a little, so as not
//!   to run along a wall) meets a face, and a face is on the outside when a point just
//!   off either side of it, at its centre or halfway from there to a corner, is not
//!   enclosed. Only outside faces bound the box, and its centre must be enclosed.
//! - Candidates stand on the ground of the object's bounds and are its footprint inset
//!   by an even margin, at eight heights (an eighth of the object's height to all of
//!   it). For each height the smallest margin is found by bisection (each step exact:
//!   no outside face may meet the box), and the candidate with the largest
//!   silhouette, (width + depth) × height, wins. Boxes lower than 2 m or narrower than
//!   1 m are not worth testing against and give none.
//! - A mesh with a hole escapes through it: its faces there are outside faces and its
//!   box, if any, stays clear of the hole's sight lines.
//! - Each candidate's sides are then pushed out one at a time as far as they stay
//!   free, so a notch or recess on one side does not cost the others.
//! - Up to two more boxes are stacked, each the best that stands on the one below (at
//!   least 1 m high): the inside of a roof, a setback tier. The other ground
//!   candidates that no taller one covers (a wide plinth under a narrow tower) follow
//!   them: they hide what their own footprints do.
//! - Each box is shrunk by 1 cm at the end, so rounding in the tests that use it cannot
//!   let it poke out of the solid.

use glam::Vec3;

use super::intersect::{ray_triangle_distance, triangle_meets_box, triangles};
use crate::geom::Aabb;
use crate::scene::Mesh;

/// Candidate heights, as eighths of the object's height.
const HEIGHTS: u32 = 8;
/// Bisection steps on the margin: 2^-14 of the half-width, well under a centimetre.
const STEPS: u32 = 14;
/// What the found box is shrunk by, in metres.
const SAFETY: f32 = 0.01;
const MIN_HEIGHT: f32 = 2.0;
/// Boxes stacked on the first (a roof's inside, a setback tier), and the least height
/// of one.
const STACKED: usize = 3;
const MIN_UPPER_HEIGHT: f32 = 1.0;
const MIN_WIDTH: f32 = 1.0;
/// How far outside a face its samples are taken, in metres.
const PROBE: f32 = 1e-3;
/// Columns of the grids that sort faces for the enclosure rays, per side.
const COLUMNS: usize = 16;

/// Boxes inside `mesh`'s solid: the first standing on its footprint, each next on the
/// one below, then other boxes standing on the footprint that none of those covers
/// (wider and lower ones); none when there is no worthwhile one (the mesh is small,
/// flat, open, or does not stand on its bounds' ground).
pub fn occluder_boxes(mesh: &Mesh) -> Vec<Aabb> {
    let mut boxes = Vec::new();
    if mesh.validate().is_err() || mesh.triangle_count() == 0 {
        return boxes;
    }
    let (lo, hi) = mesh.bounds();
    let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
    let size = hi - lo;
    if size.y < MIN_HEIGHT || size.x.min(size.z) < MIN_WIDTH {
        return boxes;
    }
    let solid = Solid::new(mesh, lo, hi);
    let outside: Vec<[Vec3; 3]> = solid
        .triangles
        .iter()
        .filter(|t| solid.is_outside(t))
        .copied()
        .collect();
    let free = |b: &Aabb| !outside.iter().any(|t| triangle_meets_box(t, b));
    let mut floor = lo.y;
    let mut extra: Vec<Aabb> = Vec::new();
    while boxes.len() < STACKED {
        let min_height = if boxes.is_empty() {
            MIN_HEIGHT
        } else {
            MIN_UPPER_HEIGHT
        };
        let mut best: Option<(f32, Aabb)> = None;
        let mut ground: Vec<Aabb> = Vec::new();
        for k in 1..=HEIGHTS {
            // A hair under the level, or a roof lying on it would always meet the box.
            let height = (hi.y - floor) * k as f32 / HEIGHTS as f32 - SAFETY;
            if height < min_height {
                continue;
            }
            let Some(b) = widest_free(lo, hi, floor, height, &free) else {
                continue;
            };
            if boxes.is_empty() {
                ground.push(b);
            }
            let score = (b.max.x - b.min.x + b.max.z - b.min.z) * height;
            if best.is_none_or(|(s, _)| score > s) {
                best = Some((score, b));
            }
        }
        let Some((_, b)) = best else { break };
        if !solid.encloses(b.center()) {
            break;
        }
        floor = b.max.y;
        let inset = |b: &Aabb| Aabb {
            min: b.min + Vec3::splat(SAFETY),
            max: b.max - Vec3::splat(SAFETY),
        };
        boxes.push(inset(&b));
        // The other boxes standing on the ground that no taller one covers (a wide
        // plinth beside a narrow tower): each hides what its own footprint does.
        for (i, g) in ground.iter().enumerate() {
            let covered = |h: &Aabb| {
                h.max.y >= g.max.y
                    && h.min.x <= g.min.x
                    && h.min.z <= g.min.z
                    && h.max.x >= g.max.x
                    && h.max.z >= g.max.z
            };
            let dominated = covered(&b)
                || ground
                    .iter()
                    .enumerate()
                    .any(|(j, h)| j != i && covered(h) && (h != g || j < i));
            if !dominated && solid.encloses(g.center()) {
                extra.push(inset(g));
            }
        }
    }
    boxes.extend(extra);
    boxes
}

/// The footprint box from `floor` up `height`, inset by the smallest even margin (to
/// a bisection's precision) that leaves it meeting no outside face, then each side
/// pushed back out on its own as far as it stays free; `None` when even the narrowest
/// worthwhile box meets one.
fn widest_free(
    lo: Vec3,
    hi: Vec3,
    floor: f32,
    height: f32,
    free: &impl Fn(&Aabb) -> bool,
) -> Option<Aabb> {
    // A floor face would always meet a box standing on it: the boxes tested stand a
    // hair above their floor.
    let candidate = |margin: f32| Aabb {
        min: Vec3::new(lo.x + margin, floor + SAFETY, lo.z + margin),
        max: Vec3::new(hi.x - margin, floor + height, hi.z - margin),
    };
    let narrowest = 0.5 * ((hi.x - lo.x).min(hi.z - lo.z) - MIN_WIDTH) - SAFETY;
    if narrowest < 0.0 || !free(&candidate(narrowest)) {
        return None;
    }
    // `bad` is a margin known to meet a face (or to be the bounds' own), `good` one
    // known to be free.
    let (mut bad, mut good) = (0.0f32, narrowest);
    if free(&candidate(0.0)) {
        good = 0.0;
    } else {
        for _ in 0..STEPS {
            let mid = 0.5 * (bad + good);
            if free(&candidate(mid)) {
                good = mid;
            } else {
                bad = mid;
            }
        }
    }
    // Then each side on its own, out from the even margin as far as it stays free: a
    // footprint with a notch or a recess on one side keeps its other sides.
    let mut b = candidate(good);
    for side in 0..4 {
        let (axis, low) = ([0, 0, 2, 2][side], side % 2 == 0);
        let at = |b: &Aabb, margin: f32| {
            let mut c = *b;
            if low {
                c.min[axis] = lo[axis] + margin;
            } else {
                c.max[axis] = hi[axis] - margin;
            }
            c
        };
        let (mut bad, mut ok) = (0.0f32, good);
        if free(&at(&b, 0.0)) {
            ok = 0.0;
        } else {
            for _ in 0..STEPS {
                let mid = 0.5 * (bad + ok);
                if free(&at(&b, mid)) {
                    ok = mid;
                } else {
                    bad = mid;
                }
            }
        }
        b = at(&b, ok);
    }
    b.min.y = floor;
    Some(b)
}

/// The six directions an enclosed point's rays take: the axes, tilted a little.
const DIRECTIONS: [Vec3; 6] = [
    Vec3::new(1.0, 0.0021, 0.0013),
    Vec3::new(-1.0, -0.0017, 0.0023),
    Vec3::new(0.0013, 1.0, 0.0021),
    Vec3::new(-0.0023, -1.0, -0.0011),
    Vec3::new(0.0021, 0.0013, 1.0),
    Vec3::new(-0.0011, 0.0023, -1.0),
];

/// An object's triangles, sorted into columns along each axis for the rays that tell
/// enclosed points from open ones.
struct Solid {
    triangles: Vec<[Vec3; 3]>,
    /// Per axis: the columns of faces that rays along that axis may meet.
    grids: [Columns; 3],
}

/// Faces sorted into a square grid of columns across one axis.
struct Columns {
    /// The two axes across the columns.
    across: [usize; 2],
    lo: [f32; 2],
    cell: [f32; 2],
    columns: Vec<Vec<u32>>,
}

impl Columns {
    fn new(axis: usize, triangles: &[[Vec3; 3]], lo: Vec3, hi: Vec3) -> Columns {
        let across = [(axis + 1) % 3, (axis + 2) % 3];
        let cell = across.map(|a| ((hi[a] - lo[a]) / COLUMNS as f32).max(1e-3));
        let lo2 = across.map(|a| lo[a]);
        // A tilted ray drifts sideways as it goes: a face joins every column the drift
        // can bring a ray into.
        let drift = (hi - lo).max_element() * 0.0025 + PROBE;
        let mut columns = vec![Vec::new(); COLUMNS * COLUMNS];
        for (i, t) in triangles.iter().enumerate() {
            let tlo = t[0].min(t[1]).min(t[2]) - Vec3::splat(drift);
            let thi = t[0].max(t[1]).max(t[2]) + Vec3::splat(drift);
            let range = |k: usize| {
                let f =
                    |v: f32| (((v - lo2[k]) / cell[k]).floor().max(0.0) as usize).min(COLUMNS - 1);
                f(tlo[across[k]])..=f(thi[across[k]])
            };
            for r in range(1) {
                for c in range(0) {
                    columns[r * COLUMNS + c].push(i as u32);
                }
            }
        }
        Columns {
            across,
            lo: lo2,
            cell,
            columns,
        }
    }

    /// The faces a ray along the axis from `p` may meet; none when `p` is beside the
    /// bounds, where such a ray meets nothing.
    fn column(&self, p: Vec3) -> &[u32] {
        let k = |i: usize| ((p[self.across[i]] - self.lo[i]) / self.cell[i]).floor();
        let (c, r) = (k(0), k(1));
        if c < 0.0 || r < 0.0 || c >= COLUMNS as f32 || r >= COLUMNS as f32 {
            return &[];
        }
        &self.columns[r as usize * COLUMNS + c as usize]
    }
}

impl Solid {
    fn new(mesh: &Mesh, lo: Vec3, hi: Vec3) -> Solid {
        let triangles = triangles(mesh);
        let grids = [0, 1, 2].map(|axis| Columns::new(axis, &triangles, lo, hi));
        Solid { triangles, grids }
    }

    /// Whether every one of the six rays from `p` meets a face.
    fn encloses(&self, p: Vec3) -> bool {
        DIRECTIONS.iter().enumerate().all(|(k, &dir)| {
            self.grids[k / 2]
                .column(p)
                .iter()
                .any(|&i| ray_triangle_distance(p, dir, &self.triangles[i as usize]).is_some())
        })
    }

    /// Whether the face `t` is on the outside somewhere: a point just off either side
    /// of it, at its centre or halfway from there to a corner, is not enclosed.
    fn is_outside(&self, t: &[Vec3; 3]) -> bool {
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        if n.length_squared() == 0.0 {
            return false;
        }
        let off = n.normalize() * PROBE;
        let centre = (t[0] + t[1] + t[2]) / 3.0;
        [
            centre,
            0.5 * (centre + t[0]),
            0.5 * (centre + t[1]),
            0.5 * (centre + t[2]),
        ]
        .into_iter()
        .any(|p| !self.encloses(p + off) || !self.encloses(p - off))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buildings_get_an_occluder_inside_them() {
        let objects = crate::visibility::tests::city(60);
        let (mut found, mut total) = (0, 0.0);
        for o in &objects {
            let boxes = occluder_boxes(&o.mesh);
            if boxes.is_empty() {
                continue;
            }
            found += 1;
            let (lo, hi) = o.mesh.bounds();
            let bounds = Aabb::new(lo, hi).unwrap();
            // The stacked boxes, then the others standing on the ground.
            let on_ground = |b: &Aabb| b.min.y <= boxes[0].min.y + 1e-4;
            let stacked = 1 + boxes[1..].iter().take_while(|b| !on_ground(b)).count();
            assert!(boxes[stacked..].iter().all(on_ground));
            for w in boxes[..stacked].windows(2) {
                assert!(
                    w[1].min.y >= w[0].max.y,
                    "object {}: stacked boxes overlap",
                    o.id
                );
            }
            for b in &boxes {
                assert!(bounds.contains(b), "object {}: {b} outside {bounds}", o.id);
                // Every point of the box is enclosed, as seen along 26 directions with no
                // columns: a 5 × 5 × 5 grid over it, corners included.
                let triangles = triangles(&o.mesh);
                let tilt = Vec3::new(0.0031, 0.0017, 0.0027);
                let dirs: Vec<Vec3> = (0..27)
                    .filter(|&i| i != 13)
                    .map(|i| Vec3::new((i % 3) as f32, (i / 3 % 3) as f32, (i / 9) as f32) - 1.0)
                    .map(|d| d + tilt)
                    .collect();
                for i in 0..125 {
                    let f = Vec3::new((i % 5) as f32, (i / 5 % 5) as f32, (i / 25) as f32) / 4.0;
                    let p = b.min + f * b.extent();
                    for d in &dirs {
                        assert!(
                            triangles
                                .iter()
                                .any(|t| ray_triangle_distance(p, *d, t).is_some()),
                            "object {}: {p} of {b} sees out along {d}",
                            o.id
                        );
                    }
                }
            }
            // A worthwhile part of the building (a house under a tall roof keeps the
            // least, about a tenth of its bounds).
            let share = boxes.iter().map(Aabb::volume).sum::<f32>() / bounds.volume();
            assert!(
                share > 0.05,
                "object {}: {boxes:?} is {share} of {bounds}",
                o.id
            );
            total += share;
        }
        assert!(
            total / found as f32 > 0.3,
            "mean share {}",
            total / found as f32
        );
        assert_eq!(found, objects.len(), "every building has an occluder");
    }

    #[test]
    fn a_closed_block_is_filled_by_its_occluder() {
        // A closed 10 × 6 × 4 m block: its occluder fills it, less the safety margin.
        let mut mesh = Mesh::default();
        let p = |x: f32, y: f32, z: f32| [x, y, z];
        mesh.positions = vec![
            p(0., 0., 0.),
            p(10., 0., 0.),
            p(10., 0., 4.),
            p(0., 0., 4.),
            p(0., 6., 0.),
            p(10., 6., 0.),
            p(10., 6., 4.),
            p(0., 6., 4.),
        ];
        mesh.normals = vec![[0.0, 1.0, 0.0]; 8];
        mesh.indices = vec![
            0, 1, 2, 0, 2, 3, 4, 6, 5, 4, 7, 6, 0, 4, 5, 0, 5, 1, 1, 5, 6, 1, 6, 2, 2, 6, 7, 2, 7,
            3, 3, 7, 4, 3, 4, 0,
        ];
        let boxes = occluder_boxes(&mesh);
        assert_eq!(boxes.len(), 1);
        let b = boxes[0];
        assert!(b.extent().x > 9.9 && b.extent().y > 5.9 && b.extent().z > 3.9);
    }

    #[test]
    fn flat_open_and_broken_meshes_give_none() {
        let mut m = Mesh::default();
        assert!(occluder_boxes(&m).is_empty());
        m.positions = vec![[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 0.0, 10.0]];
        m.normals = vec![[0.0, 1.0, 0.0]; 3];
        m.indices = vec![0, 1, 2];
        assert!(occluder_boxes(&m).is_empty(), "flat");
        m.positions[2] = [0.0, 10.0, f32::NAN];
        assert!(occluder_boxes(&m).is_empty(), "NaN");
        // An open box (no top, no bottom) has no inside.
        let p = |x: f32, y: f32, z: f32| [x, y, z];
        m.positions = vec![
            p(0., 0., 0.),
            p(10., 0., 0.),
            p(10., 0., 4.),
            p(0., 0., 4.),
            p(0., 6., 0.),
            p(10., 6., 0.),
            p(10., 6., 4.),
            p(0., 6., 4.),
        ];
        m.normals = vec![[0.0, 1.0, 0.0]; 8];
        m.indices = vec![
            0, 4, 5, 0, 5, 1, 1, 5, 6, 1, 6, 2, 2, 6, 7, 2, 7, 3, 3, 7, 4, 3, 4, 0,
        ];
        assert!(occluder_boxes(&m).is_empty(), "open");
    }
}
