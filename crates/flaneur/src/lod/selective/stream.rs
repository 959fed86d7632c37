//! View-dependent streaming by truly selective refinement (Kim–Lee–Kobbelt §5): what
//! a server holds of a mesh ([`SelectiveSource`]: the vertex hierarchy and what
//! `qrefine` reads of each node), a server's session ([`SelectiveServer`]: the front of
//! what it has sent, which only moves down, split where the client's view asks and in
//! the partial order, each split sent once as a [`VsplitPacket`]), and a client
//! ([`SelectiveClient`]: the part of the hierarchy it was sent, named ⟨tree-id,
//! node-id⟩, refined and coarsened locally for each view, asking the server only for
//! what it has not got).
//!
//! `qrefine` is Hoppe's criteria as Zheng's refinement applies them (view cone, cone
//! of normals, screen-space error under τ), read from the DAG attributes of the split
//! that splits the node. Each view is brought to a fixed point, the same on both sides:
//! every active node `qrefine` wants split is split (forcing what the partial order
//! asks), then every node whose children are active and which `qrefine` no longer
//! wants split is collapsed where the mesh stays a manifold, each pass in the order of
//! the nodes' names.
//!
//! Crease and seam runs (splits that must go together) are not streamed: KLK's scheme
//! is for manifold vertex splits, and a mesh with runs is refused by name.

use std::collections::HashMap;

use glam::Vec3;

use super::{CutMesh, Front, HeapIndex, NodeName, VertexHierarchy};
use crate::error::{Error, Result};
use crate::lod::dag::Dag;
use crate::lod::pm::ProgressiveMesh;
use crate::lod::refine::{Criteria, NodeGeometry, View, ViewTest};

/// What `qrefine` reads of a node that splits: its split's v_c (sphere centre, cone
/// apex), v_c's normal (the cone's axis) and the DAG attributes of its split.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineInfo {
    /// The sphere's centre.
    pub centre: [f32; 3],
    /// The cone's axis (unit, or zero: never back-facing).
    pub axis: [f32; 3],
    /// The sphere's radius, metres.
    pub radius: f32,
    /// sin of the cone's half-angle.
    pub cone_sin: f32,
    /// The approximation error, metres.
    pub error: f32,
}

impl RefineInfo {
    fn geometry(&self) -> NodeGeometry {
        NodeGeometry {
            centre: Vec3::from(self.centre),
            radius: self.radius,
            axis: Vec3::from(self.axis),
            cone_sin: self.cone_sin,
            error: self.error,
        }
    }
}

/// One split as the server sends it: the node, its fundamental cut vertices, the new
/// vertex (the right child; the left keeps the node's), and what `qrefine` reads of
/// each child (`None` for a leaf of the whole hierarchy).
#[derive(Clone, Debug, PartialEq)]
pub struct VsplitPacket {
    /// The node split.
    pub node: NodeName,
    /// Its fundamental cut vertices, left and right.
    pub cuts: [Option<NodeName>; 2],
    /// The right child's vertex position.
    pub position: [f32; 3],
    /// The right child's vertex normal.
    pub normal: [f32; 3],
    /// What `qrefine` reads of the left and the right child.
    pub children: [Option<RefineInfo>; 2],
}

/// What a client starts from: the base mesh over the roots (numbered by tree-id) and
/// each root's vertex and what `qrefine` reads of it.
#[derive(Clone, Debug, PartialEq)]
pub struct SelectiveBase {
    /// The base mesh's triangles, corners as tree-ids.
    pub triangles: Vec<[u32; 3]>,
    /// Each root's vertex position and normal, and what `qrefine` reads of it.
    pub roots: Vec<([f32; 3], [f32; 3], Option<RefineInfo>)>,
}

/// What a server holds of one mesh: its vertex hierarchy, each node's vertex and what
/// `qrefine` reads of it.
#[derive(Clone, Debug)]
pub struct SelectiveSource {
    h: VertexHierarchy,
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    info: Vec<Option<RefineInfo>>,
    base: Vec<[u32; 3]>,
}

