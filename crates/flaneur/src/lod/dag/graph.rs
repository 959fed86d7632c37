//! The DAG hierarchy of vertex splits — Zheng 2007 ch. 3: §3.2 (the legality condition
//! that defines the dependencies), §3.3 (the full-, non- and mini-redundant
//! constructions, `build`), §3.4 (the visibility attributes, `attrs`), and a
//! flat codec for the database (`codec`).
//!
//! A split is legal (§3.2, as `SelectiveMesh::split` checks it) when its v_p and its
//! pivots v_l, v_r are present and every adjusted triangle is present with v_p as a
//! corner; its collapse is legal when f_l and f_r are as the split made them and every
//! adjusted triangle has v_c as a corner. Each element of a split's dependency list
//! (v_p, v_l, v_r, the adjusted triangles) is created by one earlier split or by the
//! base mesh, and an edge a → b says that a created something b needs: b splits only
//! after a, and a collapses only after b. Why that suffices, for any order the DAG
//! allows: a corner of a triangle moves only by a split that names it as v_p, and
//! two splits never move one triangle's corner from the same vertex (the earlier
//! would have moved it away from the later), so the corner chains of a triangle are
//! ordered by the creator edges alone; and every reference to a vertex or a triangle a
//! node created is held by a descendant of it, which is collapsed first.
//!
//! A node is a *run* of splits: the splits of one position collapse, which differ in
//! the wedge they move (`VertexSplit::joins_previous`). They are applied and undone
//! together, in list order and back, so a crease never cracks; the run's dependency
//! list is the union of its splits'. Nodes are numbered in list order, so a parent's
//! number is always below its child's and node order is itself a topological order.
//!
//! Storage: parents and children as compressed rows of `u32` node numbers, the roots
//! (nodes with no parent: their splits need only the base mesh), the runs as split
//! offsets, and the attributes. A traversal's counters start at [`Dag::in_degrees`]
//! and its split front at [`Dag::roots`] (Zheng §4.2.2).

use std::ops::Range;

use super::attrs::NodeAttrs;
use super::build::{DagConstruction, DagEdges};
use crate::error::{Error, Result};
use crate::lod::pm::{ProgressiveMesh, SelectiveMesh};

/// The DAG hierarchy of a progressive mesh's vertex splits (Zheng 2007 ch. 3), with
/// each node's visibility attributes.
///
/// Node `k` is the run of splits [`splits(k)`](Dag::splits); an edge from a parent to
/// a child says that the child's splits need something the parent's create. Splitting
/// nodes whose parents are all split, and collapsing nodes whose children are all
/// collapsed, keeps a [`SelectiveMesh`] legal, in any such order.
///
/// ```
/// use flaneur::lod::{Dag, DagConstruction, ProgressiveMesh, SelectiveMesh};
/// let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
/// let dag = Dag::build(&pm, DagConstruction::MiniRedundant)?;
///
/// // Refine the base mesh fully, each node as soon as its parents are split.
/// let mut mesh = SelectiveMesh::new(&pm.base, pm.splits.len())?;
/// let mut waiting = dag.in_degrees();
/// let mut front = dag.roots().to_vec();
/// while let Some(node) = front.pop() {
///     dag.split_node(node, &pm, &mut mesh)?;
///     for &child in dag.children(node) {
///         waiting[child as usize] -= 1;
///         if waiting[child as usize] == 0 {
///             front.push(child);
///         }
///     }
/// }
/// assert_eq!(mesh.triangle_count(), 3674);
///
/// // A node's sphere bounds its descendants' region; errors grow toward the roots.
/// let root = dag.roots()[0];
/// assert!(dag.children(root).iter().all(|&c| dag.attrs(c).error <= dag.attrs(root).error));
///
/// // Flat little-endian bytes for the database, checked when read back.
/// let bytes = dag.to_bytes();
/// assert_eq!(Dag::from_bytes(&bytes)?, dag);
/// assert!(Dag::from_bytes(&bytes[..bytes.len() - 1]).is_err());
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Dag {
    pub(crate) edges: DagEdges,
    pub(crate) roots: Vec<u32>,
    pub(crate) attrs: Vec<NodeAttrs>,
}

