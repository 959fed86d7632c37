//! The two fronts of the DAG — Zheng 2007 §4.2: F_s, the collapsed nodes whose parents
//! are all split (they may split next), and F_c, the split nodes whose children are all
//! collapsed (they may collapse next), kept by one counter per node (§4.2.2): for a
//! collapsed node the number of its collapsed parents, for a split node the number of
//! its split children. A node is in its status's front exactly when its counter is 0.
//! Counters start at |in-edges| and F_s at the roots; a split or a collapse updates
//! them as Fig. 4.3 and Fig. 4.4 do.
//!
//! Each front is also a FIFO queue (§4.4.2), kept from frame to frame so that the
//! linear and constant-time traversals resume where they stopped. A node leaves a front
//! by its counter alone; its queue entry goes stale and is dropped when met (each node
//! is queued at most once per front, so a queue never outgrows the DAG). The priority
//! traversal, which reads whole fronts, drops the stale entries as it goes.

use std::collections::VecDeque;

use super::prefetch_hint::prefetch;
use crate::lod::dag::Dag;

// A node's status bits and its counter share one word, so that maintaining the fronts
// after an operator takes one cache miss per neighbour, not two.
const SPLIT: u32 = 1 << 31;
const QUEUED_S: u32 = 1 << 30;
const QUEUED_C: u32 = 1 << 29;
const COUNT: u32 = QUEUED_C - 1;

/// Which front, or which pass of a traversal: the split front F_s and the refinement
/// pass over it, or the collapse front F_c and the simplification pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Pass {
    Collapse,
    Split,
}

/// The split status of every DAG node, the counters of Zheng 2007 §4.2.2 and the
/// fronts F_s and F_c they define.
///
/// ```
/// use flaneur::lod::{Dag, DagConstruction, Fronts, ProgressiveMesh};
/// let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
/// let dag = Dag::build(&pm, DagConstruction::MiniRedundant)?;
/// let fronts = Fronts::new(&dag);
/// // Nothing is split: F_s is the roots, F_c is empty.
/// assert_eq!(fronts.split_front_len(), dag.roots().len());
/// assert_eq!(fronts.collapse_front_len(), 0);
/// assert!(dag.roots().iter().all(|&r| fronts.in_split_front(r)));
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct Fronts {
    /// Per node: the status bits above and the counter in the low bits.
    state: Vec<u32>,
    split_nodes: usize,
    split_len: usize,
    collapse_len: usize,
    queue_s: VecDeque<u32>,
    queue_c: VecDeque<u32>,
}

impl Fronts {
    /// Every node collapsed: counters at the in-degrees, F_s the roots, F_c empty.
    pub fn new(dag: &Dag) -> Fronts {
        // In-degrees are below the node count, which a DAG keeps far under 2^29.
        let mut state = dag.in_degrees();
        debug_assert!(state.iter().all(|&d| d <= COUNT));
        for &r in dag.roots() {
            state[r as usize] |= QUEUED_S;
        }
        Fronts {
            state,
            split_nodes: 0,
            split_len: dag.roots().len(),
            collapse_len: 0,
            queue_s: dag.roots().iter().copied().collect(),
            queue_c: VecDeque::new(),
        }
    }

    /// Bytes held: the per-node states and the two queues.
    pub fn memory(&self) -> usize {
        4 * (self.state.capacity() + self.queue_s.capacity() + self.queue_c.capacity())
    }

    /// The number of nodes.
    pub fn node_count(&self) -> usize {
        self.state.len()
    }

    /// Whether `node` is split. Panics when `node` is out of range, like slice indexing.
    pub fn is_split(&self, node: u32) -> bool {
        self.state[node as usize] & SPLIT != 0
    }

    /// `node`'s counter: its collapsed parents when it is collapsed, its split children
    /// when it is split. Panics when `node` is out of range.
    pub fn counter(&self, node: u32) -> u32 {
        self.state[node as usize] & COUNT
    }

    /// Whether `node` is in F_s (collapsed, every parent split). Panics when `node` is
    /// out of range.
    pub fn in_split_front(&self, node: u32) -> bool {
        self.state[node as usize] & (SPLIT | COUNT) == 0
    }

    /// Whether `node` is in F_c (split, every child collapsed). Panics when `node` is
    /// out of range.
    pub fn in_collapse_front(&self, node: u32) -> bool {
        self.state[node as usize] & (SPLIT | COUNT) == SPLIT
    }

    /// |F_s|.
    pub fn split_front_len(&self) -> usize {
        self.split_len
    }

    /// |F_c|.
    pub fn collapse_front_len(&self) -> usize {
        self.collapse_len
    }

    /// The number of split nodes.
    pub fn split_count(&self) -> usize {
        self.split_nodes
    }