impl SelectiveSource {
    /// The source of `pm`, `dag` being the DAG built from it (for its attributes). An
    /// `Err` for a mesh whose splits come in crease or seam runs, or a DAG of another
    /// mesh.
    pub fn new(pm: &ProgressiveMesh, dag: &Dag) -> Result<SelectiveSource> {
        if let Some(k) = pm.splits.iter().position(|s| s.joins_previous) {
            return Err(Error::Invalid(format!(
                "split {k} joins a crease or seam run: truly selective streaming is for \
                 manifold vertex splits, one at a time"
            )));
        }
        if dag.split_count() != pm.splits.len() {
            return Err(Error::Invalid(format!(
                "a DAG of {} splits with a progressive mesh of {}",
                dag.split_count(),
                pm.splits.len()
            )));
        }
        let h = VertexHierarchy::new(pm)?;
        let mut positions = pm.base.positions.clone();
        let mut normals = pm.base.normals.clone();
        positions.extend(pm.splits.iter().map(|s| s.position));
        normals.extend(pm.splits.iter().map(|s| s.normal));
        let info = (0..h.len() as u32)
            .map(|n| {
                let split = h.split_index(n)?;
                let k = dag.node_of_split(split)?;
                let (a, s) = (dag.attrs(k), &pm.splits[split]);
                Some(RefineInfo {
                    centre: s.position,
                    axis: Vec3::from(s.normal).normalize_or_zero().to_array(),
                    radius: a.radius,
                    cone_sin: a.cone_sin,
                    error: a.error,
                })
            })
            .collect();
        let base = h.roots().triangles(&h);
        Ok(SelectiveSource {
            h,
            positions,
            normals,
            info,
            base,
        })
    }

    /// The vertex hierarchy.
    pub fn hierarchy(&self) -> &VertexHierarchy {
        &self.h
    }

    /// What a client starts from: the base mesh over the roots (tree-ids), each root's
    /// vertex and what `qrefine` reads of it.
    pub fn base(&self) -> SelectiveBase {
        SelectiveBase {
            triangles: self.base.clone(),
            roots: (0..self.h.roots)
                .map(|v| (self.positions[v], self.normals[v], self.info[v]))
                .collect(),
        }
    }

    fn packet(&self, node: u32) -> VsplitPacket {
        let [left, right] = self.h.children(node).expect("a split node");
        let cuts = self
            .h
            .cut_vertices(node)
            .expect("a split node")
            .map(|c| c.map(|c| self.h.name(c)));
        let v = self.h.vertex(right) as usize;
        VsplitPacket {
            node: self.h.name(node),
            cuts,
            position: self.positions[v],
            normal: self.normals[v],
            children: [self.info[left as usize], self.info[right as usize]],
        }
    }

    /// Whether `node` should split for `test` (a leaf of the whole hierarchy never).
    fn qrefine(&self, test: &ViewTest, node: u32) -> bool {
        self.info[node as usize].is_some_and(|i| test.evaluate(&i.geometry()).needs_split)
    }

    /// A local refiner's front for `view` under `tau`, brought from `front` to the
    /// fixed point a client reaches (the module's rule): the reference a client's mesh
    /// is checked against.
    pub fn select(&self, front: &mut Front, view: &View, tau: f32) -> Result<()> {
        let test = view_test(view, tau, Criteria::default())?;
        let h = &self.h;
        let by_name = |mut nodes: Vec<u32>| {
            nodes.sort_by_cached_key(|&n| h.name(n));
            nodes
        };
        loop {
            let wanted = by_name(
                (0..h.len() as u32)
                    .filter(|&n| front.is_active(n) && self.qrefine(&test, n))
                    .collect(),
            );
            if wanted.is_empty() {
                break;
            }
            for n in wanted {
                if front.is_active(n) {
                    front.split(h, n)?;
                }
            }
        }
        loop {
            let mut changed = false;
            let parents = by_name(
                (0..h.len() as u32)
                    .filter(|&n| {
                        h.children(n)
                            .is_some_and(|[l, r]| front.is_active(l) && front.is_active(r))
                    })
                    .collect(),
            );
            for p in parents {
                if !self.qrefine(&test, p) && front.can_collapse(h, p) {
                    front.collapse(h, p)?;
                    changed = true;
                }
            }
            if !changed {
                return Ok(());
            }
        }
    }
}

fn view_test(view: &View, tau: f32, criteria: Criteria) -> Result<ViewTest> {
    view.validate()?;
    if !(tau.is_finite() && tau > 0.0) {
        return Err(Error::Invalid(format!(
            "a screen-space error τ of {tau}: give a number above 0"
        )));
    }
    Ok(ViewTest::new(view, tau, criteria))
}

