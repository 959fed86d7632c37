//! The clients of truly selective streaming: the part of the hierarchy they were sent,
//! named ⟨tree-id, node-id⟩, and their mesh over it. [`SelectiveClient`] refines and
//! coarsens on its own for each view, as a local refiner's [`Front`](super::Front)
//! would, splitting a run's nodes together and what the partial order forces first;
//! [`CutVertexClient`] (KLK §7) makes each split as it comes.
//!
//! A packet that does not fit what a client holds is an `Err` naming it; after one, the
//! client's mesh may no longer be its server's.

use std::collections::HashMap;

use super::partial::{each, ClientMesh, ClientNode, Partial};
use super::stream::{view_test, SelectiveBase, VsplitPacket};
use super::NodeName;
use crate::error::{Error, Result};
use crate::lod::refine::{Criteria, View};
use crate::scene::Mesh;

/// A client: the part of the hierarchy it was sent, its front and its mesh.
///
/// ```
/// use flaneur::lod::{Dag, DagConstruction, ProgressiveMesh, View};
/// use flaneur::lod::{SelectiveClient, SelectiveServer, SelectiveSource};
/// let pm = ProgressiveMesh::build(&flaneur::lod::bumpy_torus(800))?;
/// let dag = Dag::build(&pm, DagConstruction::MiniRedundant)?;
/// let source = SelectiveSource::new(&pm, &dag)?;
/// let (mut server, mut client) = (SelectiveServer::new(&source), SelectiveClient::new(source.base()));
/// let view = View::new(glam::Vec3::new(0.0, 0.0, 2.5), glam::Vec3::NEG_Z, 1.0)?;
/// // The client asks only when its view wants what it was not sent.
/// while !client.select(&view, 0.002)?.is_empty() {
///     client.receive(&server.refine(&source, &view, 0.002)?)?;
/// }
/// assert!(client.triangles().len() > pm.base.triangle_count());
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct SelectiveClient {
    tree: Partial,
    mesh: ClientMesh,
    criteria: Criteria,
    /// The nodes the last select split, in order.
    made: Vec<u32>,
    /// Under leaf placement, the triangles each node's packet brought.
    brought: HashMap<u32, Vec<u32>>,
    /// Whether it drops splits from its cache, so that a split the partial order
    /// forces may be missing: asked for, where it would be a server's fault.
    drops: bool,
    /// Vertex splits and collapses made so far.
    splits: u64,
    collapses: u64,
}

impl SelectiveClient {
    /// A client that has the base mesh and its roots, as [`SelectiveSource::base`](super::SelectiveSource::base)
    /// gives them.
    pub fn new(base: SelectiveBase) -> SelectiveClient {
        SelectiveClient {
            mesh: ClientMesh::new(&base),
            tree: Partial::new(base.roots),
            criteria: Criteria::default(),
            made: Vec::new(),
            brought: HashMap::new(),
            drops: false,
            splits: 0,
            collapses: 0,
        }
    }

    /// The client of a cache that drops splits ([`SelectiveClient::drop_splits`]): a
    /// split the partial order forces that it lacks is named among those to ask for.
    pub fn dropping(self) -> SelectiveClient {
        SelectiveClient {
            drops: true,
            ..self
        }
    }

    /// The client under `criteria`, as its server's session
    /// ([`SelectiveServer::with_criteria`](super::SelectiveServer::with_criteria)).
    pub fn with_criteria(self, criteria: Criteria) -> SelectiveClient {
        SelectiveClient { criteria, ..self }
    }

    /// Takes the server's packets: each node's children join the partial hierarchy
    /// (the mesh changes only when [`SelectiveClient::select`] splits them). An `Err`
    /// for a packet of a node the client does not have, or has split already.
    pub fn receive(&mut self, packets: &[VsplitPacket]) -> Result<()> {
        for p in packets {
            let k = self.tree.receive(p)?;
            let added = self.mesh.add_triangles(&self.tree, p)?;
            if !added.is_empty() {
                self.brought.insert(k, added);
            }
        }
        Ok(())
    }

