//! Which points a building's faces enclose, and which of its faces are on the outside:
//! what the occluder search needs to know of a mesh that is not one oriented solid.
//!
//! A point is enclosed when each of six rays from it (the axes, tilted a little)
//! meets a face. The faces a ray may meet are sorted into columns across its axis,
//! and within a column by how far along the ray's way they reach, so that a ray
//! tests only the faces in its column that reach past its origin; each face's part
//! of the ray–triangle test that does not depend on the ray's origin is computed
//! once per direction (what does not depend on the direction either, once per face;
//! the columns a face joins, once per axis). Both give the same answers as testing
//! every face of the column with [`ray_triangle_distance`]:
//! - A face the ray's test rejects whatever the origin (one the ray runs along, its
//!   determinant under the test's threshold) is left out.
//! - A face that ends behind the origin, along the ray's axis, by more than its
//!   margin is skipped: it cannot be crossed ahead. Only rounding could make the
//!   ray–triangle test see it crossed, and its error in where the ray meets the
//!   face's plane and where in the face that is stays under some c = 2·10⁻⁶ of the
//!   distance |s| from the origin to the face's first corner over the face's
//!   steepness k to the ray (its determinant over its two edges' lengths' product:
//!   the sine of the angle the ray meets its plane at, times that between the
//!   edges). The origin is in the face's column, so |s| ≤ δ + S, with δ how far
//!   behind the face ends and S the diagonals of the face's bounds and of a column
//!   and twice the column's drift. The margin, 1 cm + 10c·S / (k − 10c), makes δ
//!   above it exceed ten times the error, 10c·(δ + S) / k. A face the ray meets at a
//!   grazing angle thus keeps a wider margin, and one under 10c is never skipped.
//! - The six rays' answers are all needed, in any order, and the first open one
//!   ends the search: the direction that was open last time is tried first. Any
//!   face of a ray's column that it crosses will do: the one the direction's last
//!   ray crossed is tried first.
//!
//! [`ray_triangle_distance`]: crate::visibility::intersect::ray_triangle_distance

use std::cell::Cell;

use glam::Vec3;

/// How far outside a face its samples are taken, in metres.
const PROBE: f32 = 1e-3;
/// Columns of the grids that sort faces for the enclosure rays, per side.
const COLUMNS: usize = 16;

/// The six directions an enclosed point's rays take: the axes, tilted a little. Each
/// is a unit step along its own axis (`DIRECTIONS[k][k / 2]` is ±1).
const DIRECTIONS: [Vec3; 6] = [
    Vec3::new(1.0, 0.0021, 0.0013),
    Vec3::new(-1.0, -0.0017, 0.0023),
    Vec3::new(0.0013, 1.0, 0.0021),
    Vec3::new(-0.0023, -1.0, -0.0011),
    Vec3::new(0.0021, 0.0013, 1.0),
    Vec3::new(-0.0011, 0.0023, -1.0),
];

/// A face's margin behind an origin, in metres, before its share for rounding (see
/// the module's notes).
const BEHIND: f32 = 0.01;
/// The rounding error of the ray–triangle test, over the distance from the origin
/// to the face and the face's steepness, with a tenfold safety (10c in the module's
/// notes).
const ROUNDING: f32 = 2e-5;

/// An object's triangles, sorted into columns along each ray direction for the rays
/// that tell enclosed points from open ones.
pub(super) struct Solid {
    pub(super) triangles: Vec<[Vec3; 3]>,
    /// Per direction of [`DIRECTIONS`]: the faces its rays may meet.
    rays: [Rays; 6],
    /// The direction found open last: the first tried next.
    open: Cell<usize>,
}

/// A face as one direction's ray test needs it: what [`ray_triangle_distance`]
/// computes from the face and the direction alone, computed once.
///
/// [`ray_triangle_distance`]: crate::visibility::intersect::ray_triangle_distance
#[derive(Clone, Copy, Default)]
struct Prepared {
    t0: Vec3,
    e1: Vec3,
    e2: Vec3,
    p: Vec3,
    inv: f32,
}

