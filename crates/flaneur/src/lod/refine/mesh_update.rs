//! The selective mesh as a renderer holds it — Zheng 2007 §4.5, Fig. 4.10: compact
//! vertex, normal and index arrays, and the ID maps that translate the progressive
//! mesh's numbers (the "full-model space") to array positions, so that vertex splits
//! and edge collapses apply without any adjacency structure:
//!
//! - V_F→A and its inverse V_A→F for vertices, and V_recycle, the array slots that
//!   collapsed vertices left: a removed vertex stays in the array (no triangle names it,
//!   so it draws nothing) and the next new vertex takes its slot;
//! - T_F→A and T_A→F for triangles: the index array stays one contiguous block, so a
//!   removed triangle's place is filled by the last triangle, and T_A→F finds the moved
//!   triangle's entry in T_F→A.
//!
//! Every array element written is recorded, and [`CompactMesh::take_changes`] hands
//! them over as sorted, merged ranges: what a renderer re-uploads each frame.
//!
//! Choices the thesis leaves open, made here:
//! - The maps from the full model are dense arrays over all of its vertices and
//!   triangle slots (4 bytes each): constant-time, where the thesis's client kept its
//!   auxiliary memory to the triangle budget ([`CompactMesh::memory`] reports both).
//! - Each operator is checked against the arrays before it changes anything (v_p and
//!   the pivots present, the slots free, the adjusted triangles holding v_p; for a
//!   collapse, f_l and f_r as the split made them): a mismatched progressive mesh is an
//!   error, never a corrupt array.
//! - A removed triangle's slot in the index array and a removed vertex's slot keep
//!   their stale contents; the changes report only what a renderer must draw.

use std::ops::Range;

use crate::scene::Mesh;

use crate::error::{Error, Result};
use crate::lod::dag::Dag;
use crate::lod::pm::{ProgressiveMesh, SplitIds, VertexSplit};

/// An absent entry of an ID map.
const NONE: u32 = u32::MAX;

/// The array ranges that changed since the last [`CompactMesh::take_changes`], sorted
/// and disjoint, each within the arrays' current lengths: what a renderer uploads.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MeshChanges {
    /// Ranges of vertex slots (positions and normals alike).
    pub vertices: Vec<Range<u32>>,
    /// Ranges of the index array, in indices (three per triangle).
    pub indices: Vec<Range<u32>>,
    /// The vertex arrays' length now (free slots included).
    pub vertex_len: u32,
    /// The index array's length now: three times the triangle count. A renderer draws
    /// exactly this many indices.
    pub index_len: u32,
}

impl MeshChanges {
    /// The number of vertex slots the ranges cover.
    pub fn vertex_count(&self) -> usize {
        self.vertices.iter().map(|r| r.len()).sum()
    }

    /// The number of indices the ranges cover.
    pub fn index_count(&self) -> usize {
        self.indices.iter().map(|r| r.len()).sum()
    }
}

/// The memory a [`CompactMesh`] takes, as Zheng 2007 Table 4.2 splits it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeshMemory {
    /// The arrays a renderer reads: positions, normals and indices (their lengths).
    pub render: usize,
    /// The ID maps, the free-slot list and the change records.
    pub aux: usize,
}

/// The selective mesh in compact arrays, with the ID maps of Zheng 2007 §4.5.
///
/// Vertex and triangle numbers of the full model are those of the progressive mesh's
/// renumbering (split `i` creates vertex `i + base vertices` and triangle slots
/// `2i + base triangles`, `2i + 1 + base triangles`). A [`Refiner`](super::Refiner)
/// owns one and applies each frame's operators to it.
#[derive(Clone, Debug)]
pub struct CompactMesh {
    base_vertices: usize,
    base_triangles: usize,
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    indices: Vec<u32>,
    v_f2a: Vec<u32>,
    v_a2f: Vec<u32>,
    v_recycle: Vec<u32>,
    t_f2a: Vec<u32>,
    t_a2f: Vec<u32>,
    dirty_v: Vec<u32>,
    dirty_t: Vec<u32>,
    dirty_v_flag: Vec<bool>,
    dirty_t_flag: Vec<bool>,
}

