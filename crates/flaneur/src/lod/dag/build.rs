//! The three constructions of the DAG's edges — Zheng 2007 §3.3: the full-redundant
//! DAG (every creator of an element of a split's dependency list is a parent, §3.3
//! and Fig. 3.7), the non-redundant DAG (Fig. 3.9: only parents that are not also
//! ancestors of another parent) and the mini-redundant DAG (Fig. 3.10: parents that
//! are not also potential parents of a parent already taken).
//!
//! All three work on nodes, not splits: a node is a *run* of splits that one position
//! collapse made (`VertexSplit::joins_previous`), and its dependency list is the union
//! of its splits' lists. Nodes are numbered by their first split, so a parent always
//! has a smaller number than its child and node order is one topological order; the
//! constructions rely on that, as the thesis does on its ids ("all a ∈ ancestors(t)
//! have a.id < t.id").
//!
//! Departure from Fig. 3.9: the thesis tests `p' ∈ ancestors(p_max)` for every pair.
//! Here each parent taken marks its ancestors by a depth-first walk up the edges built
//! so far, cut below the smallest potential parent (an ancestor has a smaller id, so
//! nothing below it can be one of the potentials), and the marks are shared by all
//! the parents of one node. The result is the same transitive reduction; the worst
//! case is still quadratic.

use crate::error::{Error, Result};
use crate::lod::pm::ProgressiveMesh;

/// How a DAG's edges are chosen among the dependencies the legality condition gives
/// (Zheng 2007 §3.3). All three allow exactly the same orders of splits and collapses;
/// they differ in how many edges a traversal walks and the DAG stores.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DagConstruction {
    /// Every creator of an element of a node's dependency list is its parent (§3.3).
    FullRedundant,
    /// No edge that a longer path implies (Fig. 3.9): the transitive reduction.
    /// Worst case quadratic; for tests and measurements.
    NonRedundant,
    /// The thesis's practical choice (Fig. 3.10): a potential parent that is also a
    /// potential parent of a parent already taken is dropped. Linear time.
    MiniRedundant,
}

impl DagConstruction {
    /// All three, in the thesis's order.
    pub const ALL: [DagConstruction; 3] = [
        DagConstruction::FullRedundant,
        DagConstruction::NonRedundant,
        DagConstruction::MiniRedundant,
    ];

    /// The short name the thesis's tables use: "full", "non" or "mini".
    pub fn name(self) -> &'static str {
        match self {
            DagConstruction::FullRedundant => "full",
            DagConstruction::NonRedundant => "non",
            DagConstruction::MiniRedundant => "mini",
        }
    }

    pub(crate) fn code(self) -> u32 {
        match self {
            DagConstruction::FullRedundant => 0,
            DagConstruction::NonRedundant => 1,
            DagConstruction::MiniRedundant => 2,
        }
    }

    pub(crate) fn from_code(code: u32) -> Option<DagConstruction> {
        DagConstruction::ALL.into_iter().find(|c| c.code() == code)
    }
}

/// The edges of a progressive mesh's DAG as one construction chooses them, before the
/// nodes' attributes: the runs of splits that make the nodes, and each node's parents
/// and children. [`DagEdges::attributes`] computes the attributes over them and
/// [`Dag::build`](super::Dag::build) puts the two together.
#[derive(Clone, Debug, PartialEq)]
pub struct DagEdges {
    pub(crate) construction: DagConstruction,
    /// Node k's splits are `run_starts[k]..run_starts[k + 1]`; the last entry is the
    /// split count.
    pub(crate) run_starts: Vec<u32>,
    pub(crate) parents: Csr,
    pub(crate) children: Csr,
}

impl DagEdges {
    /// The edges of `pm`'s splits by `construction`: the dependency lists, the
    /// construction's choice of parents among them, and the children lists.
    ///
    /// An `Error::Invalid` when `pm` cannot be refined in any order: a split names a
    /// vertex or triangle out of range, or created only by itself or a later split.
    pub fn build(pm: &ProgressiveMesh, construction: DagConstruction) -> Result<DagEdges> {
        let run_starts = run_starts(pm)?;
        let parents = choose_parents(potentials(pm, &run_starts)?, construction);
        let children = parents.transpose();
        Ok(DagEdges {
            construction,
            run_starts,
            parents,
            children,
        })
    }
}

/// Adjacency lists in compressed rows: row `i` is `items[starts[i]..starts[i + 1]]`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Csr {
    pub starts: Vec<u32>,
    pub items: Vec<u32>,
}