/// A server's session with one client: the front of what it has sent, which only
/// moves down (KLK's active tags).
#[derive(Clone, Debug)]
pub struct SelectiveServer {
    sent: Front,
    criteria: Criteria,
    cut_vertex_only: bool,
}

impl SelectiveServer {
    /// A session that has sent the base mesh.
    pub fn new(source: &SelectiveSource) -> SelectiveServer {
        SelectiveServer {
            sent: source.h.roots(),
            criteria: Criteria::default(),
            cut_vertex_only: false,
        }
    }

    /// The session of KLK §7's variant, for a client that will not refine on its own
    /// ([`CutVertexClient`]): each packet names the split's cut vertices as they stand
    /// on the sent front (the client's), not the fundamental ones, and carries nothing
    /// for `qrefine`.
    pub fn cut_vertex_only(self) -> SelectiveServer {
        SelectiveServer {
            cut_vertex_only: true,
            ..self
        }
    }

    /// The session under `criteria` (both by default; none for a view-independent
    /// stream, which refines to the screen-space error alone).
    pub fn with_criteria(self, criteria: Criteria) -> SelectiveServer {
        SelectiveServer { criteria, ..self }
    }

    /// The splits `view` under `tau` asks for that were not sent yet, in the order a
    /// client must make them (KLK's SelectiveStreaming): each node of the sent front,
    /// in the order of the nodes, that `qrefine` wants split, with what the partial
    /// order forces first; a node's children are visited in the same pass.
    pub fn refine(
        &mut self,
        source: &SelectiveSource,
        view: &View,
        tau: f32,
    ) -> Result<Vec<VsplitPacket>> {
        let test = view_test(view, tau, self.criteria)?;
        let mut packets = Vec::new();
        // A node's children come after it, so one sequential pass reaches them.
        let h = &source.h;
        for n in 0..h.len() as u32 {
            if !(self.sent.is_active(n) && source.qrefine(&test, n)) {
                continue;
            }
            let before = self.cut_vertex_only.then(|| self.sent.clone());
            let splits = self.sent.split(h, n)?;
            let Some(mut front) = before else {
                packets.extend(splits.into_iter().map(|s| source.packet(s)));
                continue;
            };
            // The cut vertices as each split finds them on the front, split by split.
            for s in splits {
                let mut p = source.packet(s);
                let cuts = h.cut_vertices(s).expect("a split node");
                p.cuts = cuts.map(|c| c.map(|c| h.name(front.active_ancestor(h, c))));
                p.children = [None, None];
                let [l, r] = h.children(s).expect("a split node");
                front.active[s as usize] = false;
                front.active[l as usize] = true;
                front.active[r as usize] = true;
                packets.push(p);
            }
        }
        Ok(packets)
    }

    /// How many nodes the client was sent (the roots included).
    pub fn sent_nodes(&self) -> usize {
        self.sent.active.iter().filter(|a| **a).count()
    }

    /// The mesh of the front sent so far, its corners as node names: what a
    /// [`CutVertexClient`] holds.
    pub fn sent_triangles(&self, source: &SelectiveSource) -> Vec<[NodeName; 3]> {
        self.sent
            .triangles(&source.h)
            .iter()
            .map(|t| t.map(|n| source.h.name(n)))
            .collect()
    }
}

/// One node of a client's partial hierarchy.
#[derive(Clone, Debug)]
struct ClientNode {
    name: NodeName,
    children: Option<[u32; 2]>,
    cuts: [Option<NodeName>; 2],
    position: [f32; 3],
    normal: [f32; 3],
    info: Option<RefineInfo>,
}

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
    nodes: Vec<ClientNode>,
    by_name: HashMap<NodeName, u32>,
    active: Vec<bool>,
    mesh: CutMesh,
    criteria: Criteria,
}

impl SelectiveClient {
    /// A client that has the base mesh and its roots, as [`SelectiveSource::base`] gives
    /// them.
    pub fn new(SelectiveBase { triangles, roots }: SelectiveBase) -> SelectiveClient {
        let nodes: Vec<ClientNode> = roots
            .into_iter()
            .enumerate()
            .map(|(tree, (position, normal, info))| ClientNode {
                name: NodeName {
                    tree: tree as u32,
                    node: HeapIndex::root(),
                },
                children: None,
                cuts: [None, None],
                position,
                normal,
                info,
            })
            .collect();
        let by_name = nodes
            .iter()
            .enumerate()
            .map(|(k, n)| (n.name.clone(), k as u32))
            .collect();
        SelectiveClient {
            active: vec![true; nodes.len()],
            nodes,
            by_name,
            mesh: CutMesh::new(&triangles),
            criteria: Criteria::default(),
        }
    }

