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
//! Crease and seam runs (splits that must go together, some adding no triangle) are
//! ours: KLK's scheme is for manifold vertex splits, placed by their cut vertices. For
//! a mesh with such splits ([`Placement::LeafCorners`]) each packet also names its
//! run's first node and the leaves of its new triangles below its children, and the
//! client keeps the fully refined triangles it was sent at their leaves' active
//! ancestors ([`LeafMesh`]), as the hierarchy defines a front's mesh.

use std::collections::BTreeSet;

use glam::Vec3;

use super::{Front, NodeName, VertexHierarchy};
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
    pub(super) fn geometry(&self) -> NodeGeometry {
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
    /// The node of the first split of the run this split belongs to, when the run has
    /// more than one: the client splits and collapses the run's nodes together.
    pub run: Option<NodeName>,
    /// Under [`Placement::LeafCorners`], the leaves of f_l and f_r below the left and
    /// the right child (`None` where the split adds no such triangle, and always under
    /// [`Placement::CutVertices`]).
    pub leaves: [Option<[NodeName; 2]>; 2],
}

/// How a client places a split's triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placement {
    /// By the cut vertices' active ancestors, which bound the fan that goes to the
    /// right child (KLK §5.3): for meshes whose every split adds a triangle.
    CutVertices,
    /// By each triangle's leaves, sent with it: for meshes with wedge splits that add
    /// none (ours).
    LeafCorners,
}

/// What a client starts from: the base mesh over the roots (numbered by tree-id) and
/// each root's vertex and what `qrefine` reads of it.
#[derive(Clone, Debug, PartialEq)]
pub struct SelectiveBase {
    /// The base mesh's triangles, corners as tree-ids.
    pub triangles: Vec<[u32; 3]>,
    /// Each root's vertex position and normal, and what `qrefine` reads of it.
    pub roots: Vec<([f32; 3], [f32; 3], Option<RefineInfo>)>,
    /// Under [`Placement::LeafCorners`], each base triangle's corners' leaves (the
    /// same triangles, in the same order and turn); `None` under
    /// [`Placement::CutVertices`].
    pub leaves: Option<Vec<[NodeName; 3]>>,
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
    /// The base triangles' leaves, under leaf placement.
    base_leaves: Option<Vec<[u32; 3]>>,
}

impl SelectiveSource {
    /// The source of `pm`, `dag` being the DAG built from it (for its attributes). An
    /// `Err` for a DAG of another mesh.
    pub fn new(pm: &ProgressiveMesh, dag: &Dag) -> Result<SelectiveSource> {
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
        let leaf_corners = pm.splits.iter().any(|s| s.joins_previous) || h.has_wedge_splits();
        // The base triangles are the fully refined triangles whose corners lie in three
        // trees, in the same order.
        let base_leaves = leaf_corners.then(|| {
            let roots = h.roots();
            h.leaf_triangles
                .iter()
                .filter(|t| {
                    let r = t.map(|leaf| roots.active_ancestor(&h, leaf));
                    r[0] != r[1] && r[1] != r[2] && r[0] != r[2]
                })
                .copied()
                .collect()
        });
        Ok(SelectiveSource {
            h,
            positions,
            normals,
            info,
            base,
            base_leaves,
        })
    }

