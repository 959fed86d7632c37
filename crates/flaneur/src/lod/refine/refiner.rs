//! Selective refinement, frame by frame — Zheng 2007 ch. 4: the DAG's fronts (§4.2,
//! `fronts`), the error criteria (§3.4, `criteria`), the traversal manager and its three
//! traversals (§4.3–4.4, `traversal`), and the selective mesh in compact arrays (§4.5,
//! `mesh_update`), wired into one [`Refiner`].
//!
//! A frame is the thesis's client-server split run in one place: the traversal reads
//! only the DAG and the fronts and yields a list of node operators (the server's part,
//! timed as the traversal), which are then applied to the compact arrays (the client's
//! part, timed as the update). The arrays' changed ranges come back with the frame's
//! figures, for a renderer to upload.
//!
//! When an operator does not apply (a progressive mesh that is not the DAG's), the
//! frame is undone — arrays and fronts — and the error returned: a refiner is never
//! left with fronts that disagree with its mesh.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec3;

use super::criteria::{Criteria, NodeGeometry, View, ViewTest};
use super::fronts::{Fronts, Pass};
use super::mesh_update::{CompactMesh, MeshChanges};
use super::traversal::{manage, Context, FrontNode, Op, PassStats, Scratch, Traversal};
use crate::error::{Error, Result};
use crate::lod::dag::Dag;
use crate::lod::pm::ProgressiveMesh;

/// The screen-space error threshold of the thesis's experiments: 0.1 % of the viewport
/// (Zheng 2007 §4.6.1).
pub const THESIS_TAU: f32 = 0.001;
/// The bound on work per pass of the thesis's experiments (§4.6.1).
pub const THESIS_MAX_WORK: usize = 500;
/// The triangle budget of the thesis's experiments (§4.6.1).
pub const THESIS_BUDGET: usize = 60_000;

/// How a frame refines: which traversal, the fidelity τ, the triangle budget and the
/// bound N on work per pass (Zheng 2007 §4.3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineParams {
    /// The traversal algorithm.
    pub traversal: Traversal,
    /// The screen-space error threshold τ, a fraction of the viewport (> 0): a node
    /// splits only when its error projects to at least τ of the view.
    pub tau: f32,
    /// The triangle budget: `Some` for budget mode, in which a frame never takes the
    /// mesh above it (a mesh already above it does not grow); `None` for fidelity
    /// alone (the thesis's FREE-MODE).
    pub budget: Option<usize>,
    /// N (≥ 1): per pass, the most nodes split or collapsed (priority and linear
    /// traversals), or the most front nodes evaluated (constant-time traversal).
    /// `usize::MAX` for no bound.
    pub max_work: usize,
    /// The culling criteria besides the screen-space error.
    pub criteria: Criteria,
}

impl RefineParams {
    /// The settings of the thesis's experiments (§4.6.1) for `traversal`: τ = 0.1 % of
    /// the viewport, N = 500, a budget of 60,000 triangles, both culling criteria.
    pub fn thesis(traversal: Traversal) -> RefineParams {
        RefineParams {
            traversal,
            tau: THESIS_TAU,
            budget: Some(THESIS_BUDGET),
            max_work: THESIS_MAX_WORK,
            criteria: Criteria::default(),
        }
    }

    /// Checks τ and N.
    pub fn validate(&self) -> Result<()> {
        if !(self.tau.is_finite() && self.tau > 0.0) {
            return Err(Error::Invalid(format!(
                "refinement: τ = {} must be a positive fraction of the viewport",
                self.tau
            )));
        }
        if self.max_work == 0 {
            return Err(Error::Invalid(
                "refinement: a bound N of 0 allows no work; use usize::MAX for none".into(),
            ));
        }
        Ok(())
    }
}

impl Default for RefineParams {
    /// [`RefineParams::thesis`] with the priority-oriented traversal.
    fn default() -> RefineParams {
        RefineParams::thesis(Traversal::Priority)
    }
}