impl Prepared {
    /// `t` prepared for rays along `dir`, with its steepness to them (`lengths` is
    /// its two edges' from `t[0]` lengths' product); `None` when no such ray crosses
    /// it (Möller–Trumbore's determinant is under its threshold).
    fn new(dir: Vec3, t: &[Vec3; 3], lengths: f32) -> Option<(Prepared, f32)> {
        let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
        let p = dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-12 {
            return None;
        }
        let steepness = det.abs() / lengths;
        let inv = 1.0 / det;
        Some((
            Prepared {
                t0: t[0],
                e1,
                e2,
                p,
                inv,
            },
            steepness,
        ))
    }

    /// Whether the ray from `origin` along `dir` (the direction it was prepared for)
    /// crosses the face ahead: `ray_triangle_distance(origin, dir, t).is_some()`,
    /// the same operations in the same order.
    #[inline]
    fn crossed(&self, origin: Vec3, dir: Vec3) -> bool {
        let s = origin - self.t0;
        let u = s.dot(self.p) * self.inv;
        if !(0.0..=1.0).contains(&u) {
            return false;
        }
        let q = s.cross(self.e1);
        let v = dir.dot(q) * self.inv;
        if v < 0.0 || u + v > 1.0 {
            return false;
        }
        let d = self.e2.dot(q) * self.inv;
        d > 0.0
    }
}

/// The grid of columns across one axis.
#[derive(Clone, Copy)]
struct Grid {
    /// The two axes across the columns.
    across: [usize; 2],
    lo: [f32; 2],
    cell: [f32; 2],
}

impl Grid {
    fn new(axis: usize, lo: Vec3, hi: Vec3) -> Grid {
        let across = [(axis + 1) % 3, (axis + 2) % 3];
        Grid {
            across,
            lo: across.map(|a| lo[a]),
            cell: across.map(|a| ((hi[a] - lo[a]) / COLUMNS as f32).max(1e-3)),
        }
    }

    /// The column of `p`; `None` when `p` is beside the bounds, where a ray along the
    /// axis meets nothing.
    #[inline]
    fn column(&self, p: Vec3) -> Option<usize> {
        // Truncation is the floor here: negative steps are refused first (a NaN goes
        // to column 0, as its floor would).
        let k = |i: usize| (p[self.across[i]] - self.lo[i]) / self.cell[i];
        let (c, r) = (k(0), k(1));
        if c < 0.0 || r < 0.0 || c >= COLUMNS as f32 || r >= COLUMNS as f32 {
            return None;
        }
        Some(r as usize * COLUMNS + c as usize)
    }

    /// The rows and columns (first and last of each) that the face `t` joins: every
    /// one that a tilted ray drifting sideways by up to `drift` on its way can bring
    /// into it.
    fn columns_of(&self, t: &[Vec3; 3], drift: f32) -> Span {
        let tlo = t[0].min(t[1]).min(t[2]) - Vec3::splat(drift);
        let thi = t[0].max(t[1]).max(t[2]) + Vec3::splat(drift);
        // Truncation saturates a negative step to 0, as floor then max(0) did;
        // COLUMNS is under 256.
        let f =
            |v: f32, k: usize| (((v - self.lo[k]) / self.cell[k]) as usize).min(COLUMNS - 1) as u8;
        let (a, b) = (self.across[0], self.across[1]);
        [f(tlo[b], 1), f(thi[b], 1), f(tlo[a], 0), f(thi[a], 0)]
    }
}

