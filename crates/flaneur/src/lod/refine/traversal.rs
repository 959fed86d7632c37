//! The traversal of the DAG's fronts — Zheng 2007 §4.3 (MANAGE-TRAVERSAL, Fig. 4.6)
//! and §4.4 (the priority-oriented, linear and constant-time traversals, Figs. 4.7–4.9).
//!
//! A frame runs the collapse pass over F_c first, then the split pass over F_s. Both
//! passes are bounded by N: the operators applied, for the priority-oriented and the
//! linear traversal; the nodes evaluated, for the constant-time one (§4.4.3). In budget
//! mode the split pass may add no more triangles than the budget leaves after the
//! collapse pass (§4.3, counting triangles rather than operators, as the thesis advises
//! for meshes whose operators add one, two or — for a run — more triangles).
//!
//! The traversal decides and records; it does not touch the mesh (the DAG makes the
//! selection independent of the selective mesh, §3.6): its result is a list of node
//! operators in a legal order, which `mesh_update` applies.
//!
//! Choices the thesis leaves open, made here:
//! - Budget mode (Fig. 4.6 gives the split pass the collapses' count) takes the room
//!   under the budget into account as well: the split pass may add
//!   `budget − (triangles after the collapse pass)`, which is the collapses' freed
//!   triangles when the mesh is at its budget, and lets a mesh below it grow — the
//!   switch between FREE-MODE and BUDGET-MODE that the thesis leaves to the client. A
//!   mesh above its budget (the budget was lowered) does not grow; the fidelity
//!   collapses bring it down.
//! - A split that needs more triangles than are left ends the pass of the
//!   priority-oriented and linear traversals ("stops when further refinement operations
//!   would exceed the triangle budget"); the linear traversal keeps that node at the
//!   head of its queue for the next frame. The constant-time traversal's N counts the
//!   nodes evaluated "no matter whether this node will be selected to apply or not"
//!   (§4.4.3), and a split the budget has no room for is one NEED-APPLY declines: it
//!   goes to the back of the queue and the pass goes on evaluating. So a frame at its
//!   budget does the work of one still refining, which is what keeps the traversal's
//!   time flat (ending the pass there spread the bench orbit's frame times over 3.6–7×
//!   where the budget binds).
//! - The priority-oriented traversal queues only the nodes that need an operator: the
//!   priority orders every such node before every node that does not (module comment
//!   of `criteria`), so Fig. 4.7's loop, which stops at the first node that needs none,
//!   pops exactly these nodes in the same order.
//! - The linear traversal evaluates each front member once a pass and stops when all
//!   have been (Fig. 4.8, line 11, and its O(n) bound): the view is the same for the
//!   whole frame, so evaluating a member again would change nothing. The constant-time
//!   traversal, bounded by its evaluations, stops when it has evaluated the whole front
//!   since its last operator.
//! - Priority ties break on the lower node number, so a frame is deterministic.

use std::collections::BinaryHeap;

use super::criteria::{Evaluation, NodeGeometry, ViewTest};
use super::fronts::{Fronts, Pass};
use super::prefetch_hint::{self, prefetch};
use crate::lod::dag::Dag;

/// The traversal algorithm (Zheng 2007 §4.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Traversal {
    /// Every front node evaluated into a priority queue; the largest errors split
    /// first, the smallest collapse first (§4.4.1, Fig. 4.7). N bounds the operators.
    Priority,
    /// The fronts as FIFO queues kept between frames (§4.4.2, Fig. 4.8). N bounds the
    /// operators.
    Linear,
    /// As the linear traversal, but N bounds the nodes evaluated (§4.4.3, Fig. 4.9).
    ConstantTime,
}

impl Traversal {
    /// All three, in the thesis's order.
    pub const ALL: [Traversal; 3] = [
        Traversal::Priority,
        Traversal::Linear,
        Traversal::ConstantTime,
    ];