impl Dag {
    /// Builds the DAG of `pm`'s splits by `construction`, and its attributes.
    ///
    /// An `Error::Invalid` when `pm` cannot be refined in any order: a split names a
    /// vertex or triangle out of range, or created only by itself or a later split, or
    /// carries a non-finite position, normal or error.
    pub fn build(pm: &ProgressiveMesh, construction: DagConstruction) -> Result<Dag> {
        let edges = DagEdges::build(pm, construction)?;
        let attrs = edges.attributes(pm)?;
        Dag::assemble(edges, attrs)
    }

    /// The DAG of `edges` with `attrs`, one per node, as [`DagEdges::attributes`]
    /// computes them: what [`build`](Dag::build) does after building the edges, for a
    /// caller that times or shares the two steps apart. An `Error::Invalid` when
    /// `attrs` does not hold one entry per node.
    pub fn assemble(edges: DagEdges, attrs: Vec<NodeAttrs>) -> Result<Dag> {
        let nodes = edges.run_starts.len() - 1;
        if attrs.len() != nodes {
            return Err(Error::Invalid(format!(
                "LOD DAG: {} attributes for {nodes} nodes",
                attrs.len()
            )));
        }
        let parents = &edges.parents;
        let roots = (0..parents.rows() as u32)
            .filter(|&k| parents.row(k as usize).is_empty())
            .collect();
        Ok(Dag {
            edges,
            roots,
            attrs,
        })
    }

    /// How the edges were chosen.
    pub fn construction(&self) -> DagConstruction {
        self.edges.construction
    }

    /// The number of nodes: position collapses, each one split or a run of them.
    pub fn node_count(&self) -> usize {
        self.edges.run_starts.len() - 1
    }

    /// The number of vertex splits the nodes hold.
    pub fn split_count(&self) -> usize {
        *self.edges.run_starts.last().unwrap_or(&0) as usize
    }

    /// The number of edges (each counted once: the thesis's in-edges).
    pub fn edge_count(&self) -> usize {
        self.edges.parents.items.len()
    }

    /// The splits of `node`, in the order they apply. Panics when `node` is out of
    /// range, like slice indexing.
    pub fn splits(&self, node: u32) -> Range<usize> {
        self.edges.run_starts[node as usize] as usize
            ..self.edges.run_starts[node as usize + 1] as usize
    }

    /// The node that holds split `split`, `None` past the last split.
    pub fn node_of_split(&self, split: usize) -> Option<u32> {
        if split >= self.split_count() {
            return None;
        }
        // The last run start at or before `split`.
        Some(
            self.edges
                .run_starts
                .partition_point(|&s| s as usize <= split) as u32
                - 1,
        )
    }

    /// The nodes that must be split before `node`, ascending.
    pub fn parents(&self, node: u32) -> &[u32] {
        self.edges.parents.row(node as usize)
    }

    /// The nodes that must be collapsed before `node`, ascending.
    pub fn children(&self, node: u32) -> &[u32] {
        self.edges.children.row(node as usize)
    }

    /// The number of `node`'s parents.
    pub fn in_degree(&self, node: u32) -> u32 {
        self.edges.parents.starts[node as usize + 1] - self.edges.parents.starts[node as usize]
    }

    /// The number of `node`'s children.
    pub fn out_degree(&self, node: u32) -> u32 {
        self.edges.children.starts[node as usize + 1] - self.edges.children.starts[node as usize]
    }

    /// Every node's in-degree: the counters a traversal starts from, which reach 0
    /// when all of a node's parents are split.
    pub fn in_degrees(&self) -> Vec<u32> {
        self.edges
            .parents
            .starts
            .windows(2)
            .map(|w| w[1] - w[0])
            .collect()
    }