impl Csr {
    fn new() -> Csr {
        Csr {
            starts: vec![0],
            items: Vec::new(),
        }
    }

    /// Closes the row being filled.
    fn end_row(&mut self) {
        self.starts.push(self.items.len() as u32);
    }

    pub fn rows(&self) -> usize {
        self.starts.len() - 1
    }

    pub fn row(&self, i: usize) -> &[u32] {
        &self.items[self.starts[i] as usize..self.starts[i + 1] as usize]
    }

    /// The same edges, each row listing where its edges point from: `transpose` of
    /// the parents is the children. Rows come out ascending, as the input's are
    /// visited in order.
    pub fn transpose(&self) -> Csr {
        let n = self.rows();
        let mut starts = vec![0u32; n + 1];
        for &j in &self.items {
            starts[j as usize + 1] += 1;
        }
        for i in 1..=n {
            starts[i] += starts[i - 1];
        }
        let mut fill = starts.clone();
        let mut items = vec![0u32; self.items.len()];
        for i in 0..n {
            for &j in self.row(i) {
                items[fill[j as usize] as usize] = i as u32;
                fill[j as usize] += 1;
            }
        }
        Csr { starts, items }
    }
}

/// Where each node's run of splits starts, with the split count at the end: a run
/// begins at every split that does not join the one before it.
fn run_starts(pm: &ProgressiveMesh) -> Result<Vec<u32>> {
    let s = pm.splits.len();
    if s as u64 >= u32::MAX as u64 {
        return Err(Error::Invalid(format!(
            "LOD DAG: {s} splits are too many for 32-bit node ids"
        )));
    }
    let mut starts: Vec<u32> = (0..s)
        .filter(|&i| i == 0 || !pm.splits[i].joins_previous)
        .map(|i| i as u32)
        .collect();
    starts.push(s as u32);
    Ok(starts)
}

/// The node each split belongs to.
pub(crate) fn node_of_split(run_starts: &[u32]) -> Vec<u32> {
    let mut of = Vec::with_capacity(*run_starts.last().unwrap_or(&0) as usize);
    for (k, w) in run_starts.windows(2).enumerate() {
        of.extend(std::iter::repeat_n(k as u32, (w[1] - w[0]) as usize));
    }
    of
}

/// The full-redundant parents of every node (its *potential* parents, §3.3.1): the
/// nodes that created v_p, v_l, v_r or an adjusted triangle of one of its splits,
/// ascending. An `Err` names the first split whose dependency list is out of range,
/// names an element created by a later split, or names a triangle slot that its split
/// leaves empty: such a progressive mesh cannot be refined in any order.
fn potentials(pm: &ProgressiveMesh, run_starts: &[u32]) -> Result<Csr> {
    let node_of = node_of_split(run_starts);
    let base_v = pm.base.positions.len();
    let base_t = pm.base.triangle_count();
    let (nv, nt) = (pm.vertex_count(), pm.triangle_slots());
    let mut out = Csr::new();
    out.items.reserve(6 * run_starts.len());
    let mut row: Vec<u32> = Vec::new();
    for (k, w) in run_starts.windows(2).enumerate() {
        row.clear();
        for i in w[0] as usize..w[1] as usize {
            let s = &pm.splits[i];
            let bad = |what: String| Error::Invalid(format!("LOD DAG: vertex split {i}: {what}"));
            // A dependency on a split of the same run is ordered by the run itself.
            let mut depend_on = |j: usize, what: &dyn Fn() -> String| -> Result<()> {
                if j >= i {
                    return Err(bad(format!(
                        "{} is created by split {j}, not before",
                        what()
                    )));
                }
                if node_of[j] as usize != k {
                    row.push(node_of[j]);
                }
                Ok(())
            };
            for v in [Some(s.v_p), s.v_l, s.v_r].into_iter().flatten() {
                if v as usize >= nv {
                    return Err(bad(format!("vertex {v} is out of range ({nv} vertices)")));
                }
                if v as usize >= base_v {
                    depend_on(v as usize - base_v, &|| format!("vertex {v}"))?;
                }
            }
            for &t in &s.adjusted {
                if t as usize >= nt {
                    return Err(bad(format!("triangle {t} is out of range ({nt} slots)")));
                }
                if t as usize >= base_t {
                    let j = (t as usize - base_t) / 2;
                    let left = (t as usize - base_t).is_multiple_of(2);
                    depend_on(j, &|| format!("triangle {t}"))?;
                    let made = if left {
                        pm.splits[j].v_l
                    } else {
                        pm.splits[j].v_r
                    };
                    if made.is_none() {
                        return Err(bad(format!(
                            "adjusted triangle {t} is a slot that split {j} leaves empty"
                        )));
                    }
                }
            }
        }
        row.sort_unstable();
        row.dedup();
        out.items.extend_from_slice(&row);
        out.end_row();
    }
    Ok(out)
}

