//! A client's selectively refined mesh, split and collapsed in place from the cut
//! vertices' active ancestors alone (Kim–Lee–Kobbelt §5.3).

use crate::error::{Error, Result};
use crate::lod::pm::NO_TRIANGLE;

/// A selectively refined mesh kept as its triangles over active nodes, split and
/// collapsed in place as a client does that holds only part of the hierarchy
/// (Kim–Lee–Kobbelt §5.3): a split of `node` into its children is told the active
/// ancestors of its cut vertices, which bound the fan of triangles around `node` that
/// go to the right child; the rest go to the left, and the split's one or two new
/// triangles join them. It needs neither the fully refined mesh nor the nodes below
/// the front.
///
/// ```
/// use flaneur::lod::{CutMesh, ProgressiveMesh, VertexHierarchy};
/// let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
/// let h = VertexHierarchy::new(&pm)?;
/// let mut front = h.roots();
/// let mut mesh = CutMesh::new(&front.triangles(&h));
/// let node = h.split_node(0);
/// let cuts = h.cut_vertices(node).unwrap().map(|c| c.map(|c| front.active_ancestor(&h, c)));
/// front.split(&h, node)?;
/// mesh.split(node, h.children(node).unwrap(), cuts)?;
/// let (mut ours, mut truth) = (mesh.triangles(), front.triangles(&h));
/// assert_eq!(ours.len(), truth.len());
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct CutMesh {
    /// Triangle slots; a freed one is `NO_TRIANGLE`.
    slots: Vec<[u32; 3]>,
    free: Vec<u32>,
    /// The slots each vertex is a corner of.
    around: std::collections::HashMap<u32, Vec<u32>>,
}

impl CutMesh {
    /// The mesh of `triangles` (a front's, the roots' for a client that starts).
    pub fn new(triangles: &[[u32; 3]]) -> CutMesh {
        let mut m = CutMesh::default();
        for t in triangles {
            m.add(*t);
        }
        m
    }