    /// How a client of this source places a split's triangles.
    pub fn placement(&self) -> Placement {
        match self.base_leaves {
            Some(_) => Placement::LeafCorners,
            None => Placement::CutVertices,
        }
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
            leaves: self.base_leaves.as_ref().map(|triangles| {
                triangles
                    .iter()
                    .map(|t| t.map(|leaf| self.h.name(leaf)))
                    .collect()
            }),
        }
    }

    pub(super) fn packet(&self, node: u32) -> VsplitPacket {
        let [left, right] = self.h.children(node).expect("a split node");
        let cuts = self
            .h
            .cut_vertices(node)
            .expect("a split node")
            .map(|c| c.map(|c| self.h.name(c)));
        let v = self.h.vertex(right) as usize;
        let leaves = match self.placement() {
            Placement::CutVertices => [None, None],
            Placement::LeafCorners => self
                .h
                .child_leaves(node)
                .expect("a split node")
                .map(|t| t.map(|t| t.map(|leaf| self.h.name(leaf)))),
        };
        VsplitPacket {
            node: self.h.name(node),
            cuts,
            position: self.positions[v],
            normal: self.normals[v],
            children: [self.info[left as usize], self.info[right as usize]],
            run: self.h.run_leader(node).map(|n| self.h.name(n)),
            leaves,
        }
    }

    /// Whether `node` should split for `test` (a leaf of the whole hierarchy never).
    pub(super) fn qrefine(&self, test: &ViewTest, node: u32) -> bool {
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

pub(super) fn view_test(view: &View, tau: f32, criteria: Criteria) -> Result<ViewTest> {
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
    /// The sent front's nodes, in order: what a view's pass visits (KLK §5: each node
    /// of the vertex front), rather than every node of the hierarchy.
    live: BTreeSet<u32>,
    criteria: Criteria,
    cut_vertex_only: bool,
}

impl SelectiveServer {
    /// A session that has sent the base mesh.
    pub fn new(source: &SelectiveSource) -> SelectiveServer {
        SelectiveServer {
            sent: source.h.roots(),
            live: (0..source.h.roots as u32).collect(),
            criteria: Criteria::default(),
            cut_vertex_only: false,
        }
    }

    /// The session of KLK §7's variant, for a client that will not refine on its own
    /// ([`CutVertexClient`](super::CutVertexClient)): each packet names the split's cut
    /// vertices as they stand on the sent front (the client's), not the fundamental
    /// ones (under cut placement), and carries nothing for `qrefine`.
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
        self.refine_at_most(source, view, tau, usize::MAX)
    }

    /// [`SelectiveServer::refine`], stopping once `max` packets are due: no split is
    /// begun after that, but one begun is sent whole with what the partial order forces
    /// for it, so a batch may run a little past `max`. The rest comes with the next
    /// view that asks for it.
    pub fn refine_at_most(
        &mut self,
        source: &SelectiveSource,
        view: &View,
        tau: f32,
        max: usize,
    ) -> Result<Vec<VsplitPacket>> {
        let test = view_test(view, tau, self.criteria)?;
        let mut packets = Vec::new();
        let h = &source.h;
        // Cut vertices as they stand place a split only under cut placement; leaf
        // placement needs the fundamental ones, the third corners of its triangles.
        let as_they_stand = self.cut_vertex_only && source.placement() == Placement::CutVertices;
        // The front's nodes in the order of their numbers, as one pass over every node
        // would meet them: a node's children come after it, so the pass reaches them.
        let mut next = 0;
        while let Some(&n) = self.live.range(next..).next() {
            next = n + 1;
            if packets.len() >= max {
                break;
            }
            if !source.qrefine(&test, n) {
                continue;
            }
            let splits = self.sent.split(h, n)?;
            if as_they_stand {
                // Back to the front before them, then each split's cut vertices as it
                // finds them, split by split.
                for &s in splits.iter().rev() {
                    self.sent.set_split(h, s, false);
                }
            }
            for s in splits {
                let mut p = source.packet(s);
                if as_they_stand {
                    let cuts = h.cut_vertices(s).expect("a split node");
                    p.cuts = cuts.map(|c| c.map(|c| h.name(self.sent.active_ancestor(h, c))));
                    self.sent.set_split(h, s, true);
                }
                if self.cut_vertex_only {
                    p.children = [None, None];
                }
                let [l, r] = h.children(s).expect("a split node");
                self.live.remove(&s);
                self.live.extend([l, r]);
                packets.push(p);
            }
        }
        Ok(packets)
    }

    /// The session of a client that resumes on a new connection holding `leaves`: the
    /// nodes of its partial hierarchy that it was not sent a split of (KLK §5's leaf
    /// ids), which are the front the old session had sent. An `Err` naming the node
    /// when they are not a front of this hierarchy.
    pub fn resume(&self, source: &SelectiveSource, leaves: &[NodeName]) -> Result<SelectiveServer> {
        let nodes = leaves
            .iter()
            .map(|name| {
                source
                    .h
                    .find(name)
                    .ok_or_else(|| Error::Invalid(format!("node {name:?} is not in the hierarchy")))
            })
            .collect::<Result<Vec<u32>>>()?;
        Ok(SelectiveServer {
            sent: Front::from_active(&source.h, &nodes)?,
            live: nodes.into_iter().collect(),
            ..self.clone()
        })
    }

    /// The session's own bytes: its front's tags and nodes (the source is shared).
    pub fn memory(&self) -> usize {
        self.sent.active.capacity() + 40 * self.live.len()
    }

    /// How many nodes the sent front has.
    pub fn sent_nodes(&self) -> usize {
        self.live.len()
    }

    /// The mesh of the front sent so far, its corners as node names: what a
    /// [`CutVertexClient`](super::CutVertexClient) holds.
    pub fn sent_triangles(&self, source: &SelectiveSource) -> Vec<[NodeName; 3]> {
        self.sent
            .triangles(&source.h)
            .iter()
            .map(|t| t.map(|n| source.h.name(n)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::dag::DagConstruction;
    use crate::lod::selective::testing::{canonical, random_view};
    use crate::lod::selective::{CutVertexClient, SelectiveClient};
    use rand::{Rng, SeedableRng};

    /// Over `views` random views, a client streamed from a server holds, after each,
    /// the mesh a local refiner makes, triangle for triangle; each split is sent once.
    fn streams_as_a_local_refiner_refines(mesh: &crate::scene::Mesh, seed: u64, views: usize) {
        let pm = ProgressiveMesh::build(mesh).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        let source = SelectiveSource::new(&pm, &dag).unwrap();
        let h = source.hierarchy();
        let mut server = SelectiveServer::new(&source);
        let mut client = SelectiveClient::new(source.base());
        let mut local = h.roots();
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let (mut asked, mut sent, mut collapsed) = (0, 0, 0);
        for step in 0..views {
            let view = random_view(&mut rng, mesh);
            let tau = rng.gen_range(0.0005..0.01);
            let before = local.clone();
            source.select(&mut local, &view, tau).unwrap();
            collapsed +=
                usize::from((0..h.len() as u32).any(|n| {
                    before.is_active(n) && !local.is_active(n) && h.children(n).is_none()
                }));
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
            // What it draws: the same triangles over the nodes' vertices.
            let drawn = client.mesh();
            drawn.validate().unwrap();
            let at = |m: &crate::scene::Mesh, t: &[u32]| {
                let mut t: Vec<[[u32; 3]; 3]> = t
                    .chunks(3)
                    .map(|c| {
                        let mut p = [0, 1, 2].map(|k| m.positions[c[k] as usize].map(f32::to_bits));
                        // The same triangle whatever corner it starts at.
                        let first = (0..3).min_by_key(|&k| p[k]).unwrap();
                        p.rotate_left(first);
                        p
                    })
                    .collect();
                t.sort_unstable();
                t
            };
            let reference = crate::scene::Mesh {
                positions: source.positions.clone(),
                normals: source.normals.clone(),
                indices: local
                    .triangles(h)
                    .iter()
                    .flat_map(|t| t.map(|n| h.vertex(n)))
                    .collect(),
            };
            assert_eq!(
                at(&drawn, &drawn.indices),
                at(&reference, &reference.indices),
                "step {step}: what is drawn"
            );
        }
        assert!(asked > 3 && sent > 100, "asked {asked}, sent {sent}");
        assert!(
            collapsed > 0,
            "no view coarsened what an earlier one refined"
        );
        // Each split is sent once: never more than the hierarchy has.
        assert_eq!(client.nodes(), h.roots + 2 * sent);
        assert!(client.nodes() <= h.len());
    }

    #[test]
    fn a_streamed_mesh_equals_a_local_refiners_triangle_for_triangle() {
        let pm = ProgressiveMesh::build(&crate::lod::bumpy_torus(1500)).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        let source = SelectiveSource::new(&pm, &dag).unwrap();
        assert_eq!(source.placement(), Placement::CutVertices);
        streams_as_a_local_refiner_refines(&crate::lod::bumpy_torus(1500), 5, 1_000);
    }

    /// A flat-shaded building: every corner and crease a seam, so its splits come in
    /// runs, some adding no triangle. Its triangles are placed by their leaves.
    #[test]
    fn a_mesh_of_crease_runs_streams_by_its_leaves_as_a_local_refiner_refines() {
        let building = crate::lod::fixtures::building();
        let pm = ProgressiveMesh::build(&building).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        let source = SelectiveSource::new(&pm, &dag).unwrap();
        assert_eq!(source.placement(), Placement::LeafCorners);
        assert!(pm.splits.iter().any(|s| s.joins_previous));
        streams_as_a_local_refiner_refines(&building, 7, 1_000);
    }

    #[test]
    fn a_bad_tau_is_refused_by_name() {
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

    /// KLK §7: after each view the client holds exactly the sent front's mesh, under
    /// both placements.
    #[test]
    fn a_cut_vertex_only_client_holds_the_sent_front_without_qrefines_data() {
        let meshes = [
            crate::lod::bumpy_torus(1500),
            crate::lod::fixtures::building(),
        ];
        for (seed, mesh) in meshes.iter().enumerate() {
            let pm = ProgressiveMesh::build(mesh).unwrap();
            let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
            let source = SelectiveSource::new(&pm, &dag).unwrap();
            let mut server = SelectiveServer::new(&source).cut_vertex_only();
            let mut full = SelectiveServer::new(&source);
            let mut client = CutVertexClient::new(source.base());
            let mut rng = rand::rngs::StdRng::seed_from_u64(6 + seed as u64);
            let mut sent = 0;
            for step in 0..60 {
                let view = random_view(&mut rng, mesh);
                let packets = server.refine(&source, &view, 0.002).unwrap();
                let with_info = full.refine(&source, &view, 0.002).unwrap();
                // The same splits, in the same order; nothing for qrefine.
                let nodes =
                    |p: &[VsplitPacket]| p.iter().map(|p| p.node.clone()).collect::<Vec<_>>();
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
}