/// The parents `construction` keeps of the potential parents `full`.
fn choose_parents(full: Csr, construction: DagConstruction) -> Csr {
    match construction {
        DagConstruction::FullRedundant => full,
        DagConstruction::NonRedundant => non_redundant(&full),
        DagConstruction::MiniRedundant => mini_redundant(&full),
    }
}

/// The mini-redundant parents (Fig. 3.10): the potential parents taken largest first,
/// each taken one striking from the rest those among its own potential parents. O(n)
/// for a bounded number of potentials per node.
pub(crate) fn mini_redundant(full: &Csr) -> Csr {
    let mut out = Csr::new();
    out.items.reserve(full.items.len() / 2);
    let mut alive: Vec<bool> = Vec::new();
    for t in 0..full.rows() {
        let p = full.row(t);
        alive.clear();
        alive.resize(p.len(), true);
        let row_start = out.items.len();
        for j in (0..p.len()).rev() {
            if !alive[j] {
                continue;
            }
            out.items.push(p[j]);
            let q = full.row(p[j] as usize);
            for i in 0..j {
                if alive[i] && q.binary_search(&p[i]).is_ok() {
                    alive[i] = false;
                }
            }
        }
        out.items[row_start..].reverse();
        out.end_row();
    }
    out
}

/// The non-redundant parents (Fig. 3.9): the transitive reduction of `full`.
pub(crate) fn non_redundant(full: &Csr) -> Csr {
    let n = full.rows();
    let mut out = Csr::new();
    out.items.reserve(full.items.len() / 2);
    // stamp[x] == t: x is a parent of t or an ancestor of one.
    let mut stamp = vec![u32::MAX; n];
    let mut stack: Vec<u32> = Vec::new();
    for t in 0..n {
        let p = full.row(t);
        let Some(&lowest) = p.first() else {
            out.end_row();
            continue;
        };
        let row_start = out.items.len();
        for &parent in p.iter().rev() {
            if stamp[parent as usize] == t as u32 {
                continue;
            }
            out.items.push(parent);
            stamp[parent as usize] = t as u32;
            stack.push(parent);
            while let Some(x) = stack.pop() {
                for &y in out.row(x as usize) {
                    if y >= lowest && stamp[y as usize] != t as u32 {
                        stamp[y as usize] = t as u32;
                        stack.push(y);
                    }
                }
            }
        }
        out.items[row_start..].reverse();
        out.end_row();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn csr(rows: &[&[u32]]) -> Csr {
        let mut c = Csr::new();
        for r in rows {
            c.items.extend_from_slice(r);
            c.end_row();
        }
        c
    }

    #[test]
    fn mini_keeps_what_only_an_ancestor_search_finds() {
        // 0 → 1 → 2 → 3 and 0 → 3: 0 is a potential grandparent of 3 only through two
        // steps, which the mini-redundant test (one step) misses.
        let full = csr(&[&[], &[0], &[1], &[0, 2]]);
        assert_eq!(mini_redundant(&full), csr(&[&[], &[0], &[1], &[0, 2]]));
        assert_eq!(non_redundant(&full), csr(&[&[], &[0], &[1], &[2]]));
        // One step: 0 → 1 → 2 and 0 → 2; both drop 0 → 2.
        let full = csr(&[&[], &[0], &[0, 1]]);
        assert_eq!(mini_redundant(&full), csr(&[&[], &[0], &[1]]));
        assert_eq!(non_redundant(&full), csr(&[&[], &[0], &[1]]));
    }

    #[test]
    fn non_redundant_keeps_independent_parents() {
        // 3's parents 1 and 2 are independent (both children of 0); 0 is redundant.
        let full = csr(&[&[], &[0], &[0], &[0, 1, 2]]);
        let non = non_redundant(&full);
        assert_eq!(non, csr(&[&[], &[0], &[0], &[1, 2]]));
        assert_eq!(non.transpose(), csr(&[&[1, 2], &[3], &[3], &[]]));
    }
}
