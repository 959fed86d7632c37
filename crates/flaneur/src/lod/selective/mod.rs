//! Truly selective refinement (Kim & Lee 2001, as Kim–Lee–Kobbelt 2004 §4 stream it):
//! a progressive mesh's splits as a **binary vertex hierarchy**, each node named
//! ⟨tree-id, node-id⟩ with heap indexing, and each split's two **fundamental cut
//! vertices**, leaves of the hierarchy. Any front of active nodes (a cut through every
//! tree) is a mesh: each triangle of the fully refined mesh with every corner moved to
//! its leaf's **active ancestor**, those whose corners meet dropped. A split whose cut
//! vertices' active ancestors differ may be made at any time, without forcing others:
//! that is what makes the refinement truly selective, and what lets a client that holds
//! only part of the hierarchy refine it (ActiveAncestor by right shifts of a node-id).
//!
//! Our progressive meshes are built from half-edge collapses (v_c onto v_p), KLK's from
//! full-edge ones (v_t and v_u onto a new v_s). A split of v_p is read as KLK's split of
//! the node standing for v_p into two children: the left one stands for v_p from then
//! on, the right one for v_c. Node-ids grow by one bit a level, and ours are as long as
//! a node is deep ([`HeapIndex`]).
//!
//! ```
//! use flaneur::lod::{ProgressiveMesh, VertexHierarchy};
//! let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
//! let h = VertexHierarchy::new(&pm)?;
//! let mut front = h.roots();
//! // The roots' front is the base mesh; splitting every node in order gives the original.
//! assert_eq!(front.triangles(&h).len(), pm.base.triangle_count());
//! for s in 0..pm.splits.len() {
//!     front.split(&h, h.split_node(s))?;
//! }
//! assert_eq!(front.triangles(&h).len(), flaneur::scene::bunny().triangle_count());
//! # Ok::<(), flaneur::Error>(())
//! ```

mod blocks;
mod client;
mod cut_mesh;
mod front;
mod leaf_mesh;
mod partial;
mod stream;
#[cfg(test)]
mod testing;

pub use blocks::{block_of, Block, BlockClient, BlockServer, SwitchDown};
pub use client::{CutVertexClient, SelectiveClient};
pub use cut_mesh::CutMesh;
pub use front::Front;
pub use leaf_mesh::LeafMesh;
pub use stream::{
    Placement, RefineInfo, SelectiveBase, SelectiveServer, SelectiveSource, VsplitPacket,
};

use super::pm::{ProgressiveMesh, SelectiveMesh, NO_TRIANGLE};
use smallvec::{smallvec, SmallVec};

use crate::error::{Error, Result};

/// A node's name: its tree (the base vertex it descends from) and its place in that
/// tree by heap indexing (the root 1, the children of n are 2n and 2n + 1), an integer
/// of as many bits as the node is deep (our hierarchies are not balanced as KLK §6.2's:
/// a flat region collapses into a deep chain).
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeName {
    /// The base vertex the tree grows from.
    pub tree: u32,
    /// The node's heap index in its tree.
    pub node: HeapIndex,
}

impl NodeName {
    /// The name of this node's ancestor `levels` up (itself at 0): a right shift.
    pub fn up(&self, levels: u32) -> NodeName {
        NodeName {
            tree: self.tree,
            node: self.node.shr(levels),
        }
    }

    /// How deep the node lies (a root at 0).
    pub fn depth(&self) -> u32 {
        self.node.bits() - 1
    }
}

/// A heap index of any size: 64-bit words, least significant first, the top word not
/// zero. Up to two words are held inline.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct HeapIndex(SmallVec<[u64; 2]>);

impl HeapIndex {
    /// A root's index, 1.
    pub fn root() -> HeapIndex {
        HeapIndex(smallvec![1])
    }