    /// The nodes without parents, ascending: the first split front over the base mesh.
    pub fn roots(&self) -> &[u32] {
        &self.roots
    }

    /// `node`'s visibility attributes.
    pub fn attrs(&self, node: u32) -> NodeAttrs {
        self.attrs[node as usize]
    }

    /// Every node's visibility attributes, by node.
    pub fn all_attrs(&self) -> &[NodeAttrs] {
        &self.attrs
    }

    /// The bytes the DAG takes in memory: its arrays' lengths, not their capacities.
    pub fn memory_bytes(&self) -> usize {
        4 * (self.edges.run_starts.len()
            + self.edges.parents.starts.len()
            + self.edges.parents.items.len()
            + self.edges.children.starts.len()
            + self.edges.children.items.len()
            + self.roots.len())
            + std::mem::size_of::<NodeAttrs>() * self.attrs.len()
    }

    /// Applies `node`'s splits to `mesh`, in order. An `Err`, and no change, when a
    /// split is illegal there (a parent not split, the node already split), when
    /// `node` is out of range, or when `pm` is not the mesh the DAG was built from.
    pub fn split_node(
        &self,
        node: u32,
        pm: &ProgressiveMesh,
        mesh: &mut SelectiveMesh,
    ) -> Result<()> {
        let run = self.checked_run(node, pm)?;
        for i in run.clone() {
            if let Err(e) = mesh.split(i, &pm.splits[i]) {
                // Undo the run's splits applied so far: each just applied, so legal.
                for j in (run.start..i).rev() {
                    let _ = mesh.collapse(j, &pm.splits[j]);
                }
                return Err(e);
            }
        }
        Ok(())
    }

    /// Undoes `node`'s splits on `mesh`, last first. An `Err`, and no change, when a
    /// collapse is illegal there (a child not collapsed, the node not split), or as
    /// for [`split_node`](Dag::split_node).
    pub fn collapse_node(
        &self,
        node: u32,
        pm: &ProgressiveMesh,
        mesh: &mut SelectiveMesh,
    ) -> Result<()> {
        let run = self.checked_run(node, pm)?;
        for i in run.clone().rev() {
            if let Err(e) = mesh.collapse(i, &pm.splits[i]) {
                for j in i + 1..run.end {
                    let _ = mesh.split(j, &pm.splits[j]);
                }
                return Err(e);
            }
        }
        Ok(())
    }

    fn checked_run(&self, node: u32, pm: &ProgressiveMesh) -> Result<Range<usize>> {
        if pm.splits.len() != self.split_count() {
            return Err(Error::Invalid(format!(
                "LOD DAG of {} splits used with a progressive mesh of {}",
                self.split_count(),
                pm.splits.len()
            )));
        }
        if node as usize >= self.node_count() {
            return Err(Error::Invalid(format!(
                "LOD DAG node {node} is out of range ({} nodes)",
                self.node_count()
            )));
        }
        Ok(self.splits(node))
    }
}

#[cfg(test)]
mod tests {
    use rand::seq::SliceRandom;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::lod::fixtures::{building, check_full_mesh, random_patch};
    use crate::lod::NO_TRIANGLE;
    use crate::scene::Mesh;

    fn all(pm: &ProgressiveMesh) -> Vec<Dag> {
        DagConstruction::ALL
            .iter()
            .map(|&c| Dag::build(pm, c).unwrap())
            .collect()
    }