/// The faces rays along one direction may meet, column by column, each column's
/// sorted by how far along the direction they reach.
struct Rays {
    dir: Vec3,
    axis: usize,
    forward: bool,
    grid: Grid,
    /// Per triangle (by its index): prepared for this direction.
    prepared: Vec<Prepared>,
    /// Column `c`'s faces are `faces[starts[c]..starts[c + 1]]`, with `reach` the
    /// same range: how far along the direction each reaches with its margin (its
    /// furthest corner's coordinate, negated for a backward ray, plus the margin),
    /// ascending.
    starts: Vec<u32>,
    reach: Vec<f32>,
    faces: Vec<u32>,
    /// Per triangle: the rows and columns it joins (first and last of each).
    spans: Vec<[u8; 4]>,
    /// The face the last ray that met one met: the next ray, from a point near the
    /// last, likely meets it too, so it is tried first when it is in the ray's
    /// column (whether any face of the column is met does not depend on the order).
    last: Cell<usize>,
}

impl Rays {
    /// The faces that rays along direction `k` may cross, each in the columns of its
    /// axis's `columns` that it joins, which a ray drifting sideways by up to `drift`
    /// may meet it in; `shapes` is what each triangle's preparing needs of it alone.
    fn new(
        k: usize,
        columns: &Columns,
        triangles: &[[Vec3; 3]],
        shapes: &[Shape],
        drift: f32,
    ) -> Rays {
        let dir = DIRECTIONS[k];
        let (axis, forward) = (k / 2, k.is_multiple_of(2));
        let grid = columns.grid;
        let column = grid.cell[0].hypot(grid.cell[1]);
        // Per face rays cross: its reach's bits in the total order's, then its index.
        let mut keyed: Vec<(u32, u32)> = Vec::with_capacity(triangles.len());
        let mut reach_of = vec![0.0f32; triangles.len()];
        let mut skipped = false;
        let prepared = triangles
            .iter()
            .zip(shapes)
            .enumerate()
            .map(|(i, (t, shape))| {
                let Some((f, steepness)) = Prepared::new(dir, t, shape.lengths) else {
                    skipped = true;
                    return Prepared::default();
                };
                let end = if forward {
                    t[0][axis].max(t[1][axis]).max(t[2][axis])
                } else {
                    -t[0][axis].min(t[1][axis]).min(t[2][axis])
                };
                // The margin (see the module's notes); a face too grazing for one is
                // never skipped.
                let size = shape.diagonal + column + 2.0 * drift;
                let margin = if steepness > ROUNDING {
                    BEHIND + ROUNDING * size / (steepness - ROUNDING)
                } else {
                    f32::INFINITY
                };
                let key = end + margin;
                reach_of[i] = key;
                let bits = key.to_bits() as i32;
                let ordered = (bits ^ (((bits >> 31) as u32) >> 1) as i32) as u32 ^ (1 << 31);
                keyed.push((ordered, i as u32));
                f
            })
            .collect();
        // Sorted once, by reach then index, then dealt out to the columns in that
        // order: each column's faces come sorted.
        sort_by_reach(&mut keyed);
        // The axis's counts hold every face; one this direction's rays never cross
        // (rare: a face along the ray, or a sliver) is taken out of them.
        let mut starts = columns.counts.clone();
        if skipped {
            let mut crossed = vec![false; triangles.len()];
            for &(_, i) in &keyed {
                crossed[i as usize] = true;
            }
            for (span, _) in columns.spans.iter().zip(&crossed).filter(|(_, &c)| !c) {
                for c in span_columns(span) {
                    starts[c + 1] -= 1;
                }
            }
        }
        for c in 0..COLUMNS * COLUMNS {
            starts[c + 1] += starts[c];
        }
        let mut next = starts.clone();
        let total = starts[COLUMNS * COLUMNS] as usize;
        let (mut reach, mut faces) = (vec![0.0f32; total], vec![0u32; total]);
        for &(_, i) in &keyed {
            let key = reach_of[i as usize];
            for c in span_columns(&columns.spans[i as usize]) {
                let at = &mut next[c];
                (reach[*at as usize], faces[*at as usize]) = (key, i);
                *at += 1;
            }
        }
        Rays {
            dir,
            axis,
            forward,
            grid,
            prepared,
            starts,
            reach,
            faces,
            spans: columns.spans.clone(),
            last: Cell::new(usize::MAX),
        }
    }