    /// Its triangles, in no particular order.
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        self.slots
            .iter()
            .copied()
            .filter(|t| *t != NO_TRIANGLE)
            .collect()
    }

    /// Splits vertex `node` into `[left, right]`, its cut vertices' active ancestors
    /// being `cuts` (`None` where the split adds no such triangle). An `Err`, and no
    /// change, when the fan around `node` does not run from one cut to the other.
    pub fn split(
        &mut self,
        node: u32,
        [left, right]: [u32; 2],
        cuts: [Option<u32>; 2],
    ) -> Result<()> {
        let bad = |what: &str| Error::Invalid(format!("splitting vertex {node}: {what}"));
        // The fan around `node`: each triangle (node, x, y) links x to y.
        let fan = self.around.get(&node).cloned().unwrap_or_default();
        let mut next = std::collections::HashMap::new();
        let mut prev = std::collections::HashMap::new();
        for &slot in &fan {
            let t = self.slots[slot as usize];
            let k = t
                .iter()
                .position(|&v| v == node)
                .ok_or_else(|| bad("a stale corner"))?;
            let (x, y) = (t[(k + 1) % 3], t[(k + 2) % 3]);
            if next.insert(x, (y, slot)).is_some() || prev.insert(y, x).is_some() {
                return Err(bad("its fan is not a manifold's"));
            }
        }
        // The right child takes the triangles from its right cut round to its left one
        // (f_r = (left, a_r, right) and f_l = (left, right, a_l) close the two fans);
        // on a boundary or crease, from the fan's open end, or to it.
        let start = match cuts {
            [_, Some(r)] => r,
            [Some(l), None] => {
                let mut x = l;
                for _ in 0..=fan.len() {
                    match prev.get(&x) {
                        Some(&p) if p != l => x = p,
                        _ => break,
                    }
                }
                if prev.contains_key(&x) {
                    return Err(bad("one cut vertex, and its fan is closed"));
                }
                x
            }
            [None, None] => {
                return Err(bad(
                    "its split adds no triangle (a wedge of a crease or seam), so no cut \
                     vertex places it: KLK's scheme assumes manifold vertex splits",
                ))
            }
        };
        let mut to_right = Vec::new();
        let mut x = start;
        while Some(x) != cuts[0] {
            let Some(&(y, slot)) = next.get(&x) else {
                if cuts[0].is_none() {
                    break;
                }
                return Err(bad("its fan does not run from the right cut to the left"));
            };
            to_right.push(slot);
            x = y;
            if to_right.len() > fan.len() {
                return Err(bad("its fan runs round without meeting the left cut"));
            }
        }
        for &slot in &fan {
            let to = if to_right.contains(&slot) {
                right
            } else {
                left
            };
            self.recorner(slot, node, to);
        }
        self.around.remove(&node);
        if let Some(l) = cuts[0] {
            self.add([left, right, l]);
        }
        if let Some(r) = cuts[1] {
            self.add([left, r, right]);
        }
        Ok(())
    }

    /// Collapses `[left, right]` back into `node`: the triangles they share go, the rest
    /// take `node` for their corner.
    pub fn collapse(&mut self, node: u32, [left, right]: [u32; 2]) {
        let mut slots = self.around.remove(&left).unwrap_or_default();
        slots.extend(self.around.remove(&right).unwrap_or_default());
        slots.sort_unstable();
        slots.dedup();
        for slot in slots {
            let t =
                self.slots[slot as usize].map(|v| if v == left || v == right { node } else { v });
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                self.remove(slot);
            } else {
                self.slots[slot as usize] = t;
                self.around.entry(node).or_default().push(slot);
            }
        }
    }

    /// Whether collapsing `[left, right]` into `node` keeps the mesh a manifold: no
    /// directed edge at `node` twice (the only edges a collapse changes; `node` itself
    /// is no corner before it).
    pub fn collapse_keeps_manifold(&self, node: u32, [left, right]: [u32; 2]) -> bool {
        let mut slots: Vec<u32> = [left, right]
            .iter()
            .flat_map(|v| self.around.get(v).into_iter().flatten().copied())
            .collect();
        slots.sort_unstable();
        slots.dedup();
        let mut edges = std::collections::HashSet::new();
        slots.iter().all(|&slot| {
            let t =
                self.slots[slot as usize].map(|v| if v == left || v == right { node } else { v });
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return true;
            }
            (0..3).all(|k| {
                let e = (t[k], t[(k + 1) % 3]);
                !(e.0 == node || e.1 == node) || edges.insert(e)
            })
        })
    }

    fn add(&mut self, t: [u32; 3]) {
        let slot = match self.free.pop() {
            Some(s) => {
                self.slots[s as usize] = t;
                s
            }
            None => {
                self.slots.push(t);
                self.slots.len() as u32 - 1
            }
        };
        for v in t {
            self.around.entry(v).or_default().push(slot);
        }
    }

    fn remove(&mut self, slot: u32) {
        for v in self.slots[slot as usize] {
            if let Some(list) = self.around.get_mut(&v) {
                list.retain(|&s| s != slot);
            }
        }
        self.slots[slot as usize] = NO_TRIANGLE;
        self.free.push(slot);
    }

    fn recorner(&mut self, slot: u32, from: u32, to: u32) {
        for v in &mut self.slots[slot as usize] {
            if *v == from {
                *v = to;
            }
        }
        self.around.entry(to).or_default().push(slot);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::pm::ProgressiveMesh;
    use crate::lod::selective::VertexHierarchy;
    use rand::{Rng, SeedableRng};

    /// `triangles` each turned to start at its smallest corner, sorted: the same mesh
    /// gives the same list whatever the slots and rotations.
    fn canonical(mut triangles: Vec<[u32; 3]>) -> Vec<[u32; 3]> {
        for t in &mut triangles {
            let k = (0..3).min_by_key(|&k| t[k]).unwrap();
            t.rotate_left(k);
        }
        triangles.sort_unstable();
        triangles
    }

    /// A client's mesh, split and collapsed in place as the front moves at random,
    /// equals the front's mesh triangle for triangle after every step.
    fn mirrors(mesh: &crate::scene::Mesh, seed: u64, steps: usize) {
        let pm = ProgressiveMesh::build(mesh).unwrap();
        let h = VertexHierarchy::new(&pm).unwrap();
        let mut front = h.roots();
        let mut client = CutMesh::new(&front.triangles(&h));
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        for step in 0..steps {
            let node = rng.gen_range(0..h.len() as u32);
            if rng.gen_bool(0.7) {
                if !(front.is_active(node) && h.children(node).is_some()) {
                    continue;
                }
                // The nodes split in order, each told its cuts as they stand then.
                let mut probe = front.clone();
                for n in probe.split(&h, node).unwrap() {
                    let cuts = h
                        .cut_vertices(n)
                        .unwrap()
                        .map(|c| c.map(|c| front.active_ancestor(&h, c)));
                    client.split(n, h.children(n).unwrap(), cuts).unwrap();
                    let [l, r] = h.children(n).unwrap();
                    front.active[n as usize] = false;
                    front.active[l as usize] = true;
                    front.active[r as usize] = true;
                }
                assert_eq!(front, probe);
            } else if front.can_collapse(&h, node) {
                for n in h.run_nodes(node) {
                    client.collapse(n, h.children(n).unwrap());
                }
                front.collapse(&h, node).unwrap();
            } else {
                continue;
            }
            assert_eq!(
                canonical(client.triangles()),
                canonical(front.triangles(&h)),
                "step {step}"
            );
        }
    }

    #[test]
    fn a_client_mesh_equals_the_fronts_triangle_for_triangle() {
        mirrors(&crate::lod::bumpy_torus(3000), 11, 3000);
        mirrors(&crate::scene::bunny(), 12, 3000);
        mirrors(&crate::lod::fixtures::grid(24), 14, 2000);
    }

    #[test]
    fn a_wedge_split_that_adds_no_triangle_is_refused_by_name() {
        // A flat-shaded building: every corner a seam; some of its wedges' splits add no
        // triangle, which cut vertices cannot place.
        let pm = ProgressiveMesh::build(&crate::lod::fixtures::building()).unwrap();
        let h = VertexHierarchy::new(&pm).unwrap();
        let mut front = h.roots();
        let mut client = CutMesh::new(&front.triangles(&h));
        let refused = (0..pm.splits.len()).find_map(|i| {
            let n = h.split_node(i);
            let cuts = h
                .cut_vertices(n)
                .unwrap()
                .map(|c| c.map(|c| front.active_ancestor(&h, c)));
            let got = client.split(n, h.children(n).unwrap(), cuts);
            front.split(&h, n).unwrap();
            got.err()
        });
        let e = refused.expect("a building has a split that adds no triangle");
        assert!(e.to_string().contains("adds no triangle"), "{e}");
    }
}