    /// Checks `mesh` against the set of split nodes: a triangle slot is filled exactly
    /// when its creator is split, every corner is a present vertex, no triangle repeats
    /// a vertex, and the compact mesh is valid.
    fn check_state(dag: &Dag, pm: &ProgressiveMesh, applied: &[bool], mesh: &SelectiveMesh) {
        let base_v = pm.base.positions.len();
        let base_t = pm.base.triangle_count();
        let present = |v: u32| {
            (v as usize) < base_v
                || applied[dag.node_of_split(v as usize - base_v).unwrap() as usize]
        };
        let mut live = 0;
        for (slot, t) in mesh.slots().iter().enumerate() {
            let expected = slot < base_t || {
                let j = (slot - base_t) / 2;
                let made = if (slot - base_t).is_multiple_of(2) {
                    pm.splits[j].v_l
                } else {
                    pm.splits[j].v_r
                };
                made.is_some() && applied[dag.node_of_split(j).unwrap() as usize]
            };
            assert_eq!(*t != NO_TRIANGLE, expected, "slot {slot}");
            if *t == NO_TRIANGLE {
                continue;
            }
            live += 1;
            assert!(
                t.iter().all(|&v| present(v)),
                "slot {slot}: {t:?} names an absent vertex"
            );
            assert!(
                t[0] != t[1] && t[1] != t[2] && t[0] != t[2],
                "slot {slot}: {t:?}"
            );
        }
        assert_eq!(live, mesh.triangle_count());
        mesh.to_mesh().validate().unwrap();
    }

    /// The mesh with exactly the nodes `applied` split, built in node order (one
    /// topological order): any legal sequence that ends at the same set must agree.
    fn mesh_of(dag: &Dag, pm: &ProgressiveMesh, applied: &[bool]) -> SelectiveMesh {
        let mut m = SelectiveMesh::new(&pm.base, pm.splits.len()).unwrap();
        for k in (0..dag.node_count() as u32).filter(|&k| applied[k as usize]) {
            dag.split_node(k, pm, &mut m).unwrap();
        }
        m
    }

    /// `orders` random topological orders, node by node from the base mesh: every
    /// split legal, every state clean (checked every `every` steps), the end the
    /// original.
    fn random_orders(original: &Mesh, pm: &ProgressiveMesh, dag: &Dag, orders: u64, every: usize) {
        let n = dag.node_count();
        for seed in 0..orders {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let mut mesh = SelectiveMesh::new(&pm.base, pm.splits.len()).unwrap();
            let mut waiting = dag.in_degrees();
            let mut ready = dag.roots().to_vec();
            let mut applied = vec![false; n];
            let mut step = 0;
            while !ready.is_empty() {
                let node = ready.swap_remove(rng.gen_range(0..ready.len()));
                dag.split_node(node, pm, &mut mesh)
                    .unwrap_or_else(|e| panic!("seed {seed}, step {step}: {e}"));
                applied[node as usize] = true;
                for &c in dag.children(node) {
                    waiting[c as usize] -= 1;
                    if waiting[c as usize] == 0 {
                        ready.push(c);
                    }
                }
                step += 1;
                if step % every == 0 {
                    check_state(dag, pm, &applied, &mesh);
                }
            }
            assert_eq!(step, n, "seed {seed}: some nodes never became ready");
            check_state(dag, pm, &applied, &mesh);
            check_full_mesh(original, pm, &mesh);
        }
    }