    /// Whether the ray from `p` meets a face.
    #[inline]
    fn meets(&self, p: Vec3) -> bool {
        let Some(c) = self.grid.column(p) else {
            return false;
        };
        let (row, col) = ((c / COLUMNS) as u8, (c % COLUMNS) as u8);
        let last = self.last.get();
        if let Some(&[r0, r1, c0, c1]) = self.spans.get(last) {
            let joins = (r0..=r1).contains(&row) && (c0..=c1).contains(&col);
            if joins && self.prepared[last].crossed(p, self.dir) {
                return true;
            }
        }
        let (from, to) = (self.starts[c] as usize, self.starts[c + 1] as usize);
        let at = if self.forward {
            p[self.axis]
        } else {
            -p[self.axis]
        };
        let from = from + self.reach[from..to].partition_point(|&r| r < at);
        match self.faces[from..to]
            .iter()
            .find(|&&i| self.prepared[i as usize].crossed(p, self.dir))
        {
            Some(&i) => {
                self.last.set(i as usize);
                true
            }
            None => false,
        }
    }
}

/// The rows and columns of a grid that a face joins, first and last of each.
type Span = [u8; 4];

/// The columns, by their index, of `span`.
#[inline]
fn span_columns(&[r0, r1, c0, c1]: &Span) -> impl Iterator<Item = usize> {
    (usize::from(r0)..usize::from(r1) + 1)
        .flat_map(move |r| (usize::from(c0)..usize::from(c1) + 1).map(move |c| r * COLUMNS + c))
}

/// What preparing a face needs of it alone, whichever the direction: its two edges'
/// lengths' product and its bounds' diagonal.
struct Shape {
    lengths: f32,
    diagonal: f32,
}

/// One axis's grid, the columns each face joins in it, and how many faces join each
/// column: the same for the rays both ways along the axis.
struct Columns {
    grid: Grid,
    spans: Vec<Span>,
    /// Column `c`'s count is `counts[c + 1]` (`counts[0]` is 0), ready to be summed
    /// into where each column starts.
    counts: Vec<u32>,
}

impl Columns {
    fn new(grid: Grid, triangles: &[[Vec3; 3]], drift: f32) -> Columns {
        let spans: Vec<Span> = triangles
            .iter()
            .map(|t| grid.columns_of(t, drift))
            .collect();
        let mut counts = vec![0u32; COLUMNS * COLUMNS + 1];
        for span in &spans {
            for c in span_columns(span) {
                counts[c + 1] += 1;
            }
        }
        Columns {
            grid,
            spans,
            counts,
        }
    }
}

/// `keyed` (reach bits in the total order's, face index), in ascending index order,
/// sorted by reach and then index: a stable sort on the reach alone, by its bytes
/// from the lowest (a radix sort; a byte all the keys share is passed over).
fn sort_by_reach(keyed: &mut Vec<(u32, u32)>) {
    let mut counts = [[0u32; 256]; 4];
    for &(key, _) in keyed.iter() {
        for (byte, count) in counts.iter_mut().enumerate() {
            count[(key >> (8 * byte)) as usize & 255] += 1;
        }
    }
    let mut out = vec![(0u32, 0u32); keyed.len()];
    for (byte, count) in counts.iter().enumerate() {
        if count.iter().any(|&n| n as usize == keyed.len()) {
            continue;
        }
        let mut next = [0u32; 256];
        let mut sum = 0;
        for (n, c) in next.iter_mut().zip(count) {
            *n = sum;
            sum += c;
        }
        for &item in keyed.iter() {
            let at = &mut next[(item.0 >> (8 * byte)) as usize & 255];
            out[*at as usize] = item;
            *at += 1;
        }
        std::mem::swap(keyed, &mut out);
    }
}