    /// The index of this node's child: 2n for the left, 2n + 1 for the right.
    pub fn child(&self, right: bool) -> HeapIndex {
        let mut words = SmallVec::with_capacity(self.0.len() + 1);
        let mut carry = right as u64;
        for &w in &self.0 {
            words.push((w << 1) | carry);
            carry = w >> 63;
        }
        if carry != 0 {
            words.push(carry);
        }
        HeapIndex(words)
    }

    /// The index `levels` up: a right shift.
    pub fn shr(&self, levels: u32) -> HeapIndex {
        let (words, bits) = ((levels / 64) as usize, levels % 64);
        let mut out: SmallVec<[u64; 2]> = (words..self.0.len())
            .map(|k| {
                let low = self.0[k] >> bits;
                let high = match (bits, self.0.get(k + 1)) {
                    (0, _) | (_, None) => 0,
                    (b, Some(&next)) => next << (64 - b),
                };
                low | high
            })
            .collect();
        while out.len() > 1 && out.last() == Some(&0) {
            out.pop();
        }
        if out.is_empty() || out[..] == [0] {
            return HeapIndex(smallvec![0]);
        }
        HeapIndex(out)
    }

    /// Whether the step from depth `level - 1` to depth `level` on the way down from the
    /// root goes to a right child (`level` from 1 to the node's depth).
    pub(crate) fn goes_right(&self, level: u32) -> bool {
        let k = self.bits() - 1 - level;
        (self.0[(k / 64) as usize] >> (k % 64)) & 1 == 1
    }

    /// Its bits, the leading 1 included.
    pub fn bits(&self) -> u32 {
        let top = *self.0.last().unwrap_or(&0);
        (self.0.len() as u32 - 1) * 64 + (64 - top.leading_zeros())
    }

    /// The index as 64-bit words, least significant first.
    pub fn words(&self) -> &[u64] {
        &self.0
    }

    /// The index of `words` (least significant first, as [`HeapIndex::words`] gives
    /// them); `None` for zero, which names no node.
    pub fn from_words(mut words: Vec<u64>) -> Option<HeapIndex> {
        while words.len() > 1 && words.last() == Some(&0) {
            words.pop();
        }
        (words.iter().any(|&w| w != 0)).then(|| HeapIndex(SmallVec::from_vec(words)))
    }
}

/// One node of the hierarchy.
#[derive(Clone, Debug, PartialEq)]
struct Node {
    /// The base vertex its tree grows from.
    tree: u32,
    /// Levels below its root.
    depth: u32,
    parent: Option<u32>,
    /// The left child (the split vertex from then on) and the right (the new one).
    children: Option<[u32; 2]>,
    /// The progressive mesh's vertex it stands for.
    vertex: u32,
}

/// A progressive mesh's splits as a binary vertex hierarchy with fundamental cut
/// vertices (Kim & Lee 2001).
#[derive(Clone, Debug)]
pub struct VertexHierarchy {
    nodes: Vec<Node>,
    /// Split `i`'s node.
    split_nodes: Vec<u32>,
    /// Split `i`'s fundamental cut vertices, left and right: leaf nodes (`None` where
    /// the split adds no such triangle).
    cuts: Vec<[Option<u32>; 2]>,
    /// The leaves of split `i`'s f_l and f_r, fully refined, below its left and its
    /// right child (`None` where the split adds no such triangle).
    child_leaves: Vec<[Option<[u32; 2]>; 2]>,
    /// The fully refined mesh's triangles as leaf nodes.
    leaf_triangles: Vec<[u32; 3]>,
    /// Split `i`'s run: the splits of one collapse of a position on a crease or seam,
    /// made and undone together (or the surface cracks along the crease).
    runs: Vec<std::ops::Range<u32>>,
    roots: usize,
}