    /// Random walks that split a node whose parents are all split or collapse one whose
    /// children are all collapsed, leaning toward splits for the first half: every
    /// operator legal, every state clean and equal to the same set applied in node
    /// order, and the base mesh again after collapsing all.
    fn random_walks(pm: &ProgressiveMesh, dag: &Dag, walks: u64, steps: usize, every: usize) {
        let n = dag.node_count() as u32;
        for seed in 0..walks {
            let mut rng = ChaCha8Rng::seed_from_u64(1000 + seed);
            let mut mesh = SelectiveMesh::new(&pm.base, pm.splits.len()).unwrap();
            let base = mesh.clone();
            let mut applied = vec![false; n as usize];
            for step in 0..steps {
                let splittable: Vec<u32> = (0..n)
                    .filter(|&k| {
                        !applied[k as usize] && dag.parents(k).iter().all(|&p| applied[p as usize])
                    })
                    .collect();
                let collapsible: Vec<u32> = (0..n)
                    .filter(|&k| {
                        applied[k as usize] && dag.children(k).iter().all(|&c| !applied[c as usize])
                    })
                    .collect();
                let lean = if step < steps / 2 { 0.7 } else { 0.4 };
                let split =
                    collapsible.is_empty() || (!splittable.is_empty() && rng.gen_bool(lean));
                if split {
                    let k = *splittable.choose(&mut rng).unwrap();
                    dag.split_node(k, pm, &mut mesh)
                        .unwrap_or_else(|e| panic!("seed {seed}, step {step}: {e}"));
                    applied[k as usize] = true;
                } else {
                    let k = *collapsible.choose(&mut rng).unwrap();
                    dag.collapse_node(k, pm, &mut mesh)
                        .unwrap_or_else(|e| panic!("seed {seed}, step {step}: {e}"));
                    applied[k as usize] = false;
                }
                if step % every == 0 {
                    check_state(dag, pm, &applied, &mesh);
                    assert_eq!(mesh, mesh_of(dag, pm, &applied), "seed {seed}, step {step}");
                }
            }
            // Collapse everything, children first: node order backwards is one way.
            for k in (0..n).rev().filter(|&k| applied[k as usize]) {
                dag.collapse_node(k, pm, &mut mesh).unwrap();
            }
            assert_eq!(mesh, base, "seed {seed}");
        }
    }

    #[test]
    fn bunny_every_topological_order_refines_to_the_original() {
        let bunny = crate::scene::bunny();
        let pm = ProgressiveMesh::build(&bunny).unwrap();
        for dag in all(&pm) {
            assert_eq!(dag.node_count(), pm.splits.len(), "the bunny has no runs");
            let orders = if dag.construction() == DagConstruction::MiniRedundant {
                40
            } else {
                8
            };
            random_orders(&bunny, &pm, &dag, orders, 97);
        }
    }

    #[test]
    fn building_every_topological_order_refines_to_the_original() {
        let b = building();
        let pm = ProgressiveMesh::build(&b).unwrap();
        for dag in all(&pm) {
            assert!(dag.node_count() < pm.splits.len(), "the building has runs");
            random_orders(&b, &pm, &dag, 60, 1);
        }
    }

    #[test]
    fn random_patches_refine_in_any_order() {
        // Seams (runs), holes and boundaries (splits with one new triangle).
        for seed in 0..24 {
            let m = random_patch(seed);
            let pm = ProgressiveMesh::build(&m).unwrap();
            let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
            random_orders(&m, &pm, &dag, 8, 1);
            random_walks(&pm, &dag, 2, 300, 1);
        }
    }

    #[test]
    fn interleaved_splits_and_collapses_stay_legal() {
        let bunny = crate::scene::bunny();
        let pm = ProgressiveMesh::build(&bunny).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        random_walks(&pm, &dag, 4, 3000, 37);
        let b = building();
        let pm = ProgressiveMesh::build(&b).unwrap();
        for dag in all(&pm) {
            random_walks(&pm, &dag, 6, 800, 1);
        }
    }

    /// Every node's ancestors, as sorted lists (the meshes here are small).
    fn ancestors(dag: &Dag) -> Vec<Vec<u32>> {
        let mut out: Vec<Vec<u32>> = Vec::with_capacity(dag.node_count());
        for k in 0..dag.node_count() as u32 {
            let mut a: Vec<u32> = dag
                .parents(k)
                .iter()
                .flat_map(|&p| out[p as usize].iter().copied().chain([p]))
                .collect();
            a.sort_unstable();
            a.dedup();
            out.push(a);
        }
        out
    }

    fn edges(dag: &Dag) -> Vec<(u32, u32)> {
        (0..dag.node_count() as u32)
            .flat_map(|k| dag.parents(k).iter().map(move |&p| (p, k)))
            .collect()
    }

