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
//! Both sides compute a face's normal with [`face_normal`] from the same dequantised
//! positions, so the bits agree wherever the file does.

use super::quantize::{quantize_normal, Grid, QNormal, QPosition};
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
    /// Each triangle's face normal.
    faces: Vec<QNormal>,
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
    /// corner's bit goes with the corner. A triangle whose three corners are one position
    /// has no turn to find; its corners' normals stay in their slots, which draws the
    /// same nothing.
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
            for k in 0..3 {
                let n = self.normals[3 * t + (k + turn) % 3];
                if n != self.faces[t] {
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
            faces: Vec::with_capacity(corners.len() / 3),
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
            level.faces.push(face_normal(at));
            for (k, (_, n)) in tri.iter().enumerate() {
                vertices.insert((level.indices[3 * t + k], *n));
            }
        }
        level.added = self.all[first_new..].to_vec();
        level.vertices = vertices.len();
        level
    }

    /// Forgets the positions added since there were `len`: a layout tried and not kept.
    pub(crate) fn truncate(&mut self, len: usize) {
        for q in self.all.drain(len..) {
            self.ids.remove(&q);
        }
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
/// share a position and a normal become one vertex. The caller has checked every index
/// against `positions` and the exceptions' count against the bits.
#[inline]
pub(crate) fn assemble(
    positions: &[[f32; 3]],
    indices: &[u32],
    bits: &[u8],
    exceptions: &[QNormal],
) -> (Vec<[f32; 3]>, Vec<QNormal>, Vec<u32>) {
    // Every corner its face's normal, then the exceptions over theirs: two plain passes
    // rather than a bit test in the join below (which it made twice as slow).
    let mut normals: Vec<u32> = Vec::with_capacity(indices.len());
    for tri in indices.chunks_exact(3) {
        let face = word(face_normal([0, 1, 2].map(|k| positions[tri[k] as usize])));
        normals.extend_from_slice(&[face; 3]);
    }
    let mut exceptions = exceptions.iter();
    for (at, &byte) in bits.iter().enumerate() {
        let mut b = byte;
        while b != 0 {
            let c = 8 * at + b.trailing_zeros() as usize;
            b &= b - 1;
            if let (Some(slot), Some(&n)) = (normals.get_mut(c), exceptions.next()) {
                *slot = word(n);
            }
        }
    }
    // Each position's vertices as a chain: a position meets few normals (three at a
    // box's corner), so a walk along it beats hashing every corner.
    const NONE: u32 = u32::MAX;
    let mut head = vec![NONE; positions.len()];
    let mut next: Vec<u32> = Vec::with_capacity(positions.len() * 2);
    let mut out_p = Vec::with_capacity(positions.len() * 2);
    let mut out_n: Vec<u32> = Vec::with_capacity(positions.len() * 2);
    let mut out_i = Vec::with_capacity(indices.len());
    for (&p, &n) in indices.iter().zip(&normals) {
        let mut v = head[p as usize];
        while v != NONE && out_n[v as usize] != n {
            v = next[v as usize];
        }
        if v == NONE {
            v = out_p.len() as u32;
            out_p.push(positions[p as usize]);
            out_n.push(n);
            next.push(head[p as usize]);
            head[p as usize] = v;
        }
        out_i.push(v);
    }
    let out_n = out_n
        .into_iter()
        .map(|w| w.to_ne_bytes().map(|c| c as i8))
        .collect();
    (out_p, out_n, out_i)
}

#[inline]
fn word(n: QNormal) -> u32 {
    u32::from_ne_bytes(n.map(|c| c as u8))
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let (p, n, i) = assemble(&positions, &level.indices, &e.bits, &e.normals);
        assert_eq!(p.len(), level.vertices);
        // Every corner reads back its own position and normal.
        for (c, &v) in i.iter().enumerate() {
            assert_eq!(grid.quantize(p[v as usize]), corners[c].0);
            assert_eq!(n[v as usize], corners[c].1);
        }
    }

    #[test]
    fn a_tried_layout_is_forgotten() {
        let grid = Grid {
            min: [0.0; 3],
            max: [1.0; 3],
        };
        let q = |x: u16| ([x, 0, 0, 0], [0, 127, 0, 0]);
        let mut shared = SharedPositions::default();
        shared.lay_out(&grid, &[q(1), q(2), q(3)]);
        shared.lay_out(&grid, &[q(4), q(2), q(5)]);
        assert_eq!(shared.len(), 5);
        shared.truncate(3);
        let again = shared.lay_out(&grid, &[q(5), q(4), q(1)]);
        assert_eq!(again.added, vec![q(5).0, q(4).0]);
        assert_eq!(again.indices, vec![3, 4, 0]);
    }
}
