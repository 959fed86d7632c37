//! Normals from faces: a flat-shaded mesh stores its positions once and no normals.
//!
//! A building's faces are flat: every corner of a triangle carries the triangle's own
//! normal, so each position is stored once per face that meets there (1.6 vertices a
//! triangle on citygen's buildings, against 0.58 positions). In this layout the vertex
//! stream holds each quantised position once, the index buffer names positions, and a
//! reader computes each triangle's normal from its dequantised corners: glTF's rule for a
//! mesh without normals, which a viewer draws flat. Corners whose stored normal is not
//! their face's (the simplifier's coarse levels keep a vertex's normal where its faces
//! turned; a smooth mesh has them everywhere) are *exceptions*: one bit a corner says
//! which, and their normals follow in corner order. The reader then joins corners that
//! share a position and a normal into one vertex, so it builds the same mesh as the
//! vertex layout would, vertex for vertex (in another order).
//!
//! Both sides compute a face's normal from the same dequantised positions in the same turn
//! (the one stored), the writer with [`face_normal`] and the reader eight triangles at a time with the same operations in
//! the same order (`face_lanes`), so the bits agree wherever the file does.

use super::quantize::{
    dequantize_repeating, normal_word, quantize_normal, snorm8_lanes, Grid, QNormal, QPosition,
};
use rustc_hash::{FxHashMap, FxHashSet};

/// The normal a reader gives a triangle's corners unless told otherwise: the quantised
/// unit normal of its dequantised corners (zero for a triangle without area).
#[inline]
pub(crate) fn face_normal(corners: [[f32; 3]; 3]) -> QNormal {
    let [a, b, c] = corners.map(glam::Vec3::from);
    quantize_normal((b - a).cross(c - a).normalize_or_zero().to_array())
}

/// Whether the layout pays for these corners: at most one in two an exception. Past
/// that a smooth mesh's shared vertices cost less than a normal a corner.
pub(crate) fn suits(exceptions: usize, corners: usize) -> bool {
    2 * exceptions <= corners
}

/// A level's corners laid out by positions: what the encoder writes.
pub(crate) struct FaceLevel {
    /// Positions no earlier level used, in first-use order.
    pub added: Vec<QPosition>,
    /// Three a triangle, naming positions of every level so far.
    pub indices: Vec<u32>,
    /// Each corner's normal.
    normals: Vec<QNormal>,
    /// Each triangle's dequantised corners, from which its face normal is worked out in
    /// whichever turn the index codec gives it back (a cross product's bits depend on
    /// the corner it starts from).
    at: Vec<[[f32; 3]; 3]>,
    /// The vertices a reader builds: distinct (position, normal) pairs.
    pub vertices: usize,
}

/// Which corners are exceptions, and their normals, in the order a reader meets them.
pub(crate) struct Exceptions {
    /// One bit a corner, least significant first.
    pub bits: Vec<u8>,
    /// The exceptions' normals, in corner order.
    pub normals: Vec<QNormal>,
}

impl FaceLevel {
    /// The exceptions as a reader meets them in `stored`, the index buffer as the index
    /// codec gives it back: the codec may turn a triangle (its winding kept), and a
    /// corner's bit goes with the corner, and the face normal is the reader's: worked out
    /// from the corners in their stored turn. A triangle whose three corners are one
    /// position has no turn to find; its corners' normals stay in their slots, which
    /// draws the same nothing and makes the same vertices.
    pub(crate) fn exceptions(&self, stored: &[u32]) -> Result<Exceptions, String> {
        if stored.len() != self.indices.len() {
            return Err(format!(
                "the index codec gave back {} indices of {}",
                stored.len(),
                self.indices.len()
            ));
        }
        let mut out = Exceptions {
            bits: vec![0; bits_len(stored.len())],
            normals: Vec::new(),
        };
        for (t, (was, now)) in self
            .indices
            .chunks_exact(3)
            .zip(stored.chunks_exact(3))
            .enumerate()
        {
            let turn = (0..3)
                .find(|&r| (0..3).all(|k| was[(k + r) % 3] == now[k]))
                .ok_or_else(|| {
                    format!("the index codec gave back triangle {t} as {now:?}, not {was:?}")
                })?;
            let face = face_normal([0, 1, 2].map(|k| self.at[t][(k + turn) % 3]));
            for k in 0..3 {
                let n = self.normals[3 * t + (k + turn) % 3];
                if n != face {
                    let c = 3 * t + k;
                    out.bits[c / 8] |= 1 << (c % 8);
                    out.normals.push(n);
                }
            }
        }
        Ok(out)
    }
}