    /// The client under `criteria`, as its server's session
    /// ([`SelectiveServer::with_criteria`]).
    pub fn with_criteria(self, criteria: Criteria) -> SelectiveClient {
        SelectiveClient { criteria, ..self }
    }

    /// Takes the server's packets: each node's children join the partial hierarchy
    /// (the mesh changes only when [`SelectiveClient::select`] splits them). An `Err`
    /// for a packet of a node the client does not have, or has split already.
    pub fn receive(&mut self, packets: &[VsplitPacket]) -> Result<()> {
        for p in packets {
            let &k = self.by_name.get(&p.node).ok_or_else(|| {
                Error::Invalid(format!(
                    "a split of node {:?}, which the client was not sent",
                    p.node
                ))
            })?;
            if self.nodes[k as usize].children.is_some() {
                return Err(Error::Invalid(format!("node {:?} was sent twice", p.node)));
            }
            let parent = &self.nodes[k as usize];
            let (name, position, normal) = (parent.name.clone(), parent.position, parent.normal);
            let mut child = |right: bool, position, normal, info| {
                let id = self.nodes.len() as u32;
                let name = NodeName {
                    tree: name.tree,
                    node: name.node.child(right),
                };
                self.by_name.insert(name.clone(), id);
                self.nodes.push(ClientNode {
                    name,
                    children: None,
                    cuts: [None, None],
                    position,
                    normal,
                    info,
                });
                self.active.push(false);
                id
            };
            let left = child(false, position, normal, p.children[0]);
            let right = child(true, p.position, p.normal, p.children[1]);
            let node = &mut self.nodes[k as usize];
            node.children = Some([left, right]);
            node.cuts = p.cuts.clone();
        }
        Ok(())
    }

    /// Brings the client's mesh to `view` under `tau` with what it holds (the module's
    /// rule). The names of the nodes it wanted split but was not sent: empty when the
    /// mesh is what the view asks for, else what to ask the server for.
    pub fn select(&mut self, view: &View, tau: f32) -> Result<Vec<NodeName>> {
        let test = view_test(view, tau, self.criteria)?;
        let qrefine = |n: &ClientNode| {
            n.info
                .is_some_and(|i| test.evaluate(&i.geometry()).needs_split)
        };
        let missing = loop {
            let mut wanted: Vec<u32> = (0..self.nodes.len() as u32)
                .filter(|&n| self.active[n as usize] && qrefine(&self.nodes[n as usize]))
                .collect();
            wanted.sort_by(|a, b| {
                self.nodes[*a as usize]
                    .name
                    .cmp(&self.nodes[*b as usize].name)
            });
            let (have, lack): (Vec<u32>, Vec<u32>) = wanted
                .into_iter()
                .partition(|&n| self.nodes[n as usize].children.is_some());
            if have.is_empty() {
                break lack
                    .iter()
                    .map(|&n| self.nodes[n as usize].name.clone())
                    .collect::<Vec<_>>();
            }
            for n in have {
                if self.active[n as usize] {
                    self.split(n)?;
                }
            }
        };
        if !missing.is_empty() {
            return Ok(missing);
        }
        loop {
            let mut parents: Vec<u32> = (0..self.nodes.len() as u32)
                .filter(|&n| {
                    self.nodes[n as usize]
                        .children
                        .is_some_and(|[l, r]| self.active[l as usize] && self.active[r as usize])
                })
                .collect();
            parents.sort_by(|a, b| {
                self.nodes[*a as usize]
                    .name
                    .cmp(&self.nodes[*b as usize].name)
            });
            let mut changed = false;
            for p in parents {
                let [l, r] = self.nodes[p as usize].children.expect("a parent");
                if !qrefine(&self.nodes[p as usize]) && self.mesh.collapse_keeps_manifold(p, [l, r])
                {
                    self.mesh.collapse(p, [l, r]);
                    self.active[l as usize] = false;
                    self.active[r as usize] = false;
                    self.active[p as usize] = true;
                    changed = true;
                }
            }
            if !changed {
                return Ok(Vec::new());
            }
        }
    }