    /// Drops the splits of `nodes` (parents before children), which its mesh does not
    /// use: their children leave the hierarchy, and the triangles their packets
    /// brought leave the mesh. An `Err`, and nothing dropped, for a node whose split is
    /// not held, is used by the mesh or by a split below not dropped, or whose run goes
    /// on outside `nodes`.
    pub fn drop_splits(&mut self, nodes: &[NodeName]) -> Result<()> {
        for k in self.tree.drop_splits(nodes)? {
            if let (ClientMesh::Leaf(mesh), Some(triangles)) =
                (&mut self.mesh, self.brought.remove(&k))
            {
                for t in triangles {
                    mesh.remove(t)?;
                }
            }
        }
        Ok(())
    }

    /// The nodes split with node `name`, itself included: its run's, as held.
    pub fn run_of(&self, name: &NodeName) -> Vec<NodeName> {
        match self.tree.by_name.get(name) {
            Some(&k) => self
                .tree
                .run_nodes(k)
                .into_iter()
                .map(|n| self.tree.nodes[n as usize].name.clone())
                .collect(),
            None => Vec::new(),
        }
    }

    /// Whether [`SelectiveClient::drop_splits`] would drop `nodes`.
    pub fn can_drop(&self, nodes: &[NodeName]) -> bool {
        self.tree.droppable(nodes).is_ok()
    }

    /// Whether the mesh uses node `name`'s split: the front runs below it.
    pub fn is_split(&self, name: &NodeName) -> bool {
        self.tree
            .by_name
            .get(name)
            .is_some_and(|&k| self.tree.made[k as usize])
    }

    /// Brings the client's mesh to `view` under `tau` with what it holds (the
    /// stream module's rule). The names of the nodes it wanted split but was not sent:
    /// empty when the mesh is what the view asks for, else what to ask the server for.
    pub fn select(&mut self, view: &View, tau: f32) -> Result<Vec<NodeName>> {
        let test = view_test(view, tau, self.criteria)?;
        self.made.clear();
        // What `qrefine` says of each node, asked once a select: the view is fixed.
        let mut memo: HashMap<u32, bool> = HashMap::new();
        let mut wants = |nodes: &[ClientNode], n: u32| {
            *memo.entry(n).or_insert_with(|| {
                nodes[n as usize]
                    .info
                    .is_some_and(|i| test.evaluate(&i.geometry()).needs_split)
            })
        };
        // Each pass splits every active node the view wants, in the order of their
        // names; a node not wanted stays so, so a pass looks only at the nodes the last
        // one made active and at those wanted but not sent.
        let mut candidates: Vec<u32> = (0..self.tree.nodes.len() as u32)
            .filter(|&n| self.tree.active[n as usize])
            .collect();
        let missing = loop {
            let mut wanted: Vec<u32> = candidates
                .into_iter()
                .filter(|&n| self.tree.active[n as usize] && wants(&self.tree.nodes, n))
                .collect();
            self.by_name(&mut wanted);
            wanted.dedup();
            let (have, lack): (Vec<u32>, Vec<u32>) = wanted
                .into_iter()
                .partition(|&n| self.tree.nodes[n as usize].children.is_some());
            if have.is_empty() {
                break lack
                    .iter()
                    .map(|&n| self.tree.nodes[n as usize].name.clone())
                    .collect::<Vec<_>>();
            }
            let start = self.made.len();
            for n in have {
                if self.tree.active[n as usize] {
                    if let Some(k) = self.split_run(n)? {
                        return Ok(vec![self.tree.nodes[k as usize].name.clone()]);
                    }
                }
            }
            candidates = lack;
            for &m in &self.made[start..] {
                let children = self.tree.nodes[m as usize].children.expect("a node split");
                candidates.extend(
                    children
                        .into_iter()
                        .filter(|&c| self.tree.active[c as usize]),
                );
            }
        };
        if !missing.is_empty() {
            return Ok(missing);
        }
        // Each pass collapses every node the view does not want whose children are
        // active, in the order of their names, if the mesh stays a manifold; the next
        // looks at those it could not collapse and at the parents of those it did.
        let mut parents: Vec<u32> = (0..self.tree.nodes.len() as u32)
            .filter(|&n| self.children_active(n))
            .collect();
        loop {
            self.by_name(&mut parents);
            parents.dedup();
            let (mut next, mut changed) = (Vec::new(), false);
            for p in parents {
                if !self.children_active(p) || wants(&self.tree.nodes, p) {
                    continue;
                }
                if !self.can_collapse(p) {
                    next.push(p);
                    continue;
                }
                for n in self.collapse(p) {
                    next.extend(self.tree.nodes[n as usize].parent);
                }
                changed = true;
            }
            if !changed {
                return Ok(Vec::new());
            }
            parents = next;
        }
    }