impl Solid {
    /// The solid of `triangles`, all of them within `lo`..`hi`.
    pub(super) fn new(triangles: Vec<[Vec3; 3]>, lo: Vec3, hi: Vec3) -> Solid {
        // A tilted ray drifts sideways as it goes: a face joins every column the drift
        // can bring a ray into.
        let drift = (hi - lo).max_element() * 0.0025 + PROBE;
        let shapes: Vec<Shape> = triangles
            .iter()
            .map(|t| Shape {
                lengths: (t[1] - t[0]).length() * (t[2] - t[0]).length(),
                diagonal: (t[0].max(t[1]).max(t[2]) - t[0].min(t[1]).min(t[2])).length(),
            })
            .collect();
        let columns =
            [0, 1, 2].map(|axis| Columns::new(Grid::new(axis, lo, hi), &triangles, drift));
        let rays =
            std::array::from_fn(|k| Rays::new(k, &columns[k / 2], &triangles, &shapes, drift));
        Solid {
            triangles,
            rays,
            open: Cell::new(0),
        }
    }

    /// Whether every one of the six rays from `p` meets a face.
    pub(super) fn encloses(&self, p: Vec3) -> bool {
        self.encloses_first(p, self.open.get())
    }

    /// [`Solid::encloses`], trying direction `first` first: the answer is the same
    /// whatever the order, but the first open direction ends the search.
    fn encloses_first(&self, p: Vec3, first: usize) -> bool {
        for k in (first..6).chain(0..first) {
            if !self.rays[k].meets(p) {
                self.open.set(k);
                return false;
            }
        }
        true
    }