impl CompactMesh {
    /// The base mesh of `pm`, every array element marked changed (the first upload).
    /// An `Err` when the base is not a valid mesh or its numbers pass 32 bits.
    pub fn new(pm: &ProgressiveMesh) -> Result<CompactMesh> {
        CompactMesh::from_base(&pm.base, pm.splits.len())
    }

    /// The base mesh of a progressive mesh of `splits` vertex splits, as a client that
    /// holds no hierarchy starts from it (the splits then come one by one, with
    /// [`CompactMesh::apply_split`]). An `Err` as for [`CompactMesh::new`].
    ///
    /// ```
    /// use flaneur::lod::{CompactMesh, ProgressiveMesh};
    /// let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
    /// let mut mesh = CompactMesh::from_base(&pm.base, pm.splits.len())?;
    /// for (i, s) in pm.splits.iter().enumerate() {
    ///     mesh.apply_split(i, s)?;
    /// }
    /// assert_eq!(mesh.triangle_count(), pm.triangles_after(pm.splits.len()));
    /// # Ok::<(), flaneur::Error>(())
    /// ```
    pub fn from_base(base: &Mesh, splits: usize) -> Result<CompactMesh> {
        base.validate()
            .map_err(|e| Error::Invalid(format!("progressive mesh base: {e}")))?;
        let (nv, nt) = (base.positions.len(), base.triangle_count());
        let (all_v, all_t) = (
            nv.saturating_add(splits),
            nt.saturating_add(splits.saturating_mul(2)),
        );
        if all_v as u64 >= NONE as u64 || (all_t as u64).saturating_mul(3) >= NONE as u64 {
            return Err(Error::Invalid(format!(
                "progressive mesh of {all_v} vertices and {all_t} triangle slots: too many \
                 for 32-bit indices"
            )));
        }
        let mut v_f2a = vec![NONE; all_v];
        for (v, a) in v_f2a.iter_mut().enumerate().take(nv) {
            *a = v as u32;
        }
        let mut t_f2a = vec![NONE; all_t];
        for (t, a) in t_f2a.iter_mut().enumerate().take(nt) {
            *a = t as u32;
        }
        Ok(CompactMesh {
            base_vertices: nv,
            base_triangles: nt,
            positions: base.positions.clone(),
            normals: base.normals.clone(),
            indices: base.indices.clone(),
            v_f2a,
            v_a2f: (0..nv as u32).collect(),
            v_recycle: Vec::new(),
            t_f2a,
            t_a2f: (0..nt as u32).collect(),
            dirty_v: (0..nv as u32).collect(),
            dirty_t: (0..nt as u32).collect(),
            dirty_v_flag: vec![true; nv],
            dirty_t_flag: vec![true; nt],
        })
    }

    /// The vertex array's positions, free slots included.
    pub fn positions(&self) -> &[[f32; 3]] {
        &self.positions
    }

    /// The vertex array's normals, free slots included.
    pub fn normals(&self) -> &[[f32; 3]] {
        &self.normals
    }