    fn by_name(&self, nodes: &mut [u32]) {
        nodes.sort_by(|a, b| {
            self.tree.nodes[*a as usize]
                .name
                .cmp(&self.tree.nodes[*b as usize].name)
        });
    }

    fn children_active(&self, n: u32) -> bool {
        self.tree.nodes[n as usize]
            .children
            .is_some_and(|[l, r]| self.tree.active[l as usize] && self.tree.active[r as usize])
    }

    /// `node`'s run, each node with its children, if every one's children are active.
    fn collapsible_run(&self, node: u32) -> Option<Vec<(u32, [u32; 2])>> {
        self.tree
            .run_nodes(node)
            .into_iter()
            .map(|n| {
                self.children_active(n)
                    .then(|| (n, self.tree.nodes[n as usize].children.expect("a parent")))
            })
            .collect()
    }

    /// Whether `node`'s run may collapse and leave the mesh a manifold (as
    /// [`Front::can_collapse`](super::Front::can_collapse)).
    fn can_collapse(&self, node: u32) -> bool {
        let Some(run) = self.collapsible_run(node) else {
            return false;
        };
        match &self.mesh {
            ClientMesh::Cut(m) => run.iter().all(|&(n, c)| m.collapse_keeps_manifold(n, c)),
            ClientMesh::Leaf(m) => m.collapse_keeps_manifold(&run),
        }
    }

    /// Collapses `node`'s run: the nodes collapsed.
    fn collapse(&mut self, node: u32) -> Vec<u32> {
        let run = self.collapsible_run(node).expect("a run that may collapse");
        match &mut self.mesh {
            ClientMesh::Cut(m) => run.iter().for_each(|&(n, c)| m.collapse(n, c)),
            ClientMesh::Leaf(m) => m.collapse(&run),
        }
        self.collapses += run.len() as u64;
        for &(n, children) in &run {
            self.tree.unsplit(n, children);
        }
        run.into_iter().map(|(n, _)| n).collect()
    }

    /// Splits every node of `node`'s run that is not split yet. A forced split it
    /// lacks, if it drops splits: the node.
    fn split_run(&mut self, node: u32) -> Result<Option<u32>> {
        for n in self.tree.run_nodes(node) {
            if let Some(k) = self.make_split(n)? {
                return Ok(Some(k));
            }
        }
        Ok(None)
    }

    /// Splits forced node `a` and its run; a split it lacks as [`split_run`](Self::split_run).
    fn force(&mut self, a: u32) -> Result<Option<u32>> {
        match self.tree.children(a) {
            Err(_) if self.drops => Ok(Some(a)),
            Err(e) => Err(e),
            Ok(_) => self.split_run(a),
        }
    }

    /// Splits `node`, bringing it to the front first, then splitting the node both its
    /// cut vertices' active ancestors are, found by right shifts of their names, until
    /// they differ (KLK's partial order); nothing if it is split already.
    fn make_split(&mut self, node: u32) -> Result<Option<u32>> {
        while !self.tree.active[node as usize] {
            match self.tree.active_above(node) {
                None => return Ok(None),
                Some(a) => {
                    if let Some(k) = self.force(a)? {
                        return Ok(Some(k));
                    }
                }
            }
        }
        let cuts = self.tree.nodes[node as usize].cuts.clone();
        if let [Some(l), Some(r)] = &cuts {
            loop {
                let a = self.tree.active_ancestor(l)?;
                if a != self.tree.active_ancestor(r)? {
                    break;
                }
                if let Some(k) = self.force(a)? {
                    return Ok(Some(k));
                }
            }
        }
        let children = self.tree.children(node)?;
        match &mut self.mesh {
            ClientMesh::Cut(m) => {
                let at = each(&cuts, |c| self.tree.active_ancestor(c))?;
                m.split(node, children, at)?;
            }
            ClientMesh::Leaf(m) => {
                m.split(node, self.tree.nodes[node as usize].name.depth(), children)?
            }
        }
        self.tree.split(node, children);
        self.made.push(node);
        self.splits += 1;
        Ok(None)
    }