impl VertexHierarchy {
    /// The hierarchy of `pm`'s splits. An `Err` when a split's vertex is not there when
    /// it comes (a progressive mesh out of order).
    pub fn new(pm: &ProgressiveMesh) -> Result<VertexHierarchy> {
        let base = pm.base.positions.len();
        let mut nodes: Vec<Node> = (0..base as u32)
            .map(|v| Node {
                tree: v,
                depth: 0,
                parent: None,
                children: None,
                vertex: v,
            })
            .collect();
        // Each vertex's node so far: the deepest that stands for it.
        let mut current: Vec<u32> = (0..base as u32).collect();
        current.resize(pm.vertex_count(), u32::MAX);
        let mut split_nodes = Vec::with_capacity(pm.splits.len());
        for (i, s) in pm.splits.iter().enumerate() {
            let v_c = pm.ids(i).v_c;
            let at = *current
                .get(s.v_p as usize)
                .filter(|&&n| n != u32::MAX)
                .ok_or_else(|| {
                    Error::Invalid(format!("split {i}: vertex {} is not there yet", s.v_p))
                })?;
            let (tree, depth) = (nodes[at as usize].tree, nodes[at as usize].depth + 1);
            let child = |vertex: u32| Node {
                tree,
                depth,
                parent: Some(at),
                children: None,
                vertex,
            };
            let (left, right) = (nodes.len() as u32, nodes.len() as u32 + 1);
            nodes.push(child(s.v_p));
            nodes.push(child(v_c));
            nodes[at as usize].children = Some([left, right]);
            current[s.v_p as usize] = left;
            current[v_c as usize] = right;
            split_nodes.push(at);
        }
        // The fully refined mesh, slot by slot, its corners as leaves.
        let mut full = SelectiveMesh::new(&pm.base, pm.splits.len())?;
        for (i, s) in pm.splits.iter().enumerate() {
            full.split(i, s)?;
        }
        let leaf_triangles: Vec<[u32; 3]> = full
            .slots()
            .iter()
            .filter(|t| **t != NO_TRIANGLE)
            .map(|t| t.map(|v| current[v as usize]))
            .collect();
        let mut runs: Vec<std::ops::Range<u32>> = Vec::with_capacity(pm.splits.len());
        for (i, s) in pm.splits.iter().enumerate() {
            let start = match runs.last() {
                Some(r) if s.joins_previous => r.start,
                _ => i as u32,
            };
            runs.push(start..i as u32 + 1);
        }
        // Every split of a run is told the run's end.
        for i in (0..runs.len()).rev() {
            if i + 1 < runs.len() && runs[i + 1].start == runs[i].start {
                runs[i].end = runs[i + 1].end;
            }
        }
        let mut h = VertexHierarchy {
            nodes,
            split_nodes,
            cuts: Vec::with_capacity(pm.splits.len()),
            child_leaves: Vec::with_capacity(pm.splits.len()),
            leaf_triangles: Vec::new(),
            runs,
            roots: base,
        };
        // A split's fundamental cut vertex: the corner of its triangle, fully refined,
        // that does not descend from the node it splits.
        for (i, _) in pm.splits.iter().enumerate() {
            let ids = pm.ids(i);
            let at = h.split_nodes[i];
            let cut = |slot: u32| {
                let t = full.slots()[slot as usize];
                (t != NO_TRIANGLE).then(|| {
                    t.map(|v| current[v as usize])
                        .into_iter()
                        .find(|&leaf| !h.descends(leaf, at))
                })
            };
            let (l, r) = (cut(ids.f_l).flatten(), cut(ids.f_r).flatten());
            h.cuts.push([l, r]);
            let [left, right] = h.nodes[at as usize].children.expect("a split's node");
            let below = |slot: u32| {
                let t = full.slots()[slot as usize];
                (t != NO_TRIANGLE).then(|| {
                    let leaves = t.map(|v| current[v as usize]);
                    let under = |child| leaves.into_iter().find(|&leaf| h.descends(leaf, child));
                    Some([under(left)?, under(right)?])
                })?
            };
            h.child_leaves.push([below(ids.f_l), below(ids.f_r)]);
        }
        h.leaf_triangles = leaf_triangles;
        Ok(h)
    }

