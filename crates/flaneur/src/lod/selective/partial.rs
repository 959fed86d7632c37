//! What a client of truly selective streaming was sent: its partial hierarchy of nodes
//! named ⟨tree-id, node-id⟩ with its active front, and its mesh over that front (cut or
//! leaf placement). The clients' own logic, what to split or collapse for a view, is
//! `client`'s.

use std::collections::HashMap;

use super::stream::{RefineInfo, SelectiveBase, VsplitPacket};
use super::{CutMesh, HeapIndex, LeafMesh, NodeName};
use crate::error::{Error, Result};
use crate::scene::Mesh;

/// One node of a client's partial hierarchy.
#[derive(Clone, Debug)]
pub(super) struct ClientNode {
    pub(super) name: NodeName,
    pub(super) parent: Option<u32>,
    pub(super) children: Option<[u32; 2]>,
    pub(super) cuts: [Option<NodeName>; 2],
    /// The first node of its split's run, if the run has more than one.
    pub(super) run: Option<NodeName>,
    /// Its vertex.
    pub(super) position: [f32; 3],
    pub(super) normal: [f32; 3],
    pub(super) info: Option<RefineInfo>,
}

impl ClientNode {
    /// A node as it first comes: not split yet.
    pub(super) fn unsplit(
        name: NodeName,
        parent: Option<u32>,
        (position, normal): ([f32; 3], [f32; 3]),
        info: Option<RefineInfo>,
    ) -> ClientNode {
        ClientNode {
            name,
            parent,
            children: None,
            cuts: [None, None],
            run: None,
            position,
            normal,
            info,
        }
    }
}

/// The part of a hierarchy a client was sent, and which of its nodes are active.
#[derive(Clone, Debug)]
pub(super) struct Partial {
    pub(super) nodes: Vec<ClientNode>,
    pub(super) by_name: HashMap<NodeName, u32>,
    pub(super) active: Vec<bool>,
    /// The nodes of each run, by the name of its first, in the order they were sent.
    pub(super) runs: HashMap<NodeName, Vec<u32>>,
    /// Slots of nodes dropped with their split, for the next to come.
    pub(super) free: Vec<u32>,
    /// Whether the front runs below each node: its split is made and not undone.
    pub(super) made: Vec<bool>,
}

impl Partial {
    /// The roots, each with its vertex and what `qrefine` reads of it.
    pub(super) fn new(roots: Vec<([f32; 3], [f32; 3], Option<RefineInfo>)>) -> Partial {
        let nodes: Vec<ClientNode> = roots
            .into_iter()
            .enumerate()
            .map(|(tree, (position, normal, info))| {
                let name = NodeName {
                    tree: tree as u32,
                    node: HeapIndex::root(),
                };
                ClientNode::unsplit(name, None, (position, normal), info)
            })
            .collect();
        Partial {
            by_name: nodes
                .iter()
                .enumerate()
                .map(|(k, n)| (n.name.clone(), k as u32))
                .collect(),
            active: vec![true; nodes.len()],
            made: vec![false; nodes.len()],
            nodes,
            runs: HashMap::new(),
            free: Vec::new(),
        }
    }

    pub(super) fn id(&self, name: &NodeName) -> Result<u32> {
        self.by_name.get(name).copied().ok_or_else(|| {
            Error::Invalid(format!(
                "a split names node {name:?}, which the client was not sent"
            ))
        })
    }

    /// Takes packet `p`: the node's children join the hierarchy, inactive. The node.
    pub(super) fn receive(&mut self, p: &VsplitPacket) -> Result<u32> {
        let k = self.id(&p.node)?;
        if self.nodes[k as usize].children.is_some() {
            return Err(Error::Invalid(format!("node {:?} was sent twice", p.node)));
        }
        let parent = &self.nodes[k as usize];
        let (position, normal) = (parent.position, parent.normal);
        let mut child = |right: bool, vertex, info| {
            let name = NodeName {
                tree: p.node.tree,
                node: p.node.node.child(right),
            };
            let node = ClientNode::unsplit(name.clone(), Some(k), vertex, info);
            let id = match self.free.pop() {
                Some(id) => {
                    self.nodes[id as usize] = node;
                    self.made[id as usize] = false;
                    id
                }
                None => {
                    self.nodes.push(node);
                    self.active.push(false);
                    self.made.push(false);
                    self.nodes.len() as u32 - 1
                }
            };
            self.by_name.insert(name, id);
            id
        };
        // The left child keeps the node's vertex; the right is the new one.
        let children = [
            child(false, (position, normal), p.children[0]),
            child(true, (p.position, p.normal), p.children[1]),
        ];
        let node = &mut self.nodes[k as usize];
        node.children = Some(children);
        node.cuts = p.cuts.clone();
        node.run = p.run.clone();
        if let Some(leader) = &p.run {
            self.runs.entry(leader.clone()).or_default().push(k);
        }
        Ok(k)
    }