    /// The nodes the last [`SelectiveClient::select`] split, in order, with whether
    /// each has a split of its own to come (what `qrefine` reads of it was sent).
    pub fn last_splits(&self) -> Vec<(NodeName, [bool; 2])> {
        self.made
            .iter()
            .map(|&n| {
                let node = &self.tree.nodes[n as usize];
                let splits = node
                    .children
                    .expect("a node split")
                    .map(|c| self.tree.nodes[c as usize].info.is_some());
                (node.name.clone(), splits)
            })
            .collect()
    }

    /// Whether the client holds node `name`'s split.
    pub fn holds_split(&self, name: &NodeName) -> bool {
        self.tree
            .by_name
            .get(name)
            .is_some_and(|&k| self.tree.nodes[k as usize].children.is_some())
    }

    /// The mesh's triangles, their corners as node names.
    pub fn triangles(&self) -> Vec<[NodeName; 3]> {
        self.tree.named(self.mesh.triangles())
    }

    /// The mesh to draw: its triangles over their corners' vertices.
    pub fn mesh(&self) -> Mesh {
        self.tree.mesh(self.mesh.triangles())
    }

    /// The vertex splits and collapses its selects made so far (El-Sana's split/merge
    /// operations).
    pub fn operations(&self) -> (u64, u64) {
        (self.splits, self.collapses)
    }

    /// Nodes held (the roots included).
    pub fn nodes(&self) -> usize {
        self.tree.nodes.len() - self.tree.free.len()
    }

    /// The names of the nodes held whose split was not sent: what a client resuming
    /// its session tells the server
    /// ([`SelectiveServer::resume`](super::SelectiveServer::resume)).
    pub fn leaves(&self) -> Vec<NodeName> {
        self.tree.leaves()
    }
}

/// The client of KLK §7's variant: it makes every split as it comes and never refines
/// on its own
/// ([`SelectiveServer::cut_vertex_only`](super::SelectiveServer::cut_vertex_only)).
/// Under cut placement it places each split at the cut vertices the server names as
/// they stand on its mesh; under leaf placement by the triangles' leaves.
#[derive(Clone, Debug)]
pub struct CutVertexClient {
    tree: Partial,
    mesh: ClientMesh,
}

impl CutVertexClient {
    /// A client that has the base mesh.
    pub fn new(base: SelectiveBase) -> CutVertexClient {
        CutVertexClient {
            mesh: ClientMesh::new(&base),
            tree: Partial::new(base.roots),
        }
    }

    /// Makes the splits of `packets` in order. An `Err` for a split of a node the
    /// client does not hold on its front, or at a cut vertex it does not hold.
    pub fn receive(&mut self, packets: &[VsplitPacket]) -> Result<()> {
        for p in packets {
            let node = self.tree.id(&p.node)?;
            if !self.tree.active[node as usize] {
                return Err(Error::Invalid(format!(
                    "a split of node {:?}, which is not on the client's front",
                    p.node
                )));
            }
            self.tree.receive(p)?;
            let children = self.tree.children(node)?;
            // Under leaf placement the split's triangles join first, at the node.
            self.mesh.add_triangles(&self.tree, p)?;
            match &mut self.mesh {
                ClientMesh::Cut(m) => {
                    m.split(node, children, each(&p.cuts, |c| self.tree.id(c))?)?;
                }
                ClientMesh::Leaf(m) => m.split(node, p.node.depth(), children)?,
            }
            self.tree.split(node, children);
        }
        Ok(())
    }

    /// The mesh's triangles, their corners as node names.
    pub fn triangles(&self) -> Vec<[NodeName; 3]> {
        self.tree.named(self.mesh.triangles())
    }

    /// The mesh to draw: its triangles over their corners' vertices.
    pub fn mesh(&self) -> Mesh {
        self.tree.mesh(self.mesh.triangles())
    }

    /// The names of the nodes held that were not split: what a client resuming its
    /// session tells the server
    /// ([`SelectiveServer::resume`](super::SelectiveServer::resume)).
    pub fn leaves(&self) -> Vec<NodeName> {
        self.tree.leaves()
    }
}