    /// The index array: three vertex slots per triangle, every one of a present vertex.
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// The number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.t_a2f.len()
    }

    /// The number of present vertices (the vertex array less its free slots).
    pub fn vertex_count(&self) -> usize {
        self.positions.len() - self.v_recycle.len()
    }

    /// The full-model vertex in array slot `slot` (V_A→F); `None` for a free slot or
    /// one out of range.
    pub fn vertex_id(&self, slot: u32) -> Option<u32> {
        self.v_a2f
            .get(slot as usize)
            .copied()
            .filter(|&v| v != NONE)
    }

    /// The array slot of full-model vertex `v` (V_F→A); `None` when it is absent.
    pub fn vertex_slot(&self, v: u32) -> Option<u32> {
        self.v_f2a.get(v as usize).copied().filter(|&a| a != NONE)
    }

    /// The full-model triangle slot of array triangle `t` (T_A→F); `None` past the
    /// triangle count.
    pub fn triangle_id(&self, t: u32) -> Option<u32> {
        self.t_a2f.get(t as usize).copied()
    }

    /// The array triangle of full-model triangle slot `t` (T_F→A); `None` when absent.
    pub fn triangle_slot(&self, t: u32) -> Option<u32> {
        self.t_f2a.get(t as usize).copied().filter(|&a| a != NONE)
    }

    /// Array triangle `t`'s corners as full-model vertices. Panics past the triangle
    /// count, like slice indexing.
    pub fn full_triangle(&self, t: u32) -> [u32; 3] {
        let i = 3 * t as usize;
        [0, 1, 2].map(|k| self.v_a2f[self.indices[i + k] as usize])
    }

    /// The share (0–1) of `reference`'s triangles that this mesh also has, with the same
    /// corners: the accuracy measure of Zheng 2007 §4.6.2 (1 when `reference` is
    /// empty). Both meshes must come from one progressive mesh.
    pub fn shared_with(&self, reference: &CompactMesh) -> f64 {
        if reference.triangle_count() == 0 {
            return 1.0;
        }
        let shared = (0..reference.triangle_count() as u32)
            .filter(|&t| {
                let slot = reference.t_a2f[t as usize];
                self.triangle_slot(slot)
                    .is_some_and(|mine| self.full_triangle(mine) == reference.full_triangle(t))
            })
            .count();
        shared as f64 / reference.triangle_count() as f64
    }

    /// The triangles as a plain mesh: in array order, with only the vertices they use.
    pub fn to_mesh(&self) -> Mesh {
        let mut new_index = vec![NONE; self.positions.len()];
        let mut mesh = Mesh::default();
        mesh.indices.reserve(self.indices.len());
        for &a in &self.indices {
            let slot = &mut new_index[a as usize];
            if *slot == NONE {
                *slot = mesh.positions.len() as u32;
                mesh.positions.push(self.positions[a as usize]);
                mesh.normals.push(self.normals[a as usize]);
            }
            mesh.indices.push(*slot);
        }
        mesh
    }

    /// The bytes the arrays take, split as Zheng Table 4.2 does.
    pub fn memory(&self) -> MeshMemory {
        MeshMemory {
            render: 12 * (self.positions.len() + self.normals.len()) + 4 * self.indices.len(),
            aux: 4
                * (self.v_f2a.len()
                    + self.v_a2f.len()
                    + self.v_recycle.len()
                    + self.t_f2a.len()
                    + self.t_a2f.len()
                    + self.dirty_v.len()
                    + self.dirty_t.len())
                + self.dirty_v_flag.len()
                + self.dirty_t_flag.len(),
        }
    }

    /// The ranges changed since the last call (or since creation), and forgets them.
    pub fn take_changes(&mut self) -> MeshChanges {
        let vertex_len = self.positions.len() as u32;
        let triangles = self.t_a2f.len() as u32;
        let vertices = ranges(&mut self.dirty_v, &mut self.dirty_v_flag, vertex_len, 1);
        let indices = ranges(&mut self.dirty_t, &mut self.dirty_t_flag, triangles, 3);
        MeshChanges {
            vertices,
            indices,
            vertex_len,
            index_len: 3 * triangles,
        }
    }

    /// Applies the splits of DAG node `node`, in order. An `Err` when one does not apply
    /// here, and the mesh holds what it held (its arrays may be laid out otherwise).
    pub(crate) fn split_node(&mut self, dag: &Dag, pm: &ProgressiveMesh, node: u32) -> Result<()> {
        let run = dag.splits(node);
        for i in run.clone() {
            if let Err(e) = self.split(i, &pm.splits[i]) {
                for j in (run.start..i).rev() {
                    let _ = self.collapse(j, &pm.splits[j]);
                }
                return Err(e);
            }
        }
        Ok(())
    }

    /// Undoes the splits of DAG node `node`, last first. An `Err` when one does not
    /// apply here, and the mesh holds what it held (its arrays may be laid out
    /// otherwise).
    pub(crate) fn collapse_node(
        &mut self,
        dag: &Dag,
        pm: &ProgressiveMesh,
        node: u32,
    ) -> Result<()> {
        let run = dag.splits(node);
        for i in run.clone().rev() {
            if let Err(e) = self.collapse(i, &pm.splits[i]) {
                for j in i + 1..run.end {
                    let _ = self.split(j, &pm.splits[j]);
                }
                return Err(e);
            }
        }
        Ok(())
    }

    fn ids(&self, index: usize) -> Result<SplitIds> {
        let ids = SplitIds::new(index, self.base_vertices, self.base_triangles);
        if ids.v_c as usize >= self.v_f2a.len() || ids.f_r as usize >= self.t_f2a.len() {
            return Err(Error::Invalid(format!(
                "vertex split {index}: the selective mesh has room for {} splits",
                self.v_f2a.len() - self.base_vertices
            )));
        }
        Ok(ids)
    }

    fn present(&self, v: u32) -> std::result::Result<u32, String> {
        match self.v_f2a.get(v as usize) {
            Some(&a) if a != NONE => Ok(a),
            Some(_) => Err(format!("vertex {v} is absent")),
            None => Err(format!("vertex {v} is out of range")),
        }
    }

    /// The array triangles of `s`'s adjusted triangles, each checked to hold `corner`.
    fn check_adjusted(&self, s: &VertexSplit, corner: u32) -> std::result::Result<(), String> {
        for &t in &s.adjusted {
            let a = match self.t_f2a.get(t as usize) {
                None => return Err(format!("adjusted triangle {t} is out of range")),
                Some(&NONE) => return Err(format!("adjusted triangle {t} is absent")),
                Some(&a) => a as usize,
            };
            if !self.indices[3 * a..3 * a + 3].contains(&corner) {
                return Err(format!(
                    "adjusted triangle {t} has no corner at slot {corner}"
                ));
            }
        }
        Ok(())
    }

    /// Applies vertex split `index` of the progressive mesh, `s` its record: the
    /// operator a server streams. Checked against the arrays before anything changes
    /// (a split whose vertex is present, whose pivots or adjusted triangles are not, is
    /// an `Err` and leaves the mesh as it was).
    pub fn apply_split(&mut self, index: usize, s: &VertexSplit) -> Result<()> {
        self.split(index, s)
    }

    /// Undoes vertex split `index`, `s` its record (the edge collapse), checked as
    /// [`CompactMesh::apply_split`] is.
    pub fn apply_collapse(&mut self, index: usize, s: &VertexSplit) -> Result<()> {
        self.collapse(index, s)
    }

    fn split(&mut self, index: usize, s: &VertexSplit) -> Result<()> {
        let ids = self.ids(index)?;
        let bad = |what: String| Error::Invalid(format!("vertex split {index}: {what}"));
        if self.v_f2a[ids.v_c as usize] != NONE {
            return Err(bad(format!("vertex {} is already present", ids.v_c)));
        }
        let p = self.present(s.v_p).map_err(bad)?;
        for pivot in [s.v_l, s.v_r].into_iter().flatten() {
            self.present(pivot).map_err(bad)?;
        }
        for (slot, _) in s.new_triangles(ids) {
            if self.t_f2a[slot as usize] != NONE {
                return Err(bad(format!("triangle slot {slot} is taken")));
            }
        }
        self.check_adjusted(s, p).map_err(bad)?;

        let c = match self.v_recycle.pop() {
            Some(free) => {
                self.positions[free as usize] = s.position;
                self.normals[free as usize] = s.normal;
                self.v_a2f[free as usize] = ids.v_c;
                free
            }
            None => {
                self.positions.push(s.position);
                self.normals.push(s.normal);
                self.v_a2f.push(ids.v_c);
                self.dirty_v_flag.push(false);
                self.positions.len() as u32 - 1
            }
        };
        self.v_f2a[ids.v_c as usize] = c;
        self.mark_vertex(c);
        self.replace_corners(&s.adjusted, p, c);
        for (slot, t) in s.new_triangles(ids) {
            let a = self.t_a2f.len() as u32;
            self.indices.extend(t.map(|v| self.v_f2a[v as usize]));
            self.t_a2f.push(slot);
            self.t_f2a[slot as usize] = a;
            if self.dirty_t_flag.len() <= a as usize {
                self.dirty_t_flag.push(false);
            }
            self.mark_triangle(a);
        }
        Ok(())
    }

    fn collapse(&mut self, index: usize, s: &VertexSplit) -> Result<()> {
        let ids = self.ids(index)?;
        let bad = |what: String| Error::Invalid(format!("edge collapse {index}: {what}"));
        let c = self.present(ids.v_c).map_err(bad)?;
        let p = self.present(s.v_p).map_err(bad)?;
        for (slot, t) in s.new_triangles(ids) {
            let a = self.t_f2a[slot as usize];
            let made = a != NONE && {
                let a = 3 * a as usize;
                (0..3).all(|k| self.v_a2f[self.indices[a + k] as usize] == t[k])
            };
            if !made {
                return Err(bad(format!(
                    "triangle {slot} is not the one the split made"
                )));
            }
        }
        self.check_adjusted(s, c).map_err(bad)?;

        for (slot, _) in s.new_triangles(ids) {
            self.remove_triangle(slot);
        }
        self.replace_corners(&s.adjusted, c, p);
        self.v_f2a[ids.v_c as usize] = NONE;
        self.v_a2f[c as usize] = NONE;
        self.v_recycle.push(c);
        Ok(())
    }

    /// Removes full-model triangle `slot`, moving the last triangle into its place.
    fn remove_triangle(&mut self, slot: u32) {
        let a = self.t_f2a[slot as usize] as usize;
        let last = self.t_a2f.len() - 1;
        if a != last {
            let moved = self.t_a2f[last];
            self.indices.copy_within(3 * last..3 * last + 3, 3 * a);
            self.t_a2f[a] = moved;
            self.t_f2a[moved as usize] = a as u32;
            self.mark_triangle(a as u32);
        }
        self.indices.truncate(3 * last);
        self.t_a2f.pop();
        self.t_f2a[slot as usize] = NONE;
    }

    fn replace_corners(&mut self, triangles: &[u32], from: u32, to: u32) {
        for &t in triangles {
            let a = self.t_f2a[t as usize];
            for v in &mut self.indices[3 * a as usize..3 * a as usize + 3] {
                if *v == from {
                    *v = to;
                }
            }
            self.mark_triangle(a);
        }
    }

    fn mark_vertex(&mut self, a: u32) {
        if !std::mem::replace(&mut self.dirty_v_flag[a as usize], true) {
            self.dirty_v.push(a);
        }
    }

    fn mark_triangle(&mut self, a: u32) {
        if !std::mem::replace(&mut self.dirty_t_flag[a as usize], true) {
            self.dirty_t.push(a);
        }
    }
}