/// One operator of a frame: a DAG node split or collapsed, which applies or undoes the
/// node's run of vertex splits ([`Dag::splits`]); what a server streams to a client
/// that holds no hierarchy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeOperator {
    /// The DAG node.
    pub node: u32,
    /// Split (its vertex splits in order) or collapse (them undone in reverse).
    pub split: bool,
}

/// One frame's figures (a row of Zheng 2007 Table 4.1, and Table 4.3's front sizes).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameStats {
    /// Time to traverse the fronts and choose the operators.
    pub traversal: Duration,
    /// Time to apply the operators to the compact arrays and gather the changes.
    pub update: Duration,
    /// The collapse pass.
    pub collapse: PassStats,
    /// The split pass.
    pub split: PassStats,
    /// Triangles after the frame.
    pub triangles: usize,
    /// |F_s| after the frame.
    pub split_front: usize,
    /// |F_c| after the frame.
    pub collapse_front: usize,
}

impl FrameStats {
    /// Nodes split or collapsed: the thesis's "Num. Updates".
    pub fn updates(&self) -> usize {
        self.collapse.applied + self.split.applied
    }

    /// Front nodes evaluated in both passes.
    pub fn evaluated(&self) -> usize {
        self.collapse.evaluated + self.split.evaluated
    }

    /// |F_s| + |F_c|: the thesis's "Front nodes" (Table 4.3).
    pub fn front_nodes(&self) -> usize {
        self.split_front + self.collapse_front
    }
}

/// What [`Refiner::refine`] returns for a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameReport {
    /// The frame's figures.
    pub stats: FrameStats,
    /// The array ranges the frame changed (the whole base mesh on the first frame).
    pub changes: MeshChanges,
}

/// View-dependent refinement of one progressive mesh through its DAG (Zheng 2007
/// ch. 4): the fronts, and the selective mesh in compact arrays, moved frame by frame.
///
/// ```
/// use flaneur::lod::{Dag, DagConstruction, ProgressiveMesh, RefineParams, Refiner,
///                    Traversal, View};
/// use glam::Vec3;
///
/// let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
/// let dag = Dag::build(&pm, DagConstruction::MiniRedundant)?;
/// let mut refiner = Refiner::new(&pm, &dag)?;
///
/// // The thesis's settings but a budget for the bunny; the eye two sizes away.
/// let params = RefineParams { budget: Some(2_000), ..RefineParams::thesis(Traversal::Linear) };
/// let (lo, hi) = flaneur::scene::bunny().bounds();
/// let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
/// let eye = (lo + hi) * 0.5 + Vec3::Z * 2.0 * (hi - lo).length();
/// let view = View::new(eye, (lo + hi) * 0.5 - eye, 60f32.to_radians())?;
/// for _ in 0..10 {
///     let frame = refiner.refine(&view, &params)?;
///     assert!(frame.stats.triangles <= 2_000);
///     // What a renderer re-uploads: a few ranges of the compact arrays.
///     for range in &frame.changes.indices {
///         let _changed = &refiner.mesh().indices()[range.start as usize..range.end as usize];
///     }
/// }
/// assert!(refiner.mesh().triangle_count() > pm.base.triangle_count());
///
/// // Bad input is an error, not a panic.
/// let nan = View { eye: Vec3::NAN, ..view };
/// assert!(refiner.refine(&nan, &params).is_err());
/// assert!(refiner.refine(&view, &RefineParams { tau: 0.0, ..params }).is_err());
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct Refiner<'a> {
    pm: Held<'a, ProgressiveMesh>,
    dag: Held<'a, Dag>,
    /// Each DAG node's record, read-only: shared by the refiners made with
    /// [`Refiner::fresh`] (a server's sessions over one landmark).
    nodes: Arc<[FrontNode]>,
    fronts: Fronts,
    mesh: CompactMesh,
    ops: Vec<Op>,
    scratch: Scratch,
}

