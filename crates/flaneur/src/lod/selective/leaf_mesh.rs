//! A client's selectively refined mesh kept as the fully refined triangles it was sent,
//! each corner at its leaf's active ancestor: the front's mesh as the hierarchy defines
//! it, for meshes whose wedge splits add no triangle (crease and seam runs), which no
//! cut vertex places (ours; Kim–Lee–Kobbelt's scheme assumes manifold vertex splits).

use std::collections::HashMap;

use super::NodeName;
use crate::error::{Error, Result};

/// Fully refined triangles, each corner's leaf named and held at the active node it
/// descends from; those whose corners meet are kept, and are not drawn, until a split
/// parts them. The directed edges of the others are counted, so that a collapse can be
/// checked to keep the mesh a manifold without looking past the triangles it moves.
///
/// ```
/// use flaneur::lod::{LeafMesh, NodeName, HeapIndex};
/// let leaf = |tree, right: &[bool]| NodeName {
///     tree,
///     node: right.iter().fold(HeapIndex::root(), |n, &r| n.child(r)),
/// };
/// // Node 0 (root of tree 0) splits into nodes 3 and 4; a triangle of its two children
/// // and the roots of trees 1 and 2 appears when it does.
/// let mut mesh = LeafMesh::default();
/// mesh.add([leaf(0, &[false]), leaf(0, &[true]), leaf(1, &[])], [0, 0, 1]);
/// mesh.add([leaf(0, &[false]), leaf(1, &[]), leaf(2, &[])], [0, 1, 2]);
/// assert_eq!(mesh.triangles().len(), 1);
/// mesh.split(0, 0, [3, 4])?;
/// assert_eq!(mesh.triangles().len(), 2);
/// assert!(mesh.collapse_keeps_manifold(&[(0, [3, 4])]));
/// mesh.collapse(&[(0, [3, 4])]);
/// assert_eq!(mesh.triangles().len(), 1);
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct LeafMesh {
    /// Each triangle's corners' leaves.
    leaves: Vec<[NodeName; 3]>,
    /// Each triangle's corners as active nodes.
    corners: Vec<[u32; 3]>,
    /// The corners held at each active node: (triangle, corner).
    at: HashMap<u32, Vec<(u32, u8)>>,
    /// The directed edges of the triangles whose corners do not meet, counted.
    edges: HashMap<(u32, u32), u32>,
    /// How many directed edges are there more than once, over the first.
    repeated: usize,
    /// Slots of removed triangles, for the next added.
    free: Vec<u32>,
}

/// A removed triangle's corners: they meet, so it is neither drawn nor counted.
const REMOVED: [u32; 3] = [u32::MAX; 3];

fn meets(t: &[u32; 3]) -> bool {
    t[0] == t[1] || t[1] == t[2] || t[0] == t[2]
}

fn directed(t: &[u32; 3]) -> [(u32, u32); 3] {
    [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]
}

impl LeafMesh {
    /// Adds a triangle of `leaves`, each held at the active node in `corners`. Its
    /// number, until it is removed.
    pub fn add(&mut self, leaves: [NodeName; 3], corners: [u32; 3]) -> u32 {
        let t = match self.free.pop() {
            Some(t) => {
                self.leaves[t as usize] = leaves;
                self.corners[t as usize] = corners;
                t
            }
            None => {
                self.leaves.push(leaves);
                self.corners.push(corners);
                self.corners.len() as u32 - 1
            }
        };
        for (k, &c) in corners.iter().enumerate() {
            self.at.entry(c).or_default().push((t, k as u8));
        }
        self.count(&corners, true);
        t
    }

    /// Removes triangle `t`, which must not be drawn: its corners meet (a client drops
    /// a split its mesh does not use, and with it the triangles the split's packet
    /// brought). An `Err`, and no change, when it is drawn or was removed.
    pub fn remove(&mut self, t: u32) -> Result<()> {
        let corners = *self
            .corners
            .get(t as usize)
            .filter(|c| **c != REMOVED && meets(c))
            .ok_or_else(|| {
                Error::Invalid(format!(
                    "triangle {t} is drawn or gone: it cannot be removed"
                ))
            })?;
        for c in corners {
            if let Some(held) = self.at.get_mut(&c) {
                held.retain(|&(u, _)| u != t);
                if held.is_empty() {
                    self.at.remove(&c);
                }
            }
        }
        self.corners[t as usize] = REMOVED;
        self.free.push(t);
        Ok(())
    }