    /// A short name: "priority", "linear" or "constant".
    pub fn name(self) -> &'static str {
        match self {
            Traversal::Priority => "priority",
            Traversal::Linear => "linear",
            Traversal::ConstantTime => "constant",
        }
    }
}

/// What one pass of a traversal did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PassStats {
    /// Front nodes evaluated (ERROR-EVALUATE): the work the constant-time traversal's
    /// N bounds.
    pub evaluated: usize,
    /// Nodes split (split pass) or collapsed (collapse pass).
    pub applied: usize,
    /// Triangles those nodes added or removed.
    pub triangles: usize,
}

/// One node's operator, in the order a frame applies them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Op {
    pub node: u32,
    pub pass: Pass,
}

/// What a pass reads of one DAG node: its geometry, which evaluating it reads, and the
/// triangles its splits add, which applying it reads. One record, so that applying a
/// node just evaluated takes no further cache miss for its size.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FrontNode {
    pub geometry: NodeGeometry,
    pub added: u32,
}

/// What the passes read: the DAG, every node's record, the frame's view test, and the
/// traversal with its bounds.
pub(crate) struct Context<'a> {
    pub dag: &'a Dag,
    pub nodes: &'a [FrontNode],
    pub test: ViewTest,
    pub traversal: Traversal,
    /// N.
    pub max_work: usize,
    pub budget: Option<usize>,
}

impl Context<'_> {
    /// Prefetches what evaluating the node [`prefetch_hint::DISTANCE`] places down
    /// `pass`'s queue reads: its geometry and its status.
    fn prefetch_upcoming(&self, fronts: &Fronts, pass: Pass) {
        if let Some(node) = fronts.upcoming(pass, prefetch_hint::DISTANCE) {
            prefetch(&self.nodes[node as usize]);
            fronts.prefetch_status(node);
        }
    }

    fn evaluate(&self, node: u32) -> Evaluation {
        self.test.evaluate(&self.nodes[node as usize].geometry)
    }

    fn needs(&self, pass: Pass, node: u32) -> (bool, Evaluation) {
        let e = self.evaluate(node);
        let needs = match pass {
            Pass::Split => e.needs_split,
            Pass::Collapse => !e.needs_split,
        };
        (needs, e)
    }
}

/// Buffers a traversal reuses from frame to frame.
#[derive(Clone, Debug, Default)]
pub(crate) struct Scratch {
    /// The priority-oriented traversal's heap.
    heap: Vec<u64>,
    /// The linear traversal's marks: a node evaluated in the current pass holds `stamp`.
    seen: Vec<u32>,
    stamp: u32,
}

impl Scratch {
    /// Starts a pass over a DAG of `nodes` nodes: no node seen yet.
    fn begin(&mut self, nodes: usize) {
        self.seen.resize(nodes, 0);
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.seen.fill(0);
            self.stamp = 1;
        }
    }

    /// Marks `node` seen in this pass; whether it already was.
    fn mark(&mut self, node: u32) -> bool {
        std::mem::replace(&mut self.seen[node as usize], self.stamp) == self.stamp
    }
}

/// MANAGE-TRAVERSAL (Fig. 4.6) for a mesh of `triangles`: the collapse pass, then the
/// split pass, each bounded by N; in budget mode the split pass adds at most what the
/// budget leaves. Appends the operators to `ops`; `scratch` is kept by the caller
/// between frames.
pub(crate) fn manage(
    ctx: &Context,
    fronts: &mut Fronts,
    triangles: usize,
    ops: &mut Vec<Op>,
    scratch: &mut Scratch,
) -> (PassStats, PassStats) {
    let collapse = traverse(ctx, fronts, Pass::Collapse, usize::MAX, ops, scratch);
    let after = triangles.saturating_sub(collapse.triangles);
    let room = ctx.budget.map_or(usize::MAX, |b| b.saturating_sub(after));
    let split = traverse(ctx, fronts, Pass::Split, room, ops, scratch);
    (collapse, split)
}

