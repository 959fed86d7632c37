//! The vertex split and its inverse, the half-edge collapse — Zheng 2007 §3.2, Fig. 3.4
//! and Fig. 3.5.
//!
//! A split is stored with everything it changes, so it applies without asking the mesh
//! about its neighbourhood: the vertex v_p it splits, the new vertex v_c (position and
//! normal), the pivots v_l and v_r, the *adjusted triangles* whose corner moves from v_p
//! to v_c, and the error of the collapse it undoes. As in Fig. 3.5, v_c and the two new
//! triangles are not stored but implied by the split's place in the list:
//! v_c = i + base_ver_num, f_l = 2i + base_tri_num, f_r = 2i + 1 + base_tri_num.
//!
//! Departures from Fig. 3.5, each for a reason:
//! - A missing pivot is `None` rather than −1, as Rust spells it; an on-disk codec
//!   writes −1. A missing f_l or f_r leaves its slot empty (`NO_TRIANGLE`).
//! - `corners` says where v_p stands in f_l and f_r, so that a split restores each
//!   triangle with its original first corner and the fully refined mesh is the original
//!   index for index. Fig. 3.5 builds f_l = (v_p, v_c, v_l): the same oriented
//!   triangle, rotated.
//! - A collapse of a position on a crease or seam moves several vertices (one per
//!   wedge, see `topology`). Each becomes its own split, with the one or two triangles
//!   on its side; `joins_previous` marks the splits after the first of such a run,
//!   which must be applied together or the surface cracks along the crease.

use crate::scene::Mesh;

use crate::error::{Error, Result};

/// An empty triangle slot of a [`SelectiveMesh`].
pub const NO_TRIANGLE: [u32; 3] = [u32::MAX; 3];

/// One vertex split (and, read backwards, the half-edge collapse of v_c onto v_p).
///
/// Vertex and triangle numbers are those of the progressive mesh's renumbering: the
/// base mesh's vertices and triangles first, then those the splits create, in order.
#[derive(Clone, Debug, PartialEq)]
pub struct VertexSplit {
    /// The vertex that splits: the one v_c was collapsed onto.
    pub v_p: u32,
    /// v_c's position.
    pub position: [f32; 3],
    /// v_c's normal.
    pub normal: [f32; 3],
    /// The left pivot: the third corner of f_l = (v_p, v_c, v_l). `None` when the split
    /// adds no f_l (a boundary edge, or a crease whose other side is a sibling split's).
    pub v_l: Option<u32>,
    /// The right pivot: the third corner of f_r = (v_c, v_p, v_r); `None` as for `v_l`.
    pub v_r: Option<u32>,
    /// The triangles whose corner v_p becomes v_c, ascending.
    pub adjusted: Vec<u32>,
    /// The corner (0–2) of f_l and of f_r that v_p takes.
    pub corners: [u8; 2],
    /// The error of the collapse: the root of the area-weighted mean squared distance
    /// from v_p to the planes of the original triangles merged into it (metres).
    pub error: f32,
    /// Whether this split belongs to the same collapse of a position as the split
    /// before it; a run of such splits must be applied together.
    pub joins_previous: bool,
}

/// The implicit indices of split `i` (Zheng Fig. 3.5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SplitIds {
    /// The vertex the split creates: `i + base vertices`.
    pub v_c: u32,
    /// The slot of f_l: `2i + base triangles`.
    pub f_l: u32,
    /// The slot of f_r: `2i + 1 + base triangles`.
    pub f_r: u32,
}

impl SplitIds {
    /// The indices of split `index` of a progressive mesh whose base has
    /// `base_vertices` vertices and `base_triangles` triangles.
    pub fn new(index: usize, base_vertices: usize, base_triangles: usize) -> SplitIds {
        SplitIds {
            v_c: (index + base_vertices) as u32,
            f_l: (2 * index + base_triangles) as u32,
            f_r: (2 * index + 1 + base_triangles) as u32,
        }
    }
}