    /// Whether the face `t` is on the outside somewhere: a point just off either side
    /// of it, at its centre or halfway from there to a corner, is not enclosed.
    pub(super) fn is_outside(&self, t: &[Vec3; 3]) -> bool {
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        if n.length_squared() == 0.0 {
            return false;
        }
        let off = n.normalize() * PROBE;
        // The direction most along the normal: the likeliest to be open from the
        // point off the face on its side (its opposite, `out ^ 1`, from the other).
        let (axis, _) =
            off.abs()
                .to_array()
                .into_iter()
                .enumerate()
                .fold(
                    (0, -1.0),
                    |best, (a, v)| if v > best.1 { (a, v) } else { best },
                );
        let out = 2 * axis + usize::from(off[axis] < 0.0);
        let centre = (t[0] + t[1] + t[2]) / 3.0;
        [
            centre,
            0.5 * (centre + t[0]),
            0.5 * (centre + t[1]),
            0.5 * (centre + t[2]),
        ]
        .into_iter()
        .any(|p| !self.encloses_first(p + off, out) || !self.encloses_first(p - off, out ^ 1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Mesh;
    use crate::visibility::intersect::{ray_triangle_distance, triangles};

    /// Per direction, whether a ray from `p` meets a face, by testing every face of
    /// its column as the search did before faces were prepared and sorted: the
    /// answers the solid must keep.
    fn every_face_of_the_column(triangles: &[[Vec3; 3]], lo: Vec3, hi: Vec3, p: Vec3) -> [bool; 6] {
        let drift = (hi - lo).max_element() * 0.0025 + PROBE;
        std::array::from_fn(|k| {
            let (axis, dir) = (k / 2, DIRECTIONS[k]);
            let across = [(axis + 1) % 3, (axis + 2) % 3];
            let cell = across.map(|a| ((hi[a] - lo[a]) / COLUMNS as f32).max(1e-3));
            let step = |v: f32, a: usize| ((v - lo[across[a]]) / cell[a]).floor();
            let (c, r) = (step(p[across[0]], 0), step(p[across[1]], 1));
            if c < 0.0 || r < 0.0 || c >= COLUMNS as f32 || r >= COLUMNS as f32 {
                return false;
            }
            let joins = |t: &[Vec3; 3]| {
                let tlo = t[0].min(t[1]).min(t[2]) - Vec3::splat(drift);
                let thi = t[0].max(t[1]).max(t[2]) + Vec3::splat(drift);
                let f = |v: f32, a: usize| step(v, a).max(0.0).min((COLUMNS - 1) as f32);
                (f(tlo[across[0]], 0)..=f(thi[across[0]], 0)).contains(&c)
                    && (f(tlo[across[1]], 1)..=f(thi[across[1]], 1)).contains(&r)
            };
            triangles
                .iter()
                .any(|t| joins(t) && ray_triangle_distance(p, dir, t).is_some())
        })
    }

    /// Points to ask about: just off each face (as `is_outside` asks), and a grid
    /// over the bounds and a little beyond.
    fn probes(triangles: &[[Vec3; 3]], lo: Vec3, hi: Vec3) -> Vec<Vec3> {
        let mut points = Vec::new();
        for t in triangles {
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            if n.length_squared() == 0.0 {
                continue;
            }
            let off = n.normalize() * PROBE;
            let centre = (t[0] + t[1] + t[2]) / 3.0;
            for p in [centre, 0.5 * (centre + t[0]), 0.5 * (centre + t[2])] {
                points.extend([p + off, p - off]);
            }
        }
        for i in 0..9 * 9 * 9 {
            let f = Vec3::new((i % 9) as f32, (i / 9 % 9) as f32, (i / 81) as f32) / 8.0;
            points.push(lo - 0.05 * (hi - lo) + 1.1 * f * (hi - lo));
        }
        points
    }

    fn assert_same_answers(mesh: &Mesh, name: &str) {
        let triangles = triangles(mesh);
        let (lo, hi) = mesh.bounds();
        let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
        let solid = Solid::new(triangles.clone(), lo, hi);
        for p in probes(&triangles, lo, hi) {
            let got: [bool; 6] = std::array::from_fn(|k| solid.rays[k].meets(p));
            let want = every_face_of_the_column(&triangles, lo, hi, p);
            assert_eq!(got, want, "{name}: the rays from {p}");
            assert_eq!(solid.encloses(p), want.iter().all(|&m| m), "{name}: {p}");
        }
    }

    #[test]
    fn sorted_columns_answer_as_every_face_of_the_column_does() {
        for o in crate::visibility::tests::city(24) {
            assert_same_answers(&o.mesh, &format!("object {}", o.id));
        }
        // A footprint at an angle, far from the origin: the faces along no axis.
        let ring: Vec<[f64; 2]> = [[0.0, 0.0], [30.0, 4.0], [26.0, 20.0], [8.0, 26.0]]
            .iter()
            .map(|p| [p[0] + 2400.0, p[1] - 1800.0])
            .collect();
        let mesh = crate::scene::extruded(ring, vec![], 21.0);
        assert_same_answers(&mesh, "turned footprint");
    }

    #[test]
    fn a_prepared_face_is_crossed_as_the_ray_test_says() {
        // Rays along each direction from a lattice of origins, against faces of every
        // slant (and some the rays run along).
        let faces = [
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec3::ZERO, Vec3::Z, Vec3::X],
            [
                Vec3::new(0.3, 0.0, 0.0),
                Vec3::new(0.9, 1.0, 0.2),
                Vec3::new(0.1, 0.4, 1.0),
            ],
            [
                Vec3::new(1.0, 1.0, 1.0),
                Vec3::new(-0.5, 0.2, 0.7),
                Vec3::new(0.6, -0.3, 0.1),
            ],
            [Vec3::ZERO, Vec3::X, 2.0 * Vec3::X],
        ];
        for (k, &dir) in DIRECTIONS.iter().enumerate() {
            for t in &faces {
                let lengths = (t[1] - t[0]).length() * (t[2] - t[0]).length();
                let prepared = Prepared::new(dir, t, lengths);
                for i in 0..11 * 11 * 11 {
                    let o = Vec3::new((i % 11) as f32, (i / 11 % 11) as f32, (i / 121) as f32)
                        / 5.0
                        - 1.0;
                    let want = ray_triangle_distance(o, dir, t).is_some();
                    let got = prepared.is_some_and(|(f, _)| f.crossed(o, dir));
                    assert_eq!(got, want, "direction {k}, face {t:?}, origin {o}");
                }
            }
        }
    }
}