    /// Splits active node `n`, first what the partial order forces: the node both its
    /// cut vertices' active ancestors are, found by right shifts of their names.
    fn split(&mut self, n: u32) -> Result<()> {
        let cuts = self.nodes[n as usize].cuts.clone();
        if let [Some(l), Some(r)] = &cuts {
            loop {
                let (a, b) = (self.active_ancestor(l)?, self.active_ancestor(r)?);
                if a != b {
                    break;
                }
                if self.nodes[a as usize].children.is_none() {
                    return Err(Error::Invalid(format!(
                        "the partial order asks for a split of node {:?}, which was not sent",
                        self.nodes[a as usize].name
                    )));
                }
                self.split(a)?;
            }
        }
        let children = self.nodes[n as usize].children.expect("a node sent split");
        let at = [
            cuts[0]
                .as_ref()
                .map(|c| self.active_ancestor(c))
                .transpose()?,
            cuts[1]
                .as_ref()
                .map(|c| self.active_ancestor(c))
                .transpose()?,
        ];
        self.mesh.split(n, children, at)?;
        self.active[n as usize] = false;
        self.active[children[0] as usize] = true;
        self.active[children[1] as usize] = true;
        Ok(())
    }

    /// The active node `name` descends from: `name` shifted right until it names a
    /// node on the front (KLK §4).
    fn active_ancestor(&self, name: &NodeName) -> Result<u32> {
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

    /// The mesh's triangles, their corners as node names.
    pub fn triangles(&self) -> Vec<[NodeName; 3]> {
        self.mesh
            .triangles()
            .iter()
            .map(|t| t.map(|k| self.nodes[k as usize].name.clone()))
            .collect()
    }

    /// Nodes held (the roots included).
    pub fn nodes(&self) -> usize {
        self.nodes.len()
    }
}

/// The client of KLK §7's variant: it makes every split as it comes, at the cut
/// vertices the server names, and never refines on its own
/// ([`SelectiveServer::cut_vertex_only`]).
#[derive(Clone, Debug)]
pub struct CutVertexClient {
    names: Vec<NodeName>,
    by_name: HashMap<NodeName, u32>,
    mesh: CutMesh,
}

impl CutVertexClient {
    /// A client that has the base mesh.
    pub fn new(base: SelectiveBase) -> CutVertexClient {
        let names: Vec<NodeName> = (0..base.roots.len() as u32)
            .map(|tree| NodeName {
                tree,
                node: HeapIndex::root(),
            })
            .collect();
        let by_name = names.iter().cloned().zip(0..).collect();
        CutVertexClient {
            names,
            by_name,
            mesh: CutMesh::new(&base.triangles),
        }
    }

    /// Makes the splits of `packets` in order. An `Err` for a split of a node, or at a
    /// cut vertex, the client does not hold.
    pub fn receive(&mut self, packets: &[VsplitPacket]) -> Result<()> {
        for p in packets {
            let id = |name: &NodeName| {
                self.by_name.get(name).copied().ok_or_else(|| {
                    Error::Invalid(format!(
                        "a split names node {name:?}, which the client lacks"
                    ))
                })
            };
            let node = id(&p.node)?;
            let cuts = [
                p.cuts[0].as_ref().map(id).transpose()?,
                p.cuts[1].as_ref().map(id).transpose()?,
            ];
            let mut child = |right: bool| {
                let name = NodeName {
                    tree: p.node.tree,
                    node: p.node.node.child(right),
                };
                let k = self.names.len() as u32;
                self.by_name.insert(name.clone(), k);
                self.names.push(name);
                k
            };
            let children = [child(false), child(true)];
            self.mesh.split(node, children, cuts)?;
        }
        Ok(())
    }