impl VertexSplit {
    /// The triangles the split adds, as (slot, corners), f_l then f_r.
    pub(crate) fn new_triangles(
        &self,
        ids: SplitIds,
    ) -> impl Iterator<Item = (u32, [u32; 3])> + '_ {
        let place = |first: u32, second: u32, corner: u8| {
            let k = corner as usize % 3;
            let mut t = [0; 3];
            t[k] = self.v_p;
            t[(k + 1) % 3] = first;
            t[(k + 2) % 3] = second;
            t
        };
        let left = self
            .v_l
            .map(|l| (ids.f_l, place(ids.v_c, l, self.corners[0])));
        let right = self
            .v_r
            .map(|r| (ids.f_r, place(r, ids.v_c, self.corners[1])));
        left.into_iter().chain(right)
    }

    /// The number of triangles the split adds (0, 1 or 2).
    pub fn added_triangles(&self) -> usize {
        self.v_l.is_some() as usize + self.v_r.is_some() as usize
    }
}

/// A mesh that vertex splits and half-edge collapses act on in place: every vertex and
/// triangle of a progressive mesh has its slot, by the renumbering, and a slot is empty
/// until the split that creates it. Which splits are applied is up to the caller —
/// in the order of the list (a [`PmCursor`](super::PmCursor)), or selectively.
#[derive(Clone, Debug, PartialEq)]
pub struct SelectiveMesh {
    base_vertices: usize,
    base_triangles: usize,
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    present: Vec<bool>,
    triangles: Vec<[u32; 3]>,
    live: usize,
}

impl SelectiveMesh {
    /// The base mesh, with room for `splits` splits. An `Err` when the base fails
    /// `Mesh::validate`, or its slots would pass 32-bit indices.
    pub fn new(base: &Mesh, splits: usize) -> Result<SelectiveMesh> {
        base.validate()
            .map_err(|e| Error::Invalid(format!("progressive mesh base: {e}")))?;
        let (nv, nt) = (base.positions.len(), base.triangle_count());
        if (nv + splits) as u64 >= u32::MAX as u64 || (nt + 2 * splits) as u64 >= u32::MAX as u64 {
            return Err(Error::Invalid(format!(
                "progressive mesh: {splits} splits are too many for 32-bit indices"
            )));
        }
        let mut positions = base.positions.clone();
        positions.resize(nv + splits, [0.0; 3]);
        let mut normals = base.normals.clone();
        normals.resize(nv + splits, [0.0; 3]);
        let mut present = vec![true; nv];
        present.resize(nv + splits, false);
        let mut triangles: Vec<[u32; 3]> = base
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        triangles.resize(nt + 2 * splits, NO_TRIANGLE);
        Ok(SelectiveMesh {
            base_vertices: nv,
            base_triangles: nt,
            positions,
            normals,
            present,
            triangles,
            live: nt,
        })
    }

    /// The implicit indices of split `index` in this mesh.
    pub fn ids(&self, index: usize) -> SplitIds {
        SplitIds::new(index, self.base_vertices, self.base_triangles)
    }

    /// Every vertex slot's position (zero until the split that creates it).
    pub fn positions(&self) -> &[[f32; 3]] {
        &self.positions
    }

    /// Every vertex slot's normal (zero until the split that creates it).
    pub fn normals(&self) -> &[[f32; 3]] {
        &self.normals
    }