impl<'a> Refiner<'a> {
    /// A refiner at the base mesh: nothing split, F_s the DAG's roots. An `Err` when
    /// `dag` was not built from `pm` (its split count differs) or `pm`'s base is not a
    /// valid mesh.
    pub fn new(pm: &'a ProgressiveMesh, dag: &'a Dag) -> Result<Refiner<'a>> {
        Refiner::holding(Held::Borrowed(pm), Held::Borrowed(dag))
    }

    /// Another refiner of the same progressive mesh and DAG, at the base mesh, sharing
    /// this one's read-only node records rather than building its own: what a server
    /// makes for each client of one landmark.
    ///
    /// ```
    /// use flaneur::lod::{Dag, DagConstruction, ProgressiveMesh, Refiner};
    /// let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
    /// let dag = Dag::build(&pm, DagConstruction::MiniRedundant)?;
    /// let first = Refiner::new(&pm, &dag)?;
    /// let second = first.fresh()?;
    /// assert_eq!(second.mesh().triangle_count(), pm.base.triangle_count());
    /// # Ok::<(), flaneur::Error>(())
    /// ```
    pub fn fresh(&self) -> Result<Refiner<'a>> {
        Ok(Refiner {
            pm: self.pm.clone(),
            dag: self.dag.clone(),
            nodes: self.nodes.clone(),
            fronts: Fronts::new(&self.dag),
            mesh: CompactMesh::new(&self.pm)?,
            ops: Vec::new(),
            scratch: Scratch::default(),
        })
    }

    fn holding(pm: Held<'a, ProgressiveMesh>, dag: Held<'a, Dag>) -> Result<Refiner<'a>> {
        let (p, d) = (&*pm, &*dag);
        let nodes = front_nodes(p, d)?.into();
        let mesh = CompactMesh::new(p)?;
        let fronts = Fronts::new(d);
        Ok(Refiner {
            pm,
            dag,
            nodes,
            fronts,
            mesh,
            ops: Vec::new(),
            scratch: Scratch::default(),
        })
    }
}

impl Refiner<'static> {
    /// A refiner that shares its progressive mesh and DAG rather than borrowing them,
    /// for one that outlives the code that loaded them (a walk's refined objects).
    pub fn shared(pm: Arc<ProgressiveMesh>, dag: Arc<Dag>) -> Result<Refiner<'static>> {
        Refiner::holding(Held::Shared(pm), Held::Shared(dag))
    }
}

/// How a refiner holds its progressive mesh and DAG.
#[derive(Clone, Debug)]
enum Held<'a, T> {
    Borrowed(&'a T),
    Shared(Arc<T>),
}

impl<T> std::ops::Deref for Held<'_, T> {
    type Target = T;

    fn deref(&self) -> &T {
        match self {
            Held::Borrowed(t) => t,
            Held::Shared(t) => t,
        }
    }
}

/// Each DAG node's geometry and the triangles its splits add. An `Err` when `dag` was
/// not built from `pm` (its split count differs).
fn front_nodes(pm: &ProgressiveMesh, dag: &Dag) -> Result<Vec<FrontNode>> {
    if pm.splits.len() != dag.split_count() {
        return Err(Error::Invalid(format!(
            "refinement: a DAG of {} splits with a progressive mesh of {}",
            dag.split_count(),
            pm.splits.len()
        )));
    }
    let mut nodes = Vec::with_capacity(dag.node_count());
    for k in 0..dag.node_count() as u32 {
        let run = dag.splits(k);
        // The sphere's centre and the cone's axis are the run's first v_c (dag_attrs).
        let head = &pm.splits[run.start];
        let a = dag.attrs(k);
        nodes.push(FrontNode {
            geometry: NodeGeometry {
                centre: Vec3::from(head.position),
                radius: a.radius,
                axis: Vec3::from(head.normal).normalize_or_zero(),
                cone_sin: a.cone_sin,
                error: a.error,
            },
            added: pm.splits[run]
                .iter()
                .map(|s| s.added_triangles() as u32)
                .sum(),
        });
    }
    Ok(nodes)
}