    /// Moves the front from `node` to its `children`.
    pub(super) fn split(&mut self, node: u32, children: [u32; 2]) {
        self.active[node as usize] = false;
        self.made[node as usize] = true;
        self.active[children[0] as usize] = true;
        self.active[children[1] as usize] = true;
    }

    /// Moves the front from `children` back to `node`.
    pub(super) fn unsplit(&mut self, node: u32, children: [u32; 2]) {
        self.active[node as usize] = true;
        self.made[node as usize] = false;
        self.active[children[0] as usize] = false;
        self.active[children[1] as usize] = false;
    }

    /// The active node `name` descends from: `name` shifted right until it names a
    /// node on the front (KLK §4).
    pub(super) fn active_ancestor(&self, name: &NodeName) -> Result<u32> {
        for up in 0..=name.depth() {
            if let Some(&k) = self.by_name.get(&name.up(up)) {
                if self.active[k as usize] {
                    return Ok(k);
                }
            }
        }
        Err(Error::Invalid(format!(
            "no active ancestor of node {name:?}"
        )))
    }

    /// The active node strictly above `node`, if the front runs below it.
    pub(super) fn active_above(&self, node: u32) -> Option<u32> {
        let mut n = self.nodes[node as usize].parent;
        while let Some(k) = n {
            if self.active[k as usize] {
                return Some(k);
            }
            n = self.nodes[k as usize].parent;
        }
        None
    }

    /// The nodes split with `node`: its run's, or itself.
    pub(super) fn run_nodes(&self, node: u32) -> Vec<u32> {
        match &self.nodes[node as usize].run {
            Some(leader) => self.runs.get(leader).cloned().unwrap_or_default(),
            None => vec![node],
        }
    }

    pub(super) fn children(&self, node: u32) -> Result<[u32; 2]> {
        self.nodes[node as usize].children.ok_or_else(|| {
            Error::Invalid(format!(
                "the partial order asks for a split of node {:?}, which was not sent",
                self.nodes[node as usize].name
            ))
        })
    }

    /// The names of the nodes whose split was not sent.
    pub(super) fn leaves(&self) -> Vec<NodeName> {
        self.nodes
            .iter()
            .enumerate()
            .filter(|&(k, n)| n.children.is_none() && self.holds(k as u32))
            .map(|(_, n)| n.name.clone())
            .collect()
    }

    /// Whether slot `k` holds a node (it was not dropped).
    pub(super) fn holds(&self, k: u32) -> bool {
        self.by_name.get(&self.nodes[k as usize].name) == Some(&k)
    }

    /// Drops the splits of `nodes` (a block's, parents before children): their
    /// children leave the hierarchy. Each must be held split, its children inactive and
    /// not split, but by a node of `nodes`, and its run within `nodes`; else an `Err`
    /// and nothing dropped.
    pub(super) fn drop_splits(&mut self, nodes: &[NodeName]) -> Result<Vec<u32>> {
        let ids = self.droppable(nodes)?;
        for &k in ids.iter().rev() {
            let node = &mut self.nodes[k as usize];
            let children = node.children.take().expect("checked droppable");
            node.cuts = [None, None];
            if let Some(leader) = node.run.take() {
                self.runs.remove(&leader);
            }
            for c in children {
                self.by_name.remove(&self.nodes[c as usize].name);
                self.free.push(c);
            }
        }
        Ok(ids)
    }