/// Positions shared by an object's levels as the encoder adds them.
#[derive(Default)]
pub(crate) struct SharedPositions {
    ids: FxHashMap<QPosition, u32>,
    all: Vec<QPosition>,
}

impl SharedPositions {
    pub(crate) fn len(&self) -> usize {
        self.all.len()
    }

    /// Lays out `corners` (three a triangle, in the order to store them) over the
    /// positions so far, adding the new ones.
    pub(crate) fn lay_out(&mut self, grid: &Grid, corners: &[(QPosition, QNormal)]) -> FaceLevel {
        let first_new = self.all.len();
        let mut level = FaceLevel {
            added: Vec::new(),
            indices: Vec::with_capacity(corners.len()),
            normals: corners.iter().map(|(_, n)| *n).collect(),
            at: Vec::with_capacity(corners.len() / 3),
            vertices: 0,
        };
        let mut vertices: FxHashSet<(u32, QNormal)> = FxHashSet::default();
        for (t, tri) in corners.chunks_exact(3).enumerate() {
            let mut at = [[0f32; 3]; 3];
            for (k, (q, _)) in tri.iter().enumerate() {
                let id = *self.ids.entry(*q).or_insert_with(|| {
                    self.all.push(*q);
                    (self.all.len() - 1) as u32
                });
                level.indices.push(id);
                at[k] = grid.dequantize(*q);
            }
            level.at.push(at);
            for (k, (_, n)) in tri.iter().enumerate() {
                vertices.insert((level.indices[3 * t + k], *n));
            }
        }
        level.added = self.all[first_new..].to_vec();
        level.vertices = vertices.len();
        level
    }
}

/// How many of `corners` (three a triangle) a reader would not give their face's normal.
pub(crate) fn count_exceptions(grid: &Grid, corners: &[(QPosition, QNormal)]) -> usize {
    corners
        .chunks_exact(3)
        .map(|tri| {
            let face = face_normal([0, 1, 2].map(|k| grid.dequantize(tri[k].0)));
            tri.iter().filter(|(_, n)| *n != face).count()
        })
        .sum()
}

/// `corners` with their triangles in meshoptimizer's vertex-cache order over positions
/// rather than vertices; as they are where the optimiser's output cannot be matched to
/// them.
pub(crate) fn position_cache_order(corners: &[(QPosition, QNormal)]) -> Vec<(QPosition, QNormal)> {
    let mut ids: FxHashMap<QPosition, u32> = FxHashMap::default();
    let local: Vec<u32> = corners
        .iter()
        .map(|(q, _)| {
            let next = ids.len() as u32;
            *ids.entry(*q).or_insert(next)
        })
        .collect();
    // The optimiser moves whole triangles without turning them: each comes back as
    // the same three ids, so a triangle is found again by them.
    let mut triangles: FxHashMap<[u32; 3], Vec<usize>> = FxHashMap::default();
    for (t, tri) in local.chunks_exact(3).enumerate().rev() {
        triangles
            .entry([tri[0], tri[1], tri[2]])
            .or_default()
            .push(t);
    }
    let order = meshopt::optimize_vertex_cache(&local, ids.len());
    let mut out = Vec::with_capacity(corners.len());
    for tri in order.chunks_exact(3) {
        let Some(t) = triangles
            .get_mut(&[tri[0], tri[1], tri[2]])
            .and_then(Vec::pop)
        else {
            return corners.to_vec();
        };
        out.extend_from_slice(&corners[3 * t..3 * t + 3]);
    }
    out
}

/// Bytes of the bit set of `corners` corners.
pub(crate) fn bits_len(corners: usize) -> usize {
    corners.div_ceil(8)
}

/// How many corners `bits` mark as exceptions.
pub(crate) fn exception_count(bits: &[u8]) -> usize {
    bits.iter().map(|b| b.count_ones() as usize).sum()
}