    /// Counts `t`'s directed edges in or out, if its corners do not meet.
    fn count(&mut self, t: &[u32; 3], add: bool) {
        if meets(t) {
            return;
        }
        for e in directed(t) {
            let c = self.edges.entry(e).or_default();
            if add {
                self.repeated += usize::from(*c > 0);
                *c += 1;
            } else {
                *c -= 1;
                self.repeated -= usize::from(*c > 0);
                if *c == 0 {
                    self.edges.remove(&e);
                }
            }
        }
    }

    /// Gives triangle `t` the corners `to`.
    fn recorner(&mut self, t: u32, to: [u32; 3]) {
        let from = self.corners[t as usize];
        self.count(&from, false);
        self.corners[t as usize] = to;
        self.count(&to, true);
    }

    /// Splits active node `node`, `depth` levels below its root, into `[left, right]`:
    /// each corner held there moves to the child its leaf descends from. An `Err`, and
    /// no change, when a corner's leaf does not lie below the node.
    pub fn split(&mut self, node: u32, depth: u32, [left, right]: [u32; 2]) -> Result<()> {
        let held = self.at.get(&node).cloned().unwrap_or_default();
        if let Some(&(t, k)) = held
            .iter()
            .find(|&&(t, k)| self.leaves[t as usize][k as usize].depth() <= depth)
        {
            return Err(Error::Invalid(format!(
                "splitting node {node}: the leaf {:?} of a corner held there lies no \
                 deeper than it",
                self.leaves[t as usize][k as usize]
            )));
        }
        self.at.remove(&node);
        for (t, k) in held {
            let leaf = &self.leaves[t as usize][k as usize];
            let child = if leaf.node.goes_right(depth + 1) {
                right
            } else {
                left
            };
            let mut to = self.corners[t as usize];
            to[k as usize] = child;
            self.recorner(t, to);
            self.at.entry(child).or_default().push((t, k));
        }
        Ok(())
    }

    /// The triangles a collapse of each `(node, [left, right])` of `run` moves, with
    /// their corners after it.
    fn moved(&self, run: &[(u32, [u32; 2])]) -> Vec<(u32, [u32; 3])> {
        let into: HashMap<u32, u32> = run
            .iter()
            .flat_map(|&(node, [l, r])| [(l, node), (r, node)])
            .collect();
        let mut triangles: Vec<u32> = into
            .keys()
            .flat_map(|c| self.at.get(c).into_iter().flatten().map(|&(t, _)| t))
            .collect();
        triangles.sort_unstable();
        triangles.dedup();
        triangles
            .into_iter()
            .map(|t| {
                let to = self.corners[t as usize].map(|c| *into.get(&c).unwrap_or(&c));
                (t, to)
            })
            .collect()
    }

    /// Whether collapsing each `(node, [left, right])` of `run` leaves no directed edge
    /// twice: only the edges of the triangles it moves change.
    pub fn collapse_keeps_manifold(&self, run: &[(u32, [u32; 2])]) -> bool {
        let mut change: HashMap<(u32, u32), i64> = HashMap::new();
        for (t, to) in self.moved(run) {
            let from = self.corners[t as usize];
            for (tri, by) in [(from, -1), (to, 1)] {
                if !meets(&tri) {
                    for e in directed(&tri) {
                        *change.entry(e).or_default() += by;
                    }
                }
            }
        }
        let mut repeated = self.repeated as i64;
        for (e, by) in change {
            let before = i64::from(self.edges.get(&e).copied().unwrap_or(0));
            repeated += (before + by - 1).max(0) - (before - 1).max(0);
        }
        repeated == 0
    }

    /// Collapses each `(node, [left, right])` of `run`: the children's corners go back
    /// to their node.
    pub fn collapse(&mut self, run: &[(u32, [u32; 2])]) {
        for (t, to) in self.moved(run) {
            self.recorner(t, to);
        }
        for &(node, [l, r]) in run {
            let mut held = self.at.remove(&l).unwrap_or_default();
            held.extend(self.at.remove(&r).unwrap_or_default());
            self.at.entry(node).or_default().extend(held);
        }
    }

    /// The triangles whose corners do not meet, corners as active nodes.
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        self.corners.iter().filter(|t| !meets(t)).copied().collect()
    }
}