/// One pass, adding at most `room` triangles.
fn traverse(
    ctx: &Context,
    fronts: &mut Fronts,
    pass: Pass,
    room: usize,
    ops: &mut Vec<Op>,
    scratch: &mut Scratch,
) -> PassStats {
    match ctx.traversal {
        Traversal::Priority => priority_pass(ctx, fronts, pass, room, ops, &mut scratch.heap),
        Traversal::Linear => linear_pass(ctx, fronts, pass, room, ops, scratch),
        Traversal::ConstantTime => constant_time_pass(ctx, fronts, pass, room, ops),
    }
}

/// A heap entry: the priority as an order-preserving integer (descending for splits,
/// ascending for collapses, since the heap pops its largest), then the node, lower
/// numbers first.
fn heap_key(pass: Pass, priority: f32, node: u32) -> u64 {
    let p = match pass {
        Pass::Split => priority,
        Pass::Collapse => -priority,
    };
    let bits = p.to_bits();
    let ordered = if bits & 0x8000_0000 != 0 {
        !bits
    } else {
        bits | 0x8000_0000
    };
    (ordered as u64) << 32 | !node as u64
}

fn node_of(key: u64) -> u32 {
    !(key as u32)
}

/// The nodes `node`'s operator may have brought into `pass`'s front: its children
/// after a split, its parents after a collapse.
fn neighbours(dag: &Dag, pass: Pass, node: u32) -> &[u32] {
    match pass {
        Pass::Split => dag.children(node),
        Pass::Collapse => dag.parents(node),
    }
}

/// Applies `node`'s operator and records it in `ops` and `stats`, unless it is a split
/// that needs more triangles than `room` has left: then `false`, and nothing changes.
fn apply_within(
    ctx: &Context,
    fronts: &mut Fronts,
    pass: Pass,
    node: u32,
    room: usize,
    ops: &mut Vec<Op>,
    stats: &mut PassStats,
) -> bool {
    let t = ctx.nodes[node as usize].added as usize;
    if pass == Pass::Split && t > room - stats.triangles {
        return false;
    }
    fronts.apply(ctx.dag, pass, node);
    ops.push(Op { node, pass });
    stats.applied += 1;
    stats.triangles += t;
    true
}

/// PRIORITY-ORIENTED-TRAVERSAL (Fig. 4.7).
fn priority_pass(
    ctx: &Context,
    fronts: &mut Fronts,
    pass: Pass,
    room: usize,
    ops: &mut Vec<Op>,
    scratch: &mut Vec<u64>,
) -> PassStats {
    let mut stats = PassStats::default();
    scratch.clear();
    let front = fronts.compact(pass);
    for (i, &node) in front.iter().enumerate() {
        if let Some(&next) = front.get(i + prefetch_hint::DISTANCE) {
            prefetch(&ctx.nodes[next as usize]);
        }
        stats.evaluated += 1;
        let (needs, e) = ctx.needs(pass, node);
        if needs {
            scratch.push(heap_key(pass, e.priority, node));
        }
    }
    let mut heap = BinaryHeap::from(std::mem::take(scratch));
    while stats.applied < ctx.max_work {
        let Some(key) = heap.pop() else { break };
        let node = node_of(key);
        // Each node enters the queue once per pass, when it joins the front, and leaves
        // the front only by its own operator: never stale, but cheap to be sure.
        if !fronts.in_front(pass, node) {
            continue;
        }
        if !apply_within(ctx, fronts, pass, node, room, ops, &mut stats) {
            break;
        }
        for &m in neighbours(ctx.dag, pass, node) {
            if fronts.in_front(pass, m) {
                stats.evaluated += 1;
                let (needs, e) = ctx.needs(pass, m);
                if needs {
                    heap.push(heap_key(pass, e.priority, m));
                }
            }
        }
    }
    *scratch = heap.into_vec();
    stats
}