    fn check_constructions(pm: &ProgressiveMesh) {
        let dags = all(pm);
        let (full, non, mini) = (&dags[0], &dags[1], &dags[2]);
        let (ef, en, em) = (edges(full), edges(non), edges(mini));
        let contains = |big: &[(u32, u32)], small: &[(u32, u32)]| {
            small.iter().all(|e| {
                big.binary_search_by_key(&(e.1, e.0), |f| (f.1, f.0))
                    .is_ok()
            })
        };
        assert!(contains(&ef, &em), "mini ⊆ full");
        assert!(
            contains(&em, &en),
            "non ⊆ mini: the reduction is in every DAG of its closure"
        );
        // Same closure: every full edge is a path in mini (and in non); the reverse
        // holds since mini ⊆ full.
        let closure = ancestors(full);
        assert_eq!(ancestors(mini), closure);
        assert_eq!(ancestors(non), closure);
        // No non-redundant edge is implied by the others: its parent is no ancestor of
        // another parent of the same node.
        for k in 0..non.node_count() as u32 {
            let ps = non.parents(k);
            for &p in ps {
                for &q in ps.iter().filter(|&&q| q != p) {
                    assert!(
                        closure[q as usize].binary_search(&p).is_err(),
                        "{p} → {k} is implied via {q}"
                    );
                }
            }
        }
        for dag in [full, non, mini] {
            for (p, k) in edges(dag) {
                assert!(p < k, "parents come first");
            }
            assert_eq!(dag.edges.children.transpose(), dag.edges.parents);
            let roots: Vec<u32> = (0..dag.node_count() as u32)
                .filter(|&k| dag.in_degree(k) == 0)
                .collect();
            assert_eq!(dag.roots(), roots);
            assert_eq!(
                dag.all_attrs(),
                full.all_attrs(),
                "attributes do not depend on the construction"
            );
        }
        assert!(ef.len() >= em.len() && em.len() >= en.len());
    }

    #[test]
    fn constructions_share_one_closure() {
        check_constructions(&ProgressiveMesh::build(&crate::scene::bunny()).unwrap());
        check_constructions(&ProgressiveMesh::build(&building()).unwrap());
        for seed in 0..8 {
            check_constructions(&ProgressiveMesh::build(&random_patch(seed)).unwrap());
        }
    }

    #[test]
    fn every_non_redundant_edge_is_a_real_dependency() {
        // With all of a node's ancestors but one parent split, the node's split is
        // illegal: each edge of the reduction is needed, not only allowed.
        let check = |pm: &ProgressiveMesh, sample: usize| {
            let dag = Dag::build(pm, DagConstruction::NonRedundant).unwrap();
            let closure = ancestors(&dag);
            let mut all_edges = edges(&dag);
            all_edges.shuffle(&mut ChaCha8Rng::seed_from_u64(7));
            for &(p, k) in all_edges.iter().take(sample) {
                let mut applied = vec![false; dag.node_count()];
                for &a in &closure[k as usize] {
                    applied[a as usize] = a != p;
                }
                let mut mesh = mesh_of(&dag, pm, &applied);
                let before = mesh.clone();
                assert!(dag.split_node(k, pm, &mut mesh).is_err(), "{p} → {k}");
                assert_eq!(mesh, before, "a failed node changes nothing");
            }
        };
        check(
            &ProgressiveMesh::build(&crate::scene::bunny()).unwrap(),
            300,
        );
        check(&ProgressiveMesh::build(&building()).unwrap(), usize::MAX);
        check(
            &ProgressiveMesh::build(&random_patch(3)).unwrap(),
            usize::MAX,
        );
    }