impl Refiner<'_> {
    /// Runs one frame for `view`: the traversal, then the mesh update. An `Err` on an
    /// invalid view or parameters, or when an operator does not apply; the fronts and
    /// the mesh are then as they were (the arrays perhaps laid out otherwise).
    pub fn refine(&mut self, view: &View, params: &RefineParams) -> Result<FrameReport> {
        view.validate()?;
        params.validate()?;
        let ctx = Context {
            dag: &self.dag,
            nodes: &self.nodes,
            test: ViewTest::new(view, params.tau, params.criteria),
            traversal: params.traversal,
            max_work: params.max_work,
            budget: params.budget,
        };
        self.ops.clear();
        let started = Instant::now();
        let (collapse, split) = manage(
            &ctx,
            &mut self.fronts,
            self.mesh.triangle_count(),
            &mut self.ops,
            &mut self.scratch,
        );
        let traversal = started.elapsed();

        let started = Instant::now();
        let mut failed = None;
        for (i, op) in self.ops.iter().enumerate() {
            let applied = match op.pass {
                Pass::Split => self.mesh.split_node(&self.dag, &self.pm, op.node),
                Pass::Collapse => self.mesh.collapse_node(&self.dag, &self.pm, op.node),
            };
            if let Err(e) = applied {
                failed = Some((i, e));
                break;
            }
        }
        if let Some((i, e)) = failed {
            self.undo(i);
            return Err(e);
        }
        let changes = self.mesh.take_changes();
        let update = started.elapsed();
        Ok(FrameReport {
            stats: FrameStats {
                traversal,
                update,
                collapse,
                split,
                triangles: self.mesh.triangle_count(),
                split_front: self.fronts.split_front_len(),
                collapse_front: self.fronts.collapse_front_len(),
            },
            changes,
        })
    }

    /// Splits exactly the nodes of `split`, parents before children, on a refiner at
    /// its base mesh: the state of another refiner of the same DAG whose split nodes
    /// these are, as a stream server resumes a client's session from the nodes the
    /// client holds. An `Err`, the refiner left at its base mesh, when it has split
    /// anything already, when a node is out of range or named twice, or when a node's
    /// parent is not among them (no frame could have split it).
    ///
    /// The fronts' queues are in the order this restoring made them, not the order the
    /// other refiner's frames did: the linear and constant-time traversals, which resume
    /// where their queues stopped, may then choose otherwise than it would have.
    ///
    /// ```
    /// use flaneur::lod::{Dag, DagConstruction, ProgressiveMesh, RefineParams, Refiner, View};
    /// use glam::Vec3;
    /// let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
    /// let dag = Dag::build(&pm, DagConstruction::MiniRedundant)?;
    /// let mut first = Refiner::new(&pm, &dag)?;
    /// let view = View::new(Vec3::new(0.0, 0.1, 0.4), Vec3::new(0.0, 0.0, -1.0), 1.0)?;
    /// first.refine(&view, &RefineParams::default())?;
    /// let split: Vec<u32> = (0..dag.node_count() as u32)
    ///     .filter(|&n| first.fronts().is_split(n))
    ///     .collect();
    /// let mut second = first.fresh()?;
    /// second.restore(&split)?;
    /// assert_eq!(second.mesh().shared_with(first.mesh()), 1.0);
    /// # Ok::<(), flaneur::Error>(())
    /// ```
    pub fn restore(&mut self, split: &[u32]) -> Result<()> {
        if self.fronts.split_count() > 0 {
            return Err(Error::Invalid(format!(
                "restore: this refiner has {} nodes split already; restore a fresh one",
                self.fronts.split_count()
            )));
        }
        let count = self.dag.node_count();
        let mut wanted = vec![false; count];
        for &node in split {
            let slot = wanted.get_mut(node as usize).ok_or_else(|| {
                Error::Invalid(format!(
                    "restore: node {node}, past the DAG's {count} nodes"
                ))
            })?;
            if std::mem::replace(slot, true) {
                return Err(Error::Invalid(format!("restore: node {node} named twice")));
            }
        }
        let restored = self.split_wanted(&wanted);
        let unreached = split.len() - self.fronts.split_count();
        if restored.is_err() || unreached > 0 {
            self.fronts = Fronts::new(&self.dag);
            self.mesh = CompactMesh::new(&self.pm)?;
            restored?;
            // The nodes left collapsed hang below one whose parent was not named.
            let (node, parent) = split
                .iter()
                .find_map(|&n| {
                    let p = self.dag.parents(n).iter().find(|&&p| !wanted[p as usize])?;
                    Some((n, *p))
                })
                .expect("an unreached node below one whose parent is not named");
            return Err(Error::Invalid(format!(
                "restore: node {node} is named split but its parent {parent} is not"
            )));
        }
        Ok(())
    }

    /// Splits the nodes `wanted` marks, each once its parents are split; those below a
    /// node not marked stay collapsed.
    fn split_wanted(&mut self, wanted: &[bool]) -> Result<()> {
        let mut ready: Vec<u32> = self
            .dag
            .roots()
            .iter()
            .copied()
            .filter(|&r| wanted[r as usize])
            .collect();
        while let Some(node) = ready.pop() {
            self.mesh.split_node(&self.dag, &self.pm, node)?;
            self.fronts.split(&self.dag, node);
            for &c in self.dag.children(node) {
                if wanted[c as usize] && self.fronts.in_split_front(c) {
                    ready.push(c);
                }
            }
        }
        Ok(())
    }

    /// Undoes the frame whose first `applied` operators reached the mesh.
    fn undo(&mut self, applied: usize) {
        for op in self.ops[..applied].iter().rev() {
            // Each inverse undoes an operator that just applied, so it applies.
            let _ = match op.pass {
                Pass::Split => self.mesh.collapse_node(&self.dag, &self.pm, op.node),
                Pass::Collapse => self.mesh.split_node(&self.dag, &self.pm, op.node),
            };
        }
        for op in self.ops.iter().rev() {
            self.fronts.undo(&self.dag, op.pass, op.node);
        }
        self.ops.clear();
    }

    #[cfg(test)]
    pub(crate) fn node_geometry(&self, node: u32) -> NodeGeometry {
        self.nodes[node as usize].geometry
    }

    /// The operators the last frame applied, in the order it applied them (its
    /// collapses, then its splits); none after a frame that failed.
    pub fn operators(&self) -> impl ExactSizeIterator<Item = NodeOperator> + '_ {
        self.ops.iter().map(|op| NodeOperator {
            node: op.node,
            split: op.pass == Pass::Split,
        })
    }

    /// Bytes this refiner holds of its own: the selective mesh's arrays and maps, the
    /// fronts and the frame's operators. What it may share with other refiners is not
    /// counted: the progressive mesh, the DAG, and each DAG node's record
    /// ([`Refiner::node_records_memory`]).
    pub fn memory(&self) -> usize {
        let m = self.mesh.memory();
        m.render + m.aux + self.fronts.memory() + self.ops.capacity() * std::mem::size_of::<Op>()
    }

    /// Bytes of the DAG nodes' records, which the refiners made with [`Refiner::fresh`]
    /// share.
    pub fn node_records_memory(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<FrontNode>()
    }

    /// The selective mesh.
    pub fn mesh(&self) -> &CompactMesh {
        &self.mesh
    }

    /// The fronts and every node's status.
    pub fn fronts(&self) -> &Fronts {
        &self.fronts
    }

    /// The progressive mesh.
    pub fn progressive_mesh(&self) -> &ProgressiveMesh {
        &self.pm
    }

    /// The DAG.
    pub fn dag(&self) -> &Dag {
        &self.dag
    }
}