/// Sorts and merges the marked elements below `len` into ranges scaled by `scale`,
/// clearing the marks.
fn ranges(marked: &mut Vec<u32>, flags: &mut [bool], len: u32, scale: u32) -> Vec<Range<u32>> {
    marked.sort_unstable();
    let mut out: Vec<Range<u32>> = Vec::new();
    for &a in marked.iter() {
        flags[a as usize] = false;
        if a >= len {
            continue;
        }
        match out.last_mut() {
            Some(r) if r.end == scale * a => r.end += scale,
            _ => out.push(scale * a..scale * (a + 1)),
        }
    }
    marked.clear();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::{DagConstruction, SelectiveMesh};

    #[test]
    fn changes_cover_every_write_and_merge() {
        let pm = ProgressiveMesh::build(&crate::scene::bunny()).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        let mut m = CompactMesh::new(&pm).unwrap();
        let first = m.take_changes();
        assert_eq!(first.vertices, vec![0..pm.base.positions.len() as u32]);
        assert_eq!(first.indices, vec![0..pm.base.indices.len() as u32]);
        assert_eq!(m.take_changes().vertices, vec![]);
        // A shadow copy updated from the changes alone stays equal to the arrays.
        let mut shadow_p = m.positions().to_vec();
        let mut shadow_i = m.indices().to_vec();
        let mut selective = SelectiveMesh::new(&pm.base, pm.splits.len()).unwrap();
        let roots = dag.roots().to_vec();
        let mut waiting = dag.in_degrees();
        let mut order = Vec::new();
        let mut ready = roots.clone();
        while let Some(k) = ready.pop() {
            order.push(k);
            for &c in dag.children(k) {
                waiting[c as usize] -= 1;
                if waiting[c as usize] == 0 {
                    ready.push(c);
                }
            }
        }
        let sync = |m: &mut CompactMesh, sp: &mut Vec<[f32; 3]>, si: &mut Vec<u32>| {
            let ch = m.take_changes();
            sp.resize(ch.vertex_len as usize, [0.0; 3]);
            si.resize(ch.index_len as usize, 0);
            for w in ch.vertices.windows(2).chain(ch.indices.windows(2)) {
                assert!(w[0].end < w[1].start, "ranges are sorted, disjoint, merged");
            }
            for r in &ch.vertices {
                let r = r.start as usize..r.end as usize;
                sp[r.clone()].copy_from_slice(&m.positions()[r]);
            }
            for r in &ch.indices {
                let r = r.start as usize..r.end as usize;
                si[r.clone()].copy_from_slice(&m.indices()[r]);
            }
            assert_eq!(&si[..], m.indices());
            for &a in m.indices() {
                assert_eq!(sp[a as usize], m.positions()[a as usize]);
            }
        };
        for (step, &k) in order.iter().enumerate() {
            m.split_node(&dag, &pm, k).unwrap();
            dag.split_node(k, &pm, &mut selective).unwrap();
            if step % 50 == 0 {
                sync(&mut m, &mut shadow_p, &mut shadow_i);
            }
        }
        sync(&mut m, &mut shadow_p, &mut shadow_i);
        assert_eq!(m.triangle_count(), 3674);
        // Collapse back half, which frees vertex slots and moves triangles.
        for &k in order.iter().rev().take(order.len() / 2) {
            m.collapse_node(&dag, &pm, k).unwrap();
            dag.collapse_node(k, &pm, &mut selective).unwrap();
        }
        sync(&mut m, &mut shadow_p, &mut shadow_i);
        assert_eq!(m.triangle_count(), selective.triangle_count());
        assert!(m.vertex_count() < m.positions().len(), "free slots");
        let before = m.positions().len();
        // Re-splitting reuses the free slots before growing.
        for &k in order.iter().skip(order.len() - order.len() / 2).take(10) {
            m.split_node(&dag, &pm, k).unwrap();
        }
        assert_eq!(m.positions().len(), before);
        sync(&mut m, &mut shadow_p, &mut shadow_i);
        let mem = m.memory();
        assert!(mem.render > 0 && mem.aux > 0);
    }

    #[test]
    fn illegal_operators_are_errors_and_change_nothing() {
        let pm = ProgressiveMesh::build(&crate::lod::fixtures::building()).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        let mut m = CompactMesh::new(&pm).unwrap();
        // What the mesh holds, whatever the arrays' layout: triangles by slot, vertices.
        let snapshot = |m: &CompactMesh| {
            let mut t: Vec<(u32, [u32; 3])> = (0..m.triangle_count() as u32)
                .map(|t| (m.triangle_id(t).unwrap(), m.full_triangle(t)))
                .collect();
            t.sort_unstable();
            (t, m.vertex_count())
        };
        let before = snapshot(&m);
        let orphan = (0..dag.node_count() as u32)
            .find(|&k| dag.in_degree(k) > 0)
            .unwrap();
        assert!(m.split_node(&dag, &pm, orphan).is_err());
        let root = dag.roots()[0];
        assert!(m.collapse_node(&dag, &pm, root).is_err());
        assert_eq!(snapshot(&m), before);
        // A run failing at its last split leaves nothing behind. Node order is a
        // topological order: split every node before the first run.
        let run = (0..dag.node_count() as u32)
            .find(|&k| dag.splits(k).len() > 1)
            .expect("the building has runs");
        for k in 0..run {
            m.split_node(&dag, &pm, k).unwrap();
        }
        let before = snapshot(&m);
        let mut broken = pm.clone();
        broken.splits[dag.splits(run).end - 1].v_p = 1 << 30;
        assert!(m.split_node(&dag, &broken, run).is_err());
        assert_eq!(snapshot(&m), before);
        m.split_node(&dag, &pm, run).unwrap();
        assert!(m
            .split_node(&dag, &pm, run)
            .unwrap_err()
            .to_string()
            .contains("already present"));
    }
}