/// CONSTANT-TIME-TRAVERSAL (Fig. 4.9): the front in FIFO order until N evaluations.
fn constant_time_pass(
    ctx: &Context,
    fronts: &mut Fronts,
    pass: Pass,
    room: usize,
    ops: &mut Vec<Op>,
) -> PassStats {
    let mut stats = PassStats::default();
    // Nodes evaluated since the last operator.
    let mut idle = 0;
    while stats.evaluated < ctx.max_work && idle < fronts.front_len(pass) {
        ctx.prefetch_upcoming(fronts, pass);
        let Some(node) = fronts.pop(pass) else { break };
        stats.evaluated += 1;
        let (needs, _) = ctx.needs(pass, node);
        if !needs {
            fronts.requeue(pass, node, true);
            idle += 1;
            continue;
        }
        if !apply_within(ctx, fronts, pass, node, room, ops, &mut stats) {
            fronts.requeue(pass, node, true);
            idle += 1;
            continue;
        }
        idle = 0;
    }
    stats
}

/// LINEAR-TRAVERSAL (Fig. 4.8): the front in FIFO order until N operators, each
/// member evaluated once a pass. The view is fixed for the pass, so a member found
/// needing nothing needs nothing until the next frame: it is passed over (kept in its
/// place in the queue) rather than evaluated again, and the pass ends when every
/// member, those the pass brought into the front included, has been evaluated — line
/// 11's "all the front nodes have been traversed", and the thesis's O(n) bound.
fn linear_pass(
    ctx: &Context,
    fronts: &mut Fronts,
    pass: Pass,
    room: usize,
    ops: &mut Vec<Op>,
    scratch: &mut Scratch,
) -> PassStats {
    scratch.begin(ctx.dag.node_count());
    let mut stats = PassStats::default();
    // Members not yet evaluated this pass.
    let mut unseen = fronts.front_len(pass);
    // Members passed over since the last evaluation: a guard against a miscount.
    let mut skipped = 0;
    while stats.applied < ctx.max_work && unseen > 0 && skipped <= fronts.front_len(pass) {
        ctx.prefetch_upcoming(fronts, pass);
        let Some(node) = fronts.pop(pass) else { break };
        if scratch.mark(node) {
            fronts.requeue(pass, node, true);
            skipped += 1;
            continue;
        }
        skipped = 0;
        unseen -= 1;
        stats.evaluated += 1;
        let (needs, _) = ctx.needs(pass, node);
        if !needs {
            fronts.requeue(pass, node, true);
            continue;
        }
        let before = fronts.front_len(pass);
        if !apply_within(ctx, fronts, pass, node, room, ops, &mut stats) {
            fronts.requeue(pass, node, false);
            break;
        }
        // The node left the front; the rest of the change is members it brought in.
        unseen += (fronts.front_len(pass) + 1).saturating_sub(before);
    }
    stats
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heap_keys_order_priorities() {
        let split: Vec<u64> = [-1.0, 0.0, 1e-9, 0.5, 2.0, f32::INFINITY]
            .iter()
            .map(|&p| heap_key(Pass::Split, p, 7))
            .collect();
        assert!(
            split.windows(2).all(|w| w[0] < w[1]),
            "splits: larger first"
        );
        let collapse: Vec<u64> = [f32::INFINITY, 2.0, 0.5, 0.0, -1.0]
            .iter()
            .map(|&p| heap_key(Pass::Collapse, p, 7))
            .collect();
        assert!(
            collapse.windows(2).all(|w| w[0] < w[1]),
            "collapses: smaller first"
        );
        assert!(heap_key(Pass::Split, 1.0, 3) > heap_key(Pass::Split, 1.0, 4));
        assert_eq!(node_of(heap_key(Pass::Collapse, 0.25, 12345)), 12345);
    }
}