    /// The slots of `nodes` if their splits may be dropped ([`Partial::drop_splits`]).
    pub(super) fn droppable(&self, nodes: &[NodeName]) -> Result<Vec<u32>> {
        let ids = nodes
            .iter()
            .map(|n| self.id(n))
            .collect::<Result<Vec<u32>>>()?;
        let within: std::collections::HashSet<u32> = ids.iter().copied().collect();
        for &k in &ids {
            let node = &self.nodes[k as usize];
            let children = node.children.ok_or_else(|| {
                Error::Invalid(format!("dropping node {:?}'s split, not held", node.name))
            })?;
            let run_out =
                self.made[k as usize] || self.run_nodes(k).iter().any(|r| !within.contains(r));
            let busy = children.iter().any(|&c| {
                self.active[c as usize]
                    || (self.nodes[c as usize].children.is_some() && !within.contains(&c))
            });
            if run_out || busy {
                return Err(Error::Invalid(format!(
                    "dropping node {:?}'s split, which its mesh or another split uses",
                    node.name
                )));
            }
        }
        Ok(ids)
    }

    pub(super) fn named(&self, triangles: Vec<[u32; 3]>) -> Vec<[NodeName; 3]> {
        triangles
            .iter()
            .map(|t| t.map(|k| self.nodes[k as usize].name.clone()))
            .collect()
    }

    /// `triangles` as a mesh to draw: each corner node's vertex, once.
    pub(super) fn mesh(&self, triangles: Vec<[u32; 3]>) -> Mesh {
        let mut index = HashMap::new();
        let mut mesh = Mesh::default();
        for t in triangles {
            for k in t {
                let v = *index.entry(k).or_insert_with(|| {
                    let node = &self.nodes[k as usize];
                    mesh.positions.push(node.position);
                    mesh.normals.push(node.normal);
                    mesh.positions.len() as u32 - 1
                });
                mesh.indices.push(v);
            }
        }
        mesh
    }
}

/// The nodes `find` finds for each cut vertex named.
pub(super) fn each(
    cuts: &[Option<NodeName>; 2],
    find: impl Fn(&NodeName) -> Result<u32>,
) -> Result<[Option<u32>; 2]> {
    Ok([
        cuts[0].as_ref().map(&find).transpose()?,
        cuts[1].as_ref().map(&find).transpose()?,
    ])
}

/// A client's mesh, by its source's placement.
#[derive(Clone, Debug)]
pub(super) enum ClientMesh {
    Cut(CutMesh),
    Leaf(LeafMesh),
}

impl ClientMesh {
    /// The mesh of `base`: over its roots, and under leaf placement with its triangles'
    /// leaves.
    pub(super) fn new(base: &SelectiveBase) -> ClientMesh {
        match &base.leaves {
            None => ClientMesh::Cut(CutMesh::new(&base.triangles)),
            Some(leaves) => {
                let mut mesh = LeafMesh::default();
                for (t, leaves) in base.triangles.iter().zip(leaves) {
                    mesh.add(leaves.clone(), *t);
                }
                ClientMesh::Leaf(mesh)
            }
        }
    }

    /// Under leaf placement, adds the triangles packet `p` brings, at their corners'
    /// active ancestors in `tree`. Their numbers.
    pub(super) fn add_triangles(&mut self, tree: &Partial, p: &VsplitPacket) -> Result<Vec<u32>> {
        let ClientMesh::Leaf(mesh) = self else {
            return Ok(Vec::new());
        };
        let mut added = Vec::new();
        for (side, (cut, leaves)) in p.cuts.iter().zip(&p.leaves).enumerate() {
            let (Some(cut), Some([left, right])) = (cut, leaves) else {
                if cut.is_some() != leaves.is_some() {
                    return Err(Error::Invalid(format!(
                        "node {:?}'s split: a cut vertex without its triangle's leaves, \
                         or leaves without a cut vertex",
                        p.node
                    )));
                }
                continue;
            };
            // f_l is (left, right, left cut), f_r (left, right cut, right).
            let leaves = match side {
                0 => [left.clone(), right.clone(), cut.clone()],
                _ => [left.clone(), cut.clone(), right.clone()],
            };
            let corners = [
                tree.active_ancestor(&leaves[0])?,
                tree.active_ancestor(&leaves[1])?,
                tree.active_ancestor(&leaves[2])?,
            ];
            added.push(mesh.add(leaves, corners));
        }
        Ok(added)
    }

    pub(super) fn triangles(&self) -> Vec<[u32; 3]> {
        match self {
            ClientMesh::Cut(m) => m.triangles(),
            ClientMesh::Leaf(m) => m.triangles(),
        }
    }
}