/// The mesh a level's positions, indices, bits and exceptions describe: corners that
/// share a position and a normal become one vertex, numbered in the order their first
/// corner comes. The caller has checked every index against `positions` and the
/// exceptions' count against the bits. `indices` become the mesh's own.
pub(crate) fn assemble(
    positions: &[[f32; 3]],
    mut indices: Vec<u32>,
    bits: &[u8],
    exceptions: &[QNormal],
) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u32>) {
    let faces = face_words(positions, &indices);
    let mut join = Join::new(positions.len(), indices.len());
    if exceptions.is_empty() {
        // Every corner its face's normal: the bits are all clear.
        for (tri, &face) in indices.chunks_exact_mut(3).zip(&faces) {
            for c in tri {
                *c = join.vertex(*c, face);
            }
        }
    } else {
        // Every corner its face's normal, then the exceptions over theirs: two plain
        // passes rather than a bit test in the join.
        let mut normals: Vec<u32> = Vec::with_capacity(indices.len());
        for &face in &faces {
            normals.extend_from_slice(&[face; 3]);
        }
        let mut exceptions = exceptions.iter();
        for (at, &byte) in bits.iter().enumerate() {
            let mut b = byte;
            while b != 0 {
                let c = 8 * at + b.trailing_zeros() as usize;
                b &= b - 1;
                if let (Some(slot), Some(&n)) = (normals.get_mut(c), exceptions.next()) {
                    *slot = normal_word(n);
                }
            }
        }
        for (c, &n) in indices.iter_mut().zip(&normals) {
            *c = join.vertex(*c, n);
        }
    }
    let (at, words) = join.vertices();
    let out_p = at.iter().map(|&p| positions[p as usize]).collect();
    (out_p, dequantize_repeating(words), indices)
}

/// Normals a position keeps beside it; a position meets few (three at a box's corner,
/// four at a hipped roof's ridge), and the rest go to a map.
const SLOTS: usize = 4;

/// Corners joined into vertices as they come. Each position holds its first vertices'
/// normals side by side, so that finding a corner's vertex reads one place and compares
/// four words at once.
struct Join {
    /// Per position: how many of its slots hold a vertex.
    filled: Vec<u8>,
    /// Per position: its first vertices' normals (as words), then those vertices.
    slots: Vec<[u32; 2 * SLOTS]>,
    /// Vertices beyond a position's slots, by (position, normal word).
    more: FxHashMap<(u32, u32), u32>,
    /// Each vertex's position and normal word, in the order they were made.
    at: Vec<u32>,
    words: Vec<u32>,
}

impl Join {
    /// A join over `positions` positions of at most `corners` vertices.
    fn new(positions: usize, corners: usize) -> Join {
        Join {
            filled: vec![0; positions],
            slots: vec![[0; 2 * SLOTS]; positions],
            more: FxHashMap::default(),
            at: Vec::with_capacity(corners),
            words: Vec::with_capacity(corners),
        }
    }

    /// The vertex of position `p` with normal `n`, made if it is the first.
    #[inline(always)]
    fn vertex(&mut self, p: u32, n: u32) -> u32 {
        let pi = p as usize;
        let filled = usize::from(self.filled[pi]);
        let s = &mut self.slots[pi];
        let mut hits = 0u32;
        for (k, &w) in s[..SLOTS].iter().enumerate() {
            hits |= u32::from(w == n) << k;
        }
        hits &= (1 << filled) - 1;
        if hits != 0 {
            return s[SLOTS + hits.trailing_zeros() as usize];
        }
        if filled == SLOTS {
            return self.beyond(p, n);
        }
        let v = self.at.len() as u32;
        s[filled] = n;
        s[SLOTS + filled] = v;
        self.filled[pi] += 1;
        self.at.push(p);
        self.words.push(n);
        v
    }

    /// The vertex of a position whose slots are full.
    #[cold]
    fn beyond(&mut self, p: u32, n: u32) -> u32 {
        let made = self.at.len() as u32;
        let v = *self.more.entry((p, n)).or_insert(made);
        if v == made {
            self.at.push(p);
            self.words.push(n);
        }
        v
    }

    /// Each vertex's position and normal word, in the order they were made.
    fn vertices(&self) -> (&[u32], &[u32]) {
        (&self.at, &self.words)
    }
}

/// Triangles whose face normals are worked out side by side.
const LANES: usize = 8;

/// Each triangle's [`face_normal`], as a word: eight triangles at a time, their corners
/// gathered axis by axis so that the arithmetic runs on vectors (the square root and
/// division of a face normal were the largest part of a reader's time, one triangle
/// after another).
fn face_words(positions: &[[f32; 3]], indices: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(indices.len() / 3);
    let mut batches = indices.chunks_exact(3 * LANES);
    for batch in &mut batches {
        out.extend_from_slice(&face_lanes(&gather(positions, batch)));
    }
    let rest = batches.remainder();
    if !rest.is_empty() {
        // The missing lanes hold triangles at the origin, whose normals go unused.
        out.extend_from_slice(&face_lanes(&gather(positions, rest))[..rest.len() / 3]);
    }
    out
}