    /// The nodes of F_s, in queue order.
    pub fn split_front(&self) -> impl Iterator<Item = u32> + '_ {
        self.queue_s
            .iter()
            .copied()
            .filter(|&k| self.in_split_front(k))
    }

    /// The nodes of F_c, in queue order.
    pub fn collapse_front(&self) -> impl Iterator<Item = u32> + '_ {
        self.queue_c
            .iter()
            .copied()
            .filter(|&k| self.in_collapse_front(k))
    }

    pub(crate) fn in_front(&self, pass: Pass, node: u32) -> bool {
        match pass {
            Pass::Split => self.in_split_front(node),
            Pass::Collapse => self.in_collapse_front(node),
        }
    }

    pub(crate) fn front_len(&self, pass: Pass) -> usize {
        match pass {
            Pass::Split => self.split_len,
            Pass::Collapse => self.collapse_len,
        }
    }

    fn queue_parts(&mut self, pass: Pass) -> (&mut VecDeque<u32>, &mut [u32], u32) {
        match pass {
            Pass::Split => (&mut self.queue_s, &mut self.state, QUEUED_S),
            Pass::Collapse => (&mut self.queue_c, &mut self.state, QUEUED_C),
        }
    }

    /// The next member of `pass`'s front in FIFO order, taken off the queue (stale
    /// entries on the way are dropped); `None` when the front is empty.
    pub(crate) fn pop(&mut self, pass: Pass) -> Option<u32> {
        loop {
            let (queue, state, bit) = self.queue_parts(pass);
            let node = queue.pop_front()?;
            state[node as usize] &= !bit;
            if self.in_front(pass, node) {
                return Some(node);
            }
        }
    }

    /// The entry `ahead` places behind the head of `pass`'s queue, perhaps stale: the
    /// node a pass will pop soon, whose data it may prefetch.
    pub(crate) fn upcoming(&self, pass: Pass, ahead: usize) -> Option<u32> {
        match pass {
            Pass::Split => self.queue_s.get(ahead).copied(),
            Pass::Collapse => self.queue_c.get(ahead).copied(),
        }
    }

    /// Prefetches `node`'s status and counter, which popping it reads.
    pub(crate) fn prefetch_status(&self, node: u32) {
        prefetch(&self.state[node as usize]);
    }

    /// Queues `node` at the back (`back`) or the front of `pass`'s queue, unless it is
    /// already queued there.
    pub(crate) fn requeue(&mut self, pass: Pass, node: u32, back: bool) {
        let (queue, state, bit) = self.queue_parts(pass);
        if state[node as usize] & bit == 0 {
            state[node as usize] |= bit;
            if back {
                queue.push_back(node);
            } else {
                queue.push_front(node);
            }
        }
    }

    /// Drops the stale entries of `pass`'s queue, keeping the members' order, and
    /// returns the members.
    pub(crate) fn compact(&mut self, pass: Pass) -> &VecDeque<u32> {
        let split_status = pass == Pass::Split;
        let Fronts {
            state,
            queue_s,
            queue_c,
            ..
        } = self;
        let (queue, bit) = match pass {
            Pass::Split => (queue_s, QUEUED_S),
            Pass::Collapse => (queue_c, QUEUED_C),
        };
        queue.retain(|&k| {
            let s = &mut state[k as usize];
            let member = (*s & SPLIT == 0) == split_status && *s & COUNT == 0;
            if !member {
                *s &= !bit;
            }
            member
        });
        queue
    }

    /// SPLIT-MAINTENANCE (Fig. 4.3): `node`, a member of F_s, becomes split.
    pub(crate) fn split(&mut self, dag: &Dag, node: u32) {
        debug_assert!(self.in_split_front(node), "node {node} is not in F_s");
        self.state[node as usize] |= SPLIT;
        self.split_nodes += 1;
        self.split_len -= 1;
        // A node in F_s has no split child: its counter, now of split children, is 0.
        self.collapse_len += 1;
        self.requeue(Pass::Collapse, node, true);
        for &c in dag.children(node) {
            let n = &mut self.state[c as usize];
            *n -= 1;
            if *n & COUNT == 0 {
                self.split_len += 1;
                self.requeue(Pass::Split, c, true);
            }
        }
        for &p in dag.parents(node) {
            let n = &mut self.state[p as usize];
            if *n & COUNT == 0 {
                self.collapse_len -= 1;
            }
            *n += 1;
        }
    }

    /// COLLAPSE-MAINTENANCE (Fig. 4.4): `node`, a member of F_c, becomes collapsed.
    pub(crate) fn collapse(&mut self, dag: &Dag, node: u32) {
        debug_assert!(self.in_collapse_front(node), "node {node} is not in F_c");
        self.state[node as usize] &= !SPLIT;
        self.split_nodes -= 1;
        self.collapse_len -= 1;
        // Every parent of a node in F_c is split: its counter, now of collapsed
        // parents, is 0.
        self.split_len += 1;
        self.requeue(Pass::Split, node, true);
        for &p in dag.parents(node) {
            let n = &mut self.state[p as usize];
            *n -= 1;
            if *n & COUNT == 0 {
                self.collapse_len += 1;
                self.requeue(Pass::Collapse, p, true);
            }
        }
        for &c in dag.children(node) {
            let n = &mut self.state[c as usize];
            if *n & COUNT == 0 {
                self.split_len -= 1;
            }
            *n += 1;
        }
    }

    /// Applies `pass`'s operator to the maintenance: a split for [`Pass::Split`].
    pub(crate) fn apply(&mut self, dag: &Dag, pass: Pass, node: u32) {
        match pass {
            Pass::Split => self.split(dag, node),
            Pass::Collapse => self.collapse(dag, node),
        }
    }

    /// Undoes [`apply`](Fronts::apply): the node must be in the other front.
    pub(crate) fn undo(&mut self, dag: &Dag, pass: Pass, node: u32) {
        match pass {
            Pass::Split => self.collapse(dag, node),
            Pass::Collapse => self.split(dag, node),
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use rand::seq::SliceRandom;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::lod::{DagConstruction, ProgressiveMesh};

    /// Recomputes the counters and fronts from the split status alone and compares:
    /// the counters, both fronts' members and sizes, and that every member is queued
    /// exactly once.
    pub(crate) fn check_fronts(dag: &Dag, f: &Fronts) {
        let n = dag.node_count() as u32;
        let mut split_len = 0;
        let mut collapse_len = 0;
        for k in 0..n {
            let expected = if f.is_split(k) {
                dag.children(k).iter().filter(|&&c| f.is_split(c)).count()
            } else {
                dag.parents(k).iter().filter(|&&p| !f.is_split(p)).count()
            };
            assert_eq!(f.counter(k) as usize, expected, "node {k}'s counter");
            if f.is_split(k) {
                assert!(
                    dag.parents(k).iter().all(|&p| f.is_split(p)),
                    "node {k} is split under a collapsed parent"
                );
            }
            split_len += f.in_split_front(k) as usize;
            collapse_len += f.in_collapse_front(k) as usize;
        }
        assert_eq!(f.split_front_len(), split_len);
        assert_eq!(f.collapse_front_len(), collapse_len);
        assert_eq!(f.split_count(), (0..n).filter(|&k| f.is_split(k)).count());
        for (pass, queue, bit) in [
            (Pass::Split, &f.queue_s, QUEUED_S),
            (Pass::Collapse, &f.queue_c, QUEUED_C),
        ] {
            let mut seen = vec![false; n as usize];
            for &k in queue {
                assert!(
                    !std::mem::replace(&mut seen[k as usize], true),
                    "{k} queued twice"
                );
                assert!(f.state[k as usize] & bit != 0);
            }
            for k in 0..n {
                assert_eq!(f.state[k as usize] & bit != 0, seen[k as usize], "node {k}");
                if f.in_front(pass, k) {
                    assert!(seen[k as usize], "{pass:?} member {k} is not queued");
                }
            }
        }
    }

    #[test]
    fn random_walks_keep_the_counters() {
        let pm = ProgressiveMesh::build(&crate::scene::bunny()).unwrap();
        for c in DagConstruction::ALL {
            let dag = Dag::build(&pm, c).unwrap();
            let mut f = Fronts::new(&dag);
            check_fronts(&dag, &f);
            let mut rng = ChaCha8Rng::seed_from_u64(3);
            for step in 0..4000 {
                let pass = if rng.gen_bool(if step < 2000 { 0.7 } else { 0.4 }) {
                    Pass::Split
                } else {
                    Pass::Collapse
                };
                let members: Vec<u32> = match pass {
                    Pass::Split => f.split_front().collect(),
                    Pass::Collapse => f.collapse_front().collect(),
                };
                if let Some(&k) = members.choose(&mut rng) {
                    f.apply(&dag, pass, k);
                }
                if rng.gen_bool(0.1) {
                    // Pops as the FIFO traversals do, put back or not.
                    if let Some(k) = f.pop(pass) {
                        assert!(f.in_front(pass, k));
                        if rng.gen_bool(0.5) {
                            f.apply(&dag, pass, k);
                        } else {
                            f.requeue(pass, k, rng.gen_bool(0.5));
                        }
                    }
                }
                if rng.gen_bool(0.05) {
                    let members = f.compact(pass).len();
                    assert_eq!(members, f.front_len(pass));
                }
                if step % 97 == 0 {
                    check_fronts(&dag, &f);
                }
            }
            check_fronts(&dag, &f);
            // Undo brings back the state before.
            let first = f.split_front().next();
            if let Some(k) = first {
                // Status and counters; the queue bits may differ.
                let core = |f: &Fronts| {
                    f.state
                        .iter()
                        .map(|b| b & (SPLIT | COUNT))
                        .collect::<Vec<_>>()
                };
                let before = core(&f);
                f.apply(&dag, Pass::Split, k);
                f.undo(&dag, Pass::Split, k);
                check_fronts(&dag, &f);
                assert_eq!(before, core(&f));
            }
        }
    }
}