    /// The number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether it has no nodes (a progressive mesh without vertices).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The node split `split` splits.
    pub fn split_node(&self, split: usize) -> u32 {
        self.split_nodes[split]
    }

    /// The nodes split together with `node` (itself among them): its split's run, on a
    /// crease or seam; just itself elsewhere. Empty for a leaf.
    pub fn run_nodes(&self, node: u32) -> Vec<u32> {
        match self.split_index(node) {
            Some(s) => self.runs[s]
                .clone()
                .map(|j| self.split_nodes[j as usize])
                .collect(),
            None => Vec::new(),
        }
    }

    /// Node `node`'s name: read off the path from its root.
    pub fn name(&self, node: u32) -> NodeName {
        let mut path = Vec::new();
        let mut n = node;
        while let Some(p) = self.nodes[n as usize].parent {
            path.push(self.children(p).is_some_and(|[_, r]| r == n));
            n = p;
        }
        let index = path
            .iter()
            .rev()
            .fold(HeapIndex::root(), |index, &right| index.child(right));
        NodeName {
            tree: self.nodes[node as usize].tree,
            node: index,
        }
    }

    /// The node `name` names, if the hierarchy has it: down from its tree's root, a
    /// child for each bit below the leading one.
    pub fn find(&self, name: &NodeName) -> Option<u32> {
        if name.tree as usize >= self.roots {
            return None;
        }
        let mut n = name.tree;
        for level in 1..=name.depth() {
            let [left, right] = self.children(n)?;
            n = if name.node.goes_right(level) {
                right
            } else {
                left
            };
        }
        Some(n)
    }

    /// The nodes split together with `node` when its split is one of a run of more
    /// than one: the node of the run's first split. `None` for a split alone, or a
    /// leaf.
    pub fn run_leader(&self, node: u32) -> Option<u32> {
        let run = self.runs[self.split_index(node)?].clone();
        (run.len() > 1).then(|| self.split_nodes[run.start as usize])
    }

    /// The leaves of the two triangles `node`'s split adds (f_l, then f_r), fully
    /// refined, that lie below its left and its right child: with the cut vertex, each
    /// triangle's corners, in the order (left, right, left cut) for f_l and (left,
    /// right cut, right) for f_r. `None` for a leaf; `None` for a triangle the split
    /// does not add.
    pub fn child_leaves(&self, node: u32) -> Option<[Option<[u32; 2]>; 2]> {
        Some(self.child_leaves[self.split_index(node)?])
    }

    /// Whether some split adds no triangle (a wedge of a crease or seam run), so that
    /// no cut vertex places it and a client must place triangles by their leaves.
    pub fn has_wedge_splits(&self) -> bool {
        self.cuts.iter().any(|c| c == &[None, None])
    }

    /// Node `node`'s children, if it splits.
    pub fn children(&self, node: u32) -> Option<[u32; 2]> {
        self.nodes[node as usize].children
    }

    /// Node `node`'s parent (`None` for a root).
    pub fn parent(&self, node: u32) -> Option<u32> {
        self.nodes[node as usize].parent
    }

    /// The progressive mesh's vertex node `node` stands for.
    pub fn vertex(&self, node: u32) -> u32 {
        self.nodes[node as usize].vertex
    }

    /// The fundamental cut vertices (leaves) of the split of node `node`.
    pub fn cut_vertices(&self, node: u32) -> Option<[Option<u32>; 2]> {
        let split = self.split_index(node)?;
        Some(self.cuts[split])
    }

    /// The deepest node of the hierarchy, levels below its root.
    pub fn depth(&self) -> u32 {
        self.nodes.iter().map(|n| n.depth).max().unwrap_or(0)
    }

    /// The front of the roots: the base mesh.
    pub fn roots(&self) -> Front {
        let mut active = vec![false; self.nodes.len()];
        active[..self.roots].fill(true);
        Front { active }
    }