/// Corners of up to [`LANES`] triangles: `g[3 * corner + axis][lane]`.
#[inline(always)]
fn gather(positions: &[[f32; 3]], indices: &[u32]) -> [[f32; LANES]; 9] {
    let mut g = [[0f32; LANES]; 9];
    for (lane, tri) in indices.chunks_exact(3).take(LANES).enumerate() {
        for (k, &i) in tri.iter().enumerate() {
            let p = positions[i as usize];
            g[3 * k][lane] = p[0];
            g[3 * k + 1][lane] = p[1];
            g[3 * k + 2][lane] = p[2];
        }
    }
    g
}

/// [`face_normal`] of each lane's triangle, bit for bit: glam's cross product, length and
/// `normalize_or_zero`, then [`quantize_normal`]'s rounding, operation for operation in
/// the same order (IEEE's square root and division round the same in a vector lane).
#[inline(always)]
fn face_lanes(g: &[[f32; LANES]; 9]) -> [u32; LANES] {
    let mut n = [[0f32; LANES]; 3];
    for l in 0..LANES {
        let (ax, ay, az) = (g[0][l], g[1][l], g[2][l]);
        let (ex, ey, ez) = (g[3][l] - ax, g[4][l] - ay, g[5][l] - az);
        let (fx, fy, fz) = (g[6][l] - ax, g[7][l] - ay, g[8][l] - az);
        let x = ey * fz - fy * ez;
        let y = ez * fx - fz * ex;
        let z = ex * fy - fx * ey;
        let rcp = 1.0 / (x * x + y * y + z * z).sqrt();
        // `rcp.is_finite() && rcp > 0.0`, glam's test.
        let unit = rcp > 0.0 && rcp < f32::INFINITY;
        n[0][l] = if unit { x * rcp } else { 0.0 };
        n[1][l] = if unit { y * rcp } else { 0.0 };
        n[2][l] = if unit { z * rcp } else { 0.0 };
    }
    let q = [snorm8_lanes(n[0]), snorm8_lanes(n[1]), snorm8_lanes(n[2])];
    let mut out = [0u32; LANES];
    for l in 0..LANES {
        out[l] = (q[0][l] & 0xff) | (q[1][l] & 0xff) << 8 | (q[2][l] & 0xff) << 16;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::mesh_codec::quantize::dequantize_normal;

    #[test]
    fn a_flat_box_needs_no_exception_and_comes_back_vertex_for_vertex() {
        let mesh = crate::lod::fixtures::building();
        let grid = Grid::around([&mesh]);
        let corners: Vec<_> = mesh
            .indices
            .iter()
            .map(|&i| {
                let i = i as usize;
                (
                    grid.quantize(mesh.positions[i]),
                    quantize_normal(mesh.normals[i]),
                )
            })
            .collect();
        let mut shared = SharedPositions::default();
        let level = shared.lay_out(&grid, &corners);
        let e = level.exceptions(&level.indices).unwrap();
        assert!(e.normals.is_empty());
        assert_eq!(count_exceptions(&grid, &corners), 0);
        assert!(
            level.added.len() < mesh.positions.len(),
            "positions are welded"
        );
        let positions: Vec<_> = level.added.iter().map(|&q| grid.dequantize(q)).collect();
        let (p, n, i) = assemble(&positions, level.indices.clone(), &e.bits, &e.normals);
        assert_eq!(p.len(), level.vertices);
        // Every corner reads back its own position and normal.
        for (c, &v) in i.iter().enumerate() {
            assert_eq!(grid.quantize(p[v as usize]), corners[c].0);
            assert_eq!(n[v as usize], dequantize_normal(corners[c].1));
        }
    }

    #[test]
    fn a_triangle_the_index_codec_turns_keeps_its_corners_normals() {
        // A cross product's bits depend on the corner it starts from: find triangles whose
        // face normal changes when turned, give each corner its face normal in the
        // writer's turn, and let the codec hand every one back turned. The reader, which
        // works the normal out in the stored turn, must still read each corner's own
        // normal and make the vertices the writer counted.
        let grid = Grid::around_points([[0.0; 3], [50.0, 50.0, 50.0]]);
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % 50_000) as f32 / 1000.0
        };
        let mut corners = Vec::new();
        while corners.len() < 3 * 20 {
            let q = [0, 1, 2].map(|_| grid.quantize([next(), next(), next()]));
            let at = q.map(|q| grid.dequantize(q));
            let face = face_normal(at);
            if face_normal([at[1], at[2], at[0]]) != face {
                corners.extend(q.map(|q| (q, face)));
            }
        }
        let level = SharedPositions::default().lay_out(&grid, &corners);
        let turned: Vec<u32> = level
            .indices
            .chunks_exact(3)
            .flat_map(|t| [t[1], t[2], t[0]])
            .collect();
        let e = level.exceptions(&turned).unwrap();
        let positions: Vec<_> = level.added.iter().map(|&q| grid.dequantize(q)).collect();
        let (p, n, i) = assemble(&positions, turned, &e.bits, &e.normals);
        assert_eq!(p.len(), level.vertices);
        for (c, &v) in i.iter().enumerate() {
            let written = corners[c - c % 3 + (c + 1) % 3];
            assert_eq!(grid.quantize(p[v as usize]), written.0);
            assert_eq!(n[v as usize], dequantize_normal(written.1), "corner {c}");
        }
    }

    #[test]
    fn face_normals_side_by_side_are_face_normals_one_at_a_time() {
        // Triangles of every size and turn, slivers, points and huge ones: the reader's
        // batch must give each the bits the writer's `face_normal` gave it.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        let mut positions = Vec::new();
        for k in 0..3000 {
            let scale = [1e-30f32, 1e-3, 1.0, 100.0, 3e3, 1e18, 1e36][k % 7];
            positions.push([0, 1, 2].map(|_| ((next() % 20001) as f32 - 10000.0) / 1e4 * scale));
        }
        positions.extend([[0.0; 3], [0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]);
        let n = positions.len() as u64;
        let mut indices: Vec<u32> = (0..3 * 4001).map(|_| (next() % n) as u32).collect();
        indices.extend([3000, 3001, 3002, 3000, 3002, 3003, 7, 7, 7]);
        for len in [indices.len(), 3, 24, 27, 48 + 15] {
            let got = face_words(&positions, &indices[..len]);
            for (t, tri) in indices[..len].chunks_exact(3).enumerate() {
                let want = face_normal([0, 1, 2].map(|k| positions[tri[k] as usize]));
                assert_eq!(got[t], normal_word(want), "triangle {t} {tri:?}");
            }
        }
    }

    /// `assemble` as plainly as it can be written: one map from (position, normal) to
    /// vertex, corner after corner.
    fn assemble_plainly(
        positions: &[[f32; 3]],
        indices: &[u32],
        bits: &[u8],
        exceptions: &[QNormal],
    ) -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u32>) {
        let mut exceptions = exceptions.iter();
        let mut ids: FxHashMap<(u32, QNormal), u32> = FxHashMap::default();
        let (mut p, mut n, mut i) = (Vec::new(), Vec::new(), Vec::new());
        for (c, &at) in indices.iter().enumerate() {
            let tri = &indices[c - c % 3..][..3];
            let face = face_normal([0, 1, 2].map(|k| positions[tri[k] as usize]));
            let normal = if bits[c / 8] & (1 << (c % 8)) != 0 {
                *exceptions.next().unwrap()
            } else {
                face
            };
            let next = p.len() as u32;
            let v = *ids.entry((at, normal)).or_insert_with(|| {
                p.push(positions[at as usize]);
                n.push(dequantize_normal(normal));
                next
            });
            i.push(v);
        }
        (p, n, i)
    }

    #[test]
    fn a_position_of_many_normals_and_exceptions_join_as_plainly() {
        // A cone of 12 facets whose apex meets 12 normals (past the slots a position
        // keeps), then its base as a fan, each corner of some triangles an exception.
        let mut positions = vec![[0.0, 2.0, 0.0], [0.0, 0.0, 0.0]];
        for k in 0..12 {
            let a = k as f32 * std::f32::consts::TAU / 12.0;
            positions.push([a.cos(), 0.0, a.sin()]);
        }
        let mut indices = Vec::new();
        for k in 0..12u32 {
            let (r, s) = (2 + k, 2 + (k + 1) % 12);
            indices.extend([0, s, r, 1, r, s]);
        }
        let corners = indices.len();
        let mut bits = vec![0u8; bits_len(corners)];
        let mut exceptions = Vec::new();
        for c in (0..corners).filter(|c| c % 5 == 0 || c % 7 == 3) {
            bits[c / 8] |= 1 << (c % 8);
            exceptions.push([(c % 3) as i8 * 40, 90, -(c as i8), (c % 2) as i8]);
        }
        for (bits, exceptions) in [(vec![0u8; bits.len()], vec![]), (bits, exceptions)] {
            let want = assemble_plainly(&positions, &indices, &bits, &exceptions);
            let got = assemble(&positions, indices.clone(), &bits, &exceptions);
            assert_eq!(got, want);
        }
    }
}
