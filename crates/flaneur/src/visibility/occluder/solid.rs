//! Which points a building's faces enclose, and which of its faces are on the outside:
//! what the occluder search needs to know of a mesh that is not one oriented solid.

use glam::Vec3;

use crate::visibility::intersect::ray_triangle_distance;

/// How far outside a face its samples are taken, in metres.
const PROBE: f32 = 1e-3;
/// Columns of the grids that sort faces for the enclosure rays, per side.
const COLUMNS: usize = 16;

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
pub(super) struct Solid {
    pub(super) triangles: Vec<[Vec3; 3]>,
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
    /// The solid of `triangles`, all of them within `lo`..`hi`.
    pub(super) fn new(triangles: Vec<[Vec3; 3]>, lo: Vec3, hi: Vec3) -> Solid {
        let grids = [0, 1, 2].map(|axis| Columns::new(axis, &triangles, lo, hi));
        Solid { triangles, grids }
    }

    /// Whether every one of the six rays from `p` meets a face.
    pub(super) fn encloses(&self, p: Vec3) -> bool {
        DIRECTIONS.iter().enumerate().all(|(k, &dir)| {
            self.grids[k / 2]
                .column(p)
                .iter()
                .any(|&i| ray_triangle_distance(p, dir, &self.triangles[i as usize]).is_some())
        })
    }

    /// Whether the face `t` is on the outside somewhere: a point just off either side
    /// of it, at its centre or halfway from there to a corner, is not enclosed.
    pub(super) fn is_outside(&self, t: &[Vec3; 3]) -> bool {
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
