//! A front of the vertex hierarchy: which nodes are active, and the mesh that makes
//! (each fully refined triangle at its corners' active ancestors); split and collapsed
//! as the partial order allows.

use super::VertexHierarchy;
use crate::error::{Error, Result};

/// A front of the hierarchy: which nodes are active (a cut through every tree).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Front {
    pub(super) active: Vec<bool>,
}

impl Front {
    /// The front whose active nodes are `nodes`, as a client that resumes names them
    /// (KLK §5: its leaf ids). An `Err` naming a node unless they cut every tree
    /// exactly once: a node out of range or named twice, one below another, a leaf of
    /// the hierarchy with none above it.
    pub fn from_active(h: &VertexHierarchy, nodes: &[u32]) -> Result<Front> {
        let mut active = vec![false; h.len()];
        for &n in nodes {
            match active.get_mut(n as usize) {
                None => return Err(Error::Invalid(format!("no node {n} in the hierarchy"))),
                Some(true) => return Err(Error::Invalid(format!("node {n} named twice"))),
                Some(a) => *a = true,
            }
        }
        let front = Front { active };
        if let Some(&below) = nodes.iter().find(|&&n| front.active_above(h, n).is_some()) {
            return Err(Error::Invalid(format!(
                "node {:?} lies below another named node",
                h.name(below)
            )));
        }
        let mut stack: Vec<u32> = (0..h.roots as u32).collect();
        while let Some(n) = stack.pop() {
            if front.is_active(n) {
                continue;
            }
            let Some([l, r]) = h.children(n) else {
                return Err(Error::Invalid(format!(
                    "leaf {:?} has no named node above it",
                    h.name(n)
                )));
            };
            stack.extend([l, r]);
        }
        Ok(front)
    }

    /// Whether `node` is on the front.
    pub fn is_active(&self, node: u32) -> bool {
        self.active[node as usize]
    }

    /// The active node `leaf` descends from.
    pub fn active_ancestor(&self, h: &VertexHierarchy, leaf: u32) -> u32 {
        let mut n = leaf;
        while !self.active[n as usize] {
            n = h.nodes[n as usize]
                .parent
                .expect("a front cuts every tree, so a leaf has an active ancestor");
        }
        n
    }

    /// Whether `node`'s split keeps the mesh a manifold now: its cut vertices' active
    /// ancestors differ (KLK §5.3's partial order). A node without a split, or off the
    /// front, cannot split.
    /// (A split of a crease's run asks this of each of its nodes.)
    pub fn can_split(&self, h: &VertexHierarchy, node: u32) -> bool {
        match h.cut_vertices(node) {
            Some([Some(l), Some(r)]) if self.is_active(node) => {
                self.active_ancestor(h, l) != self.active_ancestor(h, r)
            }
            Some(_) => self.is_active(node),
            None => false,
        }
    }

    /// Splits `node` into its children with the rest of its run, first splitting what
    /// the partial order asks for (KLK's SelStreamVSplit): the node both cut vertices'
    /// active ancestor is, until they differ, and the ancestors of a run's nodes that
    /// are not on the front yet. The nodes split, in order.
    pub fn split(&mut self, h: &VertexHierarchy, node: u32) -> Result<Vec<u32>> {
        if h.children(node).is_none() {
            return Err(Error::Invalid(format!(
                "node {node} is a leaf: it does not split"
            )));
        }
        if !self.is_active(node) {
            return Err(Error::Invalid(format!("node {node} is not on the front")));
        }
        let mut done = Vec::new();
        self.split_run(h, node, &mut done)?;
        Ok(done)
    }

    /// Splits every node of `node`'s run that is not split yet.
    fn split_run(&mut self, h: &VertexHierarchy, node: u32, done: &mut Vec<u32>) -> Result<()> {
        for n in h.run_nodes(node) {
            self.make_split(h, n, done)?;
        }
        Ok(())
    }

