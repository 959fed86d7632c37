//! Which triangles meet at each vertex while the splits apply in order: what lets the
//! quantised encoding (`compact`) name a split's adjusted triangles and pivots by their
//! place around v_p rather than by number.
//!
//! A split's adjusted triangles all have v_p as a corner (Zheng's legality condition,
//! §3.2), and its pivots share a triangle with v_p in every mesh a legal collapse leaves.
//! Once the splits before it have applied, a reader knows v_p's triangles and
//! neighbours as well as the writer: one bit a triangle then says which move to v_c
//! (about 6 bits a split on smooth meshes, where the slot numbers took 6.4 bytes), and
//! a pivot is a small place in the neighbour list.

use super::vsplit::{SelectiveMesh, VertexSplit};
use crate::error::Result;
use crate::scene::Mesh;

/// A progressive mesh part refined, with each vertex's triangles.
pub(super) struct Incidence {
    mesh: SelectiveMesh,
    /// Per vertex slot: the triangle slots with it as a corner, ascending, each once.
    around: Vec<Vec<u32>>,
}

impl Incidence {
    /// The base mesh with room for `splits` splits; an `Err` as `SelectiveMesh::new`.
    pub(super) fn new(base: &Mesh, splits: usize) -> Result<Incidence> {
        let mesh = SelectiveMesh::new(base, splits)?;
        let mut around = vec![Vec::new(); base.positions.len() + splits];
        for (t, tri) in base.indices.chunks_exact(3).enumerate() {
            for (k, &v) in tri.iter().enumerate() {
                // A corner repeated in a degenerate triangle lists it once.
                if !tri[..k].contains(&v) {
                    around[v as usize].push(t as u32);
                }
            }
        }
        Ok(Incidence { mesh, around })
    }

    /// The triangles with `v` as a corner now, ascending (none for a vertex not there).
    pub(super) fn triangles(&self, v: u32) -> &[u32] {
        self.around.get(v as usize).map_or(&[], Vec::as_slice)
    }

    /// The vertices that share a triangle with `v` now, ascending, `v` left out.
    pub(super) fn neighbours(&self, v: u32, out: &mut Vec<u32>) {
        out.clear();
        let slots = self.mesh.slots();
        for &t in self.triangles(v) {
            out.extend(slots[t as usize].iter().filter(|&&w| w != v));
        }
        out.sort_unstable();
        out.dedup();
    }

    /// Applies split `index`, as `SelectiveMesh::split` checks it (an `Err`, and no
    /// change, when it is illegal here).
    pub(super) fn apply(&mut self, index: usize, s: &VertexSplit) -> Result<()> {
        self.mesh.split(index, s)?;
        let ids = self.mesh.ids(index);
        // The adjusted triangles leave v_p for v_c: both lists stay ascending, and the
        // new triangles' slots come after every slot so far.
        let from = &mut self.around[s.v_p as usize];
        let mut moved = s.adjusted.iter().peekable();
        from.retain(|t| {
            let hit = moved.peek() == Some(&t);
            if hit {
                moved.next();
            }
            !hit
        });
        self.around[ids.v_c as usize] = s.adjusted.clone();
        for (slot, tri) in s.new_triangles(ids) {
            for v in tri {
                self.around[v as usize].push(slot);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::fixtures::{building, grid};
    use crate::lod::ProgressiveMesh;

    #[test]
    fn every_vertex_lists_the_triangles_the_refined_mesh_gives_it() {
        for mesh in [crate::scene::bunny(), building(), grid(5)] {
            let pm = ProgressiveMesh::build(&mesh).unwrap();
            let mut inc = Incidence::new(&pm.base, pm.splits.len()).unwrap();
            for (i, s) in pm.splits.iter().enumerate() {
                inc.apply(i, s).unwrap();
            }
            let mut want = vec![Vec::new(); inc.around.len()];
            for (t, tri) in inc.mesh.slots().iter().enumerate() {
                for v in tri.iter().filter(|&&v| v != u32::MAX) {
                    if want[*v as usize].last() != Some(&(t as u32)) {
                        want[*v as usize].push(t as u32);
                    }
                }
            }
            assert_eq!(inc.around, want);
        }
    }
}