    #[test]
    fn illegal_nodes_are_errors() {
        let pm = ProgressiveMesh::build(&building()).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        let mut mesh = SelectiveMesh::new(&pm.base, pm.splits.len()).unwrap();
        let orphan = (0..dag.node_count() as u32)
            .find(|&k| dag.in_degree(k) > 0)
            .unwrap();
        assert!(dag.split_node(orphan, &pm, &mut mesh).is_err());
        let root = dag.roots()[0];
        assert!(dag.collapse_node(root, &pm, &mut mesh).is_err());
        assert!(dag
            .split_node(dag.node_count() as u32, &pm, &mut mesh)
            .is_err());
        dag.split_node(root, &pm, &mut mesh).unwrap();
        assert!(dag.split_node(root, &pm, &mut mesh).is_err());
        // A run that fails halfway leaves nothing of itself behind.
        let run = (0..dag.node_count() as u32)
            .find(|&k| dag.splits(k).len() > 1)
            .unwrap();
        let mut applied = vec![false; dag.node_count()];
        for &a in &ancestors(&dag)[run as usize] {
            applied[a as usize] = true;
        }
        let mut m = mesh_of(&dag, &pm, &applied);
        let before = m.clone();
        let mut broken = pm.clone();
        let last = dag.splits(run).end - 1;
        broken.splits[last].v_p = u32::MAX - 1;
        assert!(dag.split_node(run, &broken, &mut m).is_err());
        assert_eq!(m, before);
        dag.split_node(run, &pm, &mut m).unwrap();
        let after = m.clone();
        let first = dag.splits(run).start;
        broken.splits[first].v_p = u32::MAX - 1;
        assert!(dag.collapse_node(run, &broken, &mut m).is_err());
        assert_eq!(m, after);
        let mut other = pm.clone();
        other.splits.pop();
        assert!(dag
            .split_node(root, &other, &mut mesh)
            .unwrap_err()
            .to_string()
            .contains("splits"));
    }

    #[test]
    fn a_damaged_progressive_mesh_is_an_error() {
        let pm = ProgressiveMesh::build(&building()).unwrap();
        let base_v = pm.base.positions.len() as u32;
        let base_t = pm.base.triangle_count() as u32;
        let damage = |f: &dyn Fn(&mut ProgressiveMesh)| {
            let mut bad = pm.clone();
            f(&mut bad);
            Dag::build(&bad, DagConstruction::MiniRedundant)
                .unwrap_err()
                .to_string()
        };
        let e = damage(&|p| p.splits[3].v_p = 1_000_000);
        assert!(e.contains("split 3") && e.contains("out of range"), "{e}");
        let e = damage(&|p| p.splits[3].v_l = Some(base_v + 3));
        assert!(e.contains("not before"), "{e}");
        let e = damage(&|p| p.splits[5].adjusted.push(base_t + 2 * 9));
        assert!(e.contains("not before"), "{e}");
        let e = damage(&|p| p.splits[5].adjusted.push(u32::MAX));
        assert!(e.contains("out of range"), "{e}");
        let e = damage(&|p| p.splits[2].position[1] = f32::NAN);
        assert!(e.contains("non-finite"), "{e}");
        let one_sided = pm.splits.iter().position(|s| s.v_r.is_none());
        if let Some(j) = one_sided {
            let slot = base_t + 2 * j as u32 + 1;
            let e = damage(&|p| {
                let last = p.splits.len() - 1;
                p.splits[last].adjusted.push(slot)
            });
            assert!(e.contains("empty"), "{e}");
        }
    }

    #[test]
    fn node_of_split_finds_runs() {
        let pm = ProgressiveMesh::build(&building()).unwrap();
        let dag = Dag::build(&pm, DagConstruction::FullRedundant).unwrap();
        for k in 0..dag.node_count() as u32 {
            for i in dag.splits(k) {
                assert_eq!(dag.node_of_split(i), Some(k));
                assert_eq!(pm.splits[i].joins_previous, i != dag.splits(k).start);
            }
        }
        assert_eq!(dag.node_of_split(pm.splits.len()), None);
        assert_eq!(dag.split_count(), pm.splits.len());
    }
}