    /// Every triangle slot; empty ones hold [`NO_TRIANGLE`].
    pub fn slots(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The number of triangles present.
    pub fn triangle_count(&self) -> usize {
        self.live
    }

    /// Applies split `index`: adds v_c, f_l and f_r, and moves the adjusted triangles'
    /// v_p corners to v_c. An `Err` — and no change — when the split is illegal here: v_c
    /// already present, v_p absent, a new triangle's slot taken, or an adjusted triangle
    /// absent or without v_p (Zheng's legality condition, §3.2).
    pub fn split(&mut self, index: usize, s: &VertexSplit) -> Result<()> {
        let ids = self.checked_ids(index)?;
        let bad = |what: String| Error::Invalid(format!("vertex split {index}: {what}"));
        if self.present[ids.v_c as usize] {
            return Err(bad(format!("vertex {} is already present", ids.v_c)));
        }
        self.check_vertex(s.v_p).map_err(bad)?;
        for pivot in [s.v_l, s.v_r].into_iter().flatten() {
            self.check_vertex(pivot).map_err(bad)?;
        }
        for (slot, _) in s.new_triangles(ids) {
            if self.triangles[slot as usize] != NO_TRIANGLE {
                return Err(bad(format!("triangle slot {slot} is taken")));
            }
        }
        self.check_adjusted(s, s.v_p).map_err(bad)?;

        let c = ids.v_c as usize;
        self.positions[c] = s.position;
        self.normals[c] = s.normal;
        self.present[c] = true;
        self.replace_corners(&s.adjusted, s.v_p, ids.v_c);
        for (slot, t) in s.new_triangles(ids) {
            self.triangles[slot as usize] = t;
            self.live += 1;
        }
        Ok(())
    }

    /// Undoes split `index` (the half-edge collapse of v_c onto v_p): removes f_l and
    /// f_r, moves the adjusted triangles' v_c corners back to v_p, and removes v_c. An
    /// `Err` — and no change — when the collapse is illegal here: v_c absent, f_l or
    /// f_r not as the split made them, or an adjusted triangle without v_c.
    pub fn collapse(&mut self, index: usize, s: &VertexSplit) -> Result<()> {
        let ids = self.checked_ids(index)?;
        let bad = |what: String| Error::Invalid(format!("edge collapse {index}: {what}"));
        if !self.present[ids.v_c as usize] {
            return Err(bad(format!("vertex {} is absent", ids.v_c)));
        }
        self.check_vertex(s.v_p).map_err(bad)?;
        for (slot, t) in s.new_triangles(ids) {
            if self.triangles[slot as usize] != t {
                return Err(bad(format!(
                    "triangle {slot} is not the one the split made"
                )));
            }
        }
        self.check_adjusted(s, ids.v_c).map_err(bad)?;

        for (slot, _) in s.new_triangles(ids) {
            self.triangles[slot as usize] = NO_TRIANGLE;
            self.live -= 1;
        }
        self.replace_corners(&s.adjusted, ids.v_c, s.v_p);
        let c = ids.v_c as usize;
        self.present[c] = false;
        self.positions[c] = [0.0; 3];
        self.normals[c] = [0.0; 3];
        Ok(())
    }

    /// The present triangles as a plain mesh: triangles in slot order, and only the
    /// vertices they use, in index order.
    pub fn to_mesh(&self) -> Mesh {
        let mut new_index = vec![u32::MAX; self.positions.len()];
        for t in self.triangles.iter().filter(|t| **t != NO_TRIANGLE) {
            for &v in t {
                new_index[v as usize] = 0;
            }
        }
        let mut mesh = Mesh::default();
        for (v, slot) in new_index.iter_mut().enumerate() {
            if *slot == 0 {
                *slot = mesh.positions.len() as u32;
                mesh.positions.push(self.positions[v]);
                mesh.normals.push(self.normals[v]);
            }
        }
        mesh.indices.reserve(3 * self.live);
        for t in self.triangles.iter().filter(|t| **t != NO_TRIANGLE) {
            mesh.indices
                .extend(t.iter().map(|&v| new_index[v as usize]));
        }
        mesh
    }

    fn checked_ids(&self, index: usize) -> Result<SplitIds> {
        let ids = self.ids(index);
        if ids.v_c as usize >= self.present.len() || ids.f_r as usize >= self.triangles.len() {
            return Err(Error::Invalid(format!(
                "vertex split {index}: this mesh has room for {} splits",
                self.present.len() - self.base_vertices
            )));
        }
        Ok(ids)
    }

    fn check_vertex(&self, v: u32) -> std::result::Result<(), String> {
        match self.present.get(v as usize) {
            Some(true) => Ok(()),
            Some(false) => Err(format!("vertex {v} is absent")),
            None => Err(format!("vertex {v} is out of range")),
        }
    }

    fn check_adjusted(&self, s: &VertexSplit, corner: u32) -> std::result::Result<(), String> {
        for &t in &s.adjusted {
            match self.triangles.get(t as usize) {
                None => return Err(format!("adjusted triangle {t} is out of range")),
                Some(tri) if !tri.contains(&corner) => {
                    return Err(format!("adjusted triangle {t} has no corner {corner}"))
                }
                _ => {}
            }
        }
        Ok(())
    }

    fn replace_corners(&mut self, triangles: &[u32], from: u32, to: u32) {
        for &t in triangles {
            for v in &mut self.triangles[t as usize] {
                if *v == from {
                    *v = to;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fan of four triangles around vertex 0 (a square split at its centre, 0 at the
    /// centre), and the split that restores it from three triangles around vertex 1.
    fn square() -> (Mesh, VertexSplit) {
        // Base: vertices 1..=4 renumbered 0..=3 (corners), the centre is split 0's v_c = 4.
        // Full mesh: centre c=4 with corners 0 (−,−), 1 (+,−), 2 (+,+), 3 (−,+).
        // Collapsing c onto corner 0 leaves triangles (0,1,2) and (0,2,3).
        let base = Mesh {
            positions: vec![
                [-1.0, 0.0, -1.0],
                [1.0, 0.0, -1.0],
                [1.0, 0.0, 1.0],
                [-1.0, 0.0, 1.0],
            ],
            normals: vec![[0.0, 1.0, 0.0]; 4],
            indices: vec![0, 2, 1, 0, 3, 2],
        };
        let split = VertexSplit {
            v_p: 0,
            position: [0.0; 3],
            normal: [0.0, 1.0, 0.0],
            v_l: Some(1),
            v_r: Some(3),
            adjusted: vec![0, 1],
            corners: [0, 0],
            error: 0.0,
            joins_previous: false,
        };
        (base, split)
    }

    #[test]
    fn split_then_collapse_round_trips() {
        let (base, s) = square();
        let mut m = SelectiveMesh::new(&base, 1).unwrap();
        let before = m.clone();
        m.split(0, &s).unwrap();
        assert_eq!(m.triangle_count(), 4);
        assert_eq!(m.slots(), &[[4, 2, 1], [4, 3, 2], [0, 4, 1], [0, 3, 4]]);
        // Every triangle still faces +y (CCW seen from above).
        let out = m.to_mesh();
        assert!(out.validate().is_ok());
        for t in out.indices.chunks_exact(3) {
            let p = |i: u32| glam::Vec3::from(out.positions[i as usize]);
            let n = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
            assert!(n.y > 0.0, "{t:?}");
        }
        m.collapse(0, &s).unwrap();
        assert_eq!(m, before);
    }

    #[test]
    fn illegal_operators_are_errors_and_change_nothing() {
        let (base, s) = square();
        let mut m = SelectiveMesh::new(&base, 1).unwrap();
        let before = m.clone();
        assert!(m.collapse(0, &s).is_err());
        assert!(m.split(1, &s).is_err());
        let mut bad = s.clone();
        bad.adjusted.push(7);
        assert!(m.split(0, &bad).is_err());
        let mut bad = s.clone();
        bad.v_p = 9;
        assert!(m.split(0, &bad).is_err());
        assert_eq!(m, before);
        m.split(0, &s).unwrap();
        assert!(m
            .split(0, &s)
            .unwrap_err()
            .to_string()
            .contains("already present"));
    }
}