    /// Splits `node`, bringing it to the front first; nothing if it is split already.
    fn make_split(&mut self, h: &VertexHierarchy, node: u32, done: &mut Vec<u32>) -> Result<()> {
        loop {
            if self.is_active(node) {
                break;
            }
            match self.active_above(h, node) {
                // Above the front: split already.
                None => return Ok(()),
                Some(a) => self.split_run(h, a, done)?,
            }
        }
        if let Some([Some(l), Some(r)]) = h.cut_vertices(node) {
            loop {
                let a = self.active_ancestor(h, l);
                if a != self.active_ancestor(h, r) {
                    break;
                }
                if h.children(a).is_none() {
                    return Err(Error::Invalid(format!(
                        "node {node}'s cut vertices meet in leaf {a}"
                    )));
                }
                self.split_run(h, a, done)?;
            }
        }
        let [left, right] = h.children(node).expect("a split's node has children");
        self.active[node as usize] = false;
        self.active[left as usize] = true;
        self.active[right as usize] = true;
        done.push(node);
        Ok(())
    }

    /// The active node strictly above `node`, if the front runs below it.
    pub(super) fn active_above(&self, h: &VertexHierarchy, node: u32) -> Option<u32> {
        let mut n = h.parent(node);
        while let Some(k) = n {
            if self.is_active(k) {
                return Some(k);
            }
            n = h.parent(k);
        }
        None
    }

    /// Whether the children of `node` may be collapsed back into it with the rest of
    /// its run: every child of the run active, and no active split whose cut vertices
    /// would then meet in one node (the mesh stays a manifold).
    pub fn can_collapse(&self, h: &VertexHierarchy, node: u32) -> bool {
        let run = h.run_nodes(node);
        let all_children_active = run.iter().all(|&n| {
            h.children(n)
                .is_some_and(|[l, r]| self.is_active(l) && self.is_active(r))
        });
        if run.is_empty() || !all_children_active {
            return false;
        }
        let mut after = self.clone();
        after.collapse_unchecked(h, &run);
        after.is_manifold(h)
    }

    /// Collapses the children of `node` (and of its run) back into it. An `Err`, and
    /// no change, unless [`Front::can_collapse`].
    pub fn collapse(&mut self, h: &VertexHierarchy, node: u32) -> Result<()> {
        if !self.can_collapse(h, node) {
            return Err(Error::Invalid(format!(
                "node {node}'s children cannot be collapsed here"
            )));
        }
        self.collapse_unchecked(h, &h.run_nodes(node));
        Ok(())
    }

    /// Makes `node` split (its children active in its place) or not, nothing else.
    pub(crate) fn set_split(&mut self, h: &VertexHierarchy, node: u32, split: bool) {
        let [left, right] = h.children(node).expect("a split node");
        self.active[node as usize] = !split;
        self.active[left as usize] = split;
        self.active[right as usize] = split;
    }

    fn collapse_unchecked(&mut self, h: &VertexHierarchy, run: &[u32]) {
        for &n in run {
            let [left, right] = h.children(n).expect("a run's node has children");
            self.active[left as usize] = false;
            self.active[right as usize] = false;
            self.active[n as usize] = true;
        }
    }

    /// The front's mesh: every fully refined triangle with its corners at their active
    /// ancestors, those whose corners meet left out, as active nodes, in slot order.
    pub fn triangles(&self, h: &VertexHierarchy) -> Vec<[u32; 3]> {
        h.leaf_triangles
            .iter()
            .map(|t| t.map(|leaf| self.active_ancestor(h, leaf)))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect()
    }

    /// Whether the front's mesh is an oriented 2-manifold where the original is: no
    /// directed edge twice, no triangle twice.
    pub fn is_manifold(&self, h: &VertexHierarchy) -> bool {
        let mut edges = std::collections::HashSet::new();
        self.triangles(h)
            .iter()
            .all(|t| (0..3).all(|k| edges.insert((t[k], t[(k + 1) % 3]))))
    }
}