    /// Whether `node` is `ancestor` or lies below it.
    pub(crate) fn descends(&self, node: u32, ancestor: u32) -> bool {
        let mut n = Some(node);
        while let Some(k) = n {
            if k == ancestor {
                return true;
            }
            n = self.nodes[k as usize].parent;
        }
        false
    }

    /// The split that splits `node`, if any: the nodes' order is the splits'.
    pub(crate) fn split_index(&self, node: u32) -> Option<usize> {
        let [left, _] = self.nodes[node as usize].children?;
        Some((left as usize - self.roots) / 2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn pm_of(triangles: usize) -> ProgressiveMesh {
        ProgressiveMesh::build(&crate::lod::bumpy_torus(triangles)).unwrap()
    }

    /// The prefix mesh of `k` splits, its corners as the progressive mesh's vertices.
    fn prefix(pm: &ProgressiveMesh, k: usize) -> Vec<[u32; 3]> {
        let mut m = SelectiveMesh::new(&pm.base, pm.splits.len()).unwrap();
        for (i, s) in pm.splits.iter().enumerate().take(k) {
            m.split(i, s).unwrap();
        }
        m.slots()
            .iter()
            .copied()
            .filter(|t| *t != NO_TRIANGLE)
            .collect()
    }

    #[test]
    fn splitting_in_order_gives_each_prefix_of_the_progressive_mesh() {
        let pm = pm_of(2000);
        let h = VertexHierarchy::new(&pm).unwrap();
        let mut front = h.roots();
        for k in 0..=pm.splits.len() {
            if k % 97 == 0 || k == pm.splits.len() {
                let mut ours: Vec<[u32; 3]> = front
                    .triangles(&h)
                    .iter()
                    .map(|t| t.map(|n| h.vertex(n)))
                    .collect();
                let mut theirs = prefix(&pm, k);
                ours.sort_unstable();
                theirs.sort_unstable();
                assert_eq!(ours, theirs, "after {k} splits");
            }
            if k < pm.splits.len() {
                // In order, each split is legal as it stands.
                assert!(front.can_split(&h, h.split_node(k)), "split {k}");
                assert_eq!(front.split(&h, h.split_node(k)).unwrap(), [h.split_node(k)]);
            }
        }
    }

    #[test]
    fn names_are_heap_indices_and_ancestors_right_shifts() {
        let pm = pm_of(800);
        let h = VertexHierarchy::new(&pm).unwrap();
        for n in 0..h.len() as u32 {
            if let Some(p) = h.parent(n) {
                assert_eq!(h.name(n).up(1), h.name(p));
                assert_eq!(h.name(n).depth(), h.name(p).depth() + 1);
            } else {
                assert_eq!(h.name(n).node, HeapIndex::root());
            }
        }
        // Deep chains too: a flat grid collapses into one.
        let grid = ProgressiveMesh::build(&crate::lod::fixtures::grid(24)).unwrap();
        let h = VertexHierarchy::new(&grid).unwrap();
        assert!(h.depth() > 64, "{}", h.depth());
        let deepest = (0..h.len() as u32)
            .max_by_key(|&n| h.name(n).depth())
            .unwrap();
        let name = h.name(deepest);
        assert_eq!(name.depth(), h.depth());
        let mut up = deepest;
        for levels in 1..=name.depth() {
            up = h.parent(up).unwrap();
            assert_eq!(name.up(levels), h.name(up), "{levels} up");
        }
    }

    /// Random selective refinement and coarsening: every front's mesh stays an oriented
    /// manifold, and refining everything gives back the original.
    #[test]
    fn any_order_of_legal_splits_and_collapses_keeps_a_manifold() {
        let pm = pm_of(3000);
        let h = VertexHierarchy::new(&pm).unwrap();
        let mut front = h.roots();
        wander(&h, &mut front, 7, 4000, 50, |front, step| {
            assert!(front.is_manifold(&h), "step {step}");
        });
        for s in 0..pm.splits.len() {
            let node = h.split_node(s);
            if front.is_active(node) {
                front.split(&h, node).unwrap();
            }
        }
        let mut ours: Vec<[u32; 3]> = front
            .triangles(&h)
            .iter()
            .map(|t| t.map(|n| h.vertex(n)))
            .collect();
        let mut theirs = prefix(&pm, pm.splits.len());
        ours.sort_unstable();
        theirs.sort_unstable();
        assert_eq!(ours, theirs);
    }

    /// Moves `front` at random for `steps` steps (seeded by `seed`): seven in ten try to
    /// split a node, the rest to collapse one where that is legal; `check` looks at the
    /// front every `every` steps.
    fn wander(
        h: &VertexHierarchy,
        front: &mut Front,
        seed: u64,
        steps: usize,
        every: usize,
        mut check: impl FnMut(&Front, usize),
    ) {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        for step in 0..steps {
            let node = rng.gen_range(0..h.len() as u32);
            if rng.gen_bool(0.7) {
                if front.is_active(node) && h.children(node).is_some() {
                    front.split(h, node).unwrap();
                }
            } else if front.can_collapse(h, node) {
                front.collapse(h, node).unwrap();
            }
            if step % every == 0 {
                check(front, step);
            }
        }
    }

    /// Every run is split whole or not at all.
    fn runs_whole(h: &VertexHierarchy, front: &Front) -> bool {
        (0..h.len() as u32).all(|n| {
            let split = |k: u32| !front.is_active(k) && front.active_above(h, k).is_none();
            let run = h.run_nodes(n);
            run.iter().all(|&k| split(k)) || run.iter().all(|&k| !split(k))
        })
    }

    /// The leaf triangles a split adds are (left, right, left cut) and (left, right
    /// cut, right), turned: what a client that places triangles by their leaves builds
    /// them from.
    #[test]
    fn a_splits_triangles_are_its_child_leaves_and_cut_vertices_in_order() {
        for mesh in [
            crate::lod::fixtures::building(),
            crate::lod::bumpy_torus(800),
        ] {
            let pm = ProgressiveMesh::build(&mesh).unwrap();
            let h = VertexHierarchy::new(&pm).unwrap();
            let turned = |t: [u32; 3]| {
                let k = (0..3).min_by_key(|&k| t[k]).unwrap();
                let mut t = t;
                t.rotate_left(k);
                t
            };
            let all: std::collections::HashSet<[u32; 3]> =
                h.leaf_triangles.iter().map(|&t| turned(t)).collect();
            let mut found = 0;
            for s in 0..pm.splits.len() {
                let n = h.split_node(s);
                let [cl, cr] = h.cut_vertices(n).unwrap();
                let [ll, lr] = h.child_leaves(n).unwrap();
                assert_eq!(cl.is_some(), ll.is_some(), "split {s}");
                assert_eq!(cr.is_some(), lr.is_some(), "split {s}");
                if let (Some(c), Some([a, b])) = (cl, ll) {
                    assert!(all.contains(&turned([a, b, c])), "split {s}'s f_l");
                    found += 1;
                }
                if let (Some(c), Some([a, b])) = (cr, lr) {
                    assert!(all.contains(&turned([a, c, b])), "split {s}'s f_r");
                    found += 1;
                }
            }
            assert!(
                found > pm.splits.len() / 2,
                "{found} of {} splits",
                pm.splits.len()
            );
        }
    }

    #[test]
    fn on_creases_and_seams_a_run_splits_and_collapses_whole() {
        let building = crate::lod::fixtures::building();
        let pm = ProgressiveMesh::build(&building).unwrap();
        assert!(
            pm.splits.iter().any(|s| s.joins_previous),
            "a building has runs"
        );
        let h = VertexHierarchy::new(&pm).unwrap();
        let mut front = h.roots();
        wander(&h, &mut front, 3, 3000, 25, |front, step| {
            assert!(front.is_manifold(&h), "step {step}");
            assert!(runs_whole(&h, front), "step {step}");
        });
    }
}