    /// The mesh's triangles, their corners as node names.
    pub fn triangles(&self) -> Vec<[NodeName; 3]> {
        self.mesh
            .triangles()
            .iter()
            .map(|t| t.map(|k| self.names[k as usize].clone()))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::dag::DagConstruction;
    use rand::{Rng, SeedableRng};

    /// Triangles turned to start at their smallest corner, sorted.
    fn canonical(mut triangles: Vec<[NodeName; 3]>) -> Vec<[NodeName; 3]> {
        for t in &mut triangles {
            let k = (0..3).min_by_key(|&k| t[k].clone()).unwrap();
            t.rotate_left(k);
        }
        triangles.sort_unstable();
        triangles
    }

    #[test]
    fn a_streamed_mesh_equals_a_local_refiners_triangle_for_triangle() {
        let mesh = crate::lod::bumpy_torus(1500);
        let pm = ProgressiveMesh::build(&mesh).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        let source = SelectiveSource::new(&pm, &dag).unwrap();
        let h = source.hierarchy();
        let mut server = SelectiveServer::new(&source);
        let mut client = SelectiveClient::new(source.base());
        let mut local = h.roots();
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let (mut asked, mut sent) = (0, 0);
        for step in 0..150 {
            let eye = Vec3::new(
                rng.gen_range(-3.0..3.0),
                rng.gen_range(-3.0..3.0),
                rng.gen_range(-3.0..3.0),
            );
            let look = -eye + Vec3::new(rng.gen_range(-0.5..0.5), 0.0, rng.gen_range(-0.5..0.5));
            let view = View::new(eye, look, 1.0).unwrap();
            let tau = rng.gen_range(0.0005..0.01);
            source.select(&mut local, &view, tau).unwrap();
            loop {
                let missing = client.select(&view, tau).unwrap();
                if missing.is_empty() {
                    break;
                }
                asked += 1;
                let packets = server.refine(&source, &view, tau).unwrap();
                assert!(
                    !packets.is_empty(),
                    "step {step}: the server had nothing for {missing:?}"
                );
                sent += packets.len();
                client.receive(&packets).unwrap();
            }
            let ours = canonical(client.triangles());
            let theirs = canonical(
                local
                    .triangles(h)
                    .iter()
                    .map(|t| t.map(|n| h.name(n)))
                    .collect(),
            );
            assert_eq!(ours, theirs, "step {step}");
        }
        assert!(asked > 10 && sent > 100, "asked {asked}, sent {sent}");
        // Each split is sent once: never more than the hierarchy has.
        assert_eq!(client.nodes(), h.roots + 2 * sent);
        assert!(client.nodes() <= h.len());
    }

    #[test]
    fn a_mesh_of_crease_runs_and_a_bad_tau_are_refused_by_name() {
        let pm = ProgressiveMesh::build(&crate::lod::fixtures::building()).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        let e = SelectiveSource::new(&pm, &dag).unwrap_err();
        assert!(e.to_string().contains("crease or seam run"), "{e}");
        let pm = ProgressiveMesh::build(&crate::lod::bumpy_torus(400)).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        let source = SelectiveSource::new(&pm, &dag).unwrap();
        let view = View::new(Vec3::new(0.0, 0.0, 3.0), Vec3::NEG_Z, 1.0).unwrap();
        for tau in [0.0, -1.0, f32::NAN] {
            let e = SelectiveServer::new(&source)
                .refine(&source, &view, tau)
                .unwrap_err();
            assert!(e.to_string().contains('τ'), "{e}");
        }
    }

    #[test]
    fn a_cut_vertex_only_client_holds_the_sent_front_without_qrefines_data() {
        let pm = ProgressiveMesh::build(&crate::lod::bumpy_torus(1500)).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        let source = SelectiveSource::new(&pm, &dag).unwrap();
        let mut server = SelectiveServer::new(&source).cut_vertex_only();
        let mut full = SelectiveServer::new(&source);
        let mut client = CutVertexClient::new(source.base());
        let mut rng = rand::rngs::StdRng::seed_from_u64(6);
        let mut sent = 0;
        for step in 0..60 {
            let eye = Vec3::new(
                rng.gen_range(-3.0..3.0),
                rng.gen_range(-3.0..3.0),
                rng.gen_range(-3.0..3.0),
            );
            let view = View::new(eye, -eye, 1.0).unwrap();
            let packets = server.refine(&source, &view, 0.002).unwrap();
            let with_info = full.refine(&source, &view, 0.002).unwrap();
            // The same splits, in the same order; nothing for qrefine.
            let nodes = |p: &[VsplitPacket]| p.iter().map(|p| p.node.clone()).collect::<Vec<_>>();
            assert_eq!(nodes(&packets), nodes(&with_info), "step {step}");
            assert!(packets.iter().all(|p| p.children == [None, None]));
            sent += packets.len();
            client.receive(&packets).unwrap();
            assert_eq!(
                canonical(client.triangles()),
                canonical(server.sent_triangles(&source)),
                "step {step}"
            );
        }
        assert!(sent > 100, "{sent}");
    }
}
