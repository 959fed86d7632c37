//! The figures of Zheng 2007 Tables 3.2 and 3.3 for one progressive mesh: edges,
//! construction time and memory of the full-, non- and mini-redundant DAGs, and the
//! share of the redundant edges the mini-redundant construction removes.
//!
//! Memory per vertex, as the thesis counts it (Fig. 3.18: the split, three attributes,
//! in- and out-edges per node), divided by the full mesh's vertex count: the DAG's
//! arrays in memory plus the splits as Fig. 3.5 lays them out (v_p, v_c's position and
//! normal, v_l, v_r, and the adjusted triangles with their count: 40 bytes and 4 per
//! adjusted triangle). The encoded size (what the database stores,
//! `flaneur::lod::Dag::to_bytes`) is reported beside it.
//!
//! The models to measure, the bumpy tori that stand in for the thesis's, are the
//! engine's (`flaneur::lod::bumpy_torus`): its own tests refine them too.

use std::time::{Duration, Instant};

use flaneur::error::Result;
use flaneur::lod::{Dag, DagConstruction, DagEdges, ProgressiveMesh};

/// One construction's figures (a column of Zheng Tables 3.2 and 3.3).
#[derive(Clone, Debug, PartialEq)]
pub struct ConstructionStats {
    /// Which construction.
    pub construction: DagConstruction,
    /// Edges (the thesis's "incoming edges").
    pub edges: usize,
    /// Time to build the edges from the progressive mesh: dependency lists, the
    /// construction's choice of parents, and the children lists. Attributes apart.
    pub build: Duration,
    /// The DAG's arrays in memory, attributes included, splits not.
    pub memory_bytes: usize,
    /// The DAG's encoded size ([`Dag::to_bytes`]).
    pub encoded_bytes: usize,
}

/// The DAG figures of one progressive mesh (Zheng Tables 3.2 and 3.3).
#[derive(Clone, Debug, PartialEq)]
pub struct DagStats {
    /// Vertices of the full mesh.
    pub vertices: usize,
    /// Triangles of the full mesh.
    pub triangles: usize,
    /// Vertex splits.
    pub splits: usize,
    /// DAG nodes: position collapses (a run of splits along a crease is one node).
    pub nodes: usize,
    /// The full-redundant DAG.
    pub full: ConstructionStats,
    /// The non-redundant DAG, when asked for (its construction can be slow).
    pub non: Option<ConstructionStats>,
    /// The mini-redundant DAG.
    pub mini: ConstructionStats,
    /// Time to compute the visibility attributes bottom-up (on the mini-redundant DAG).
    pub attributes: Duration,
    /// The splits as Fig. 3.5 stores them: 40 bytes and 4 per adjusted triangle each.
    pub split_bytes: usize,
}

impl DagStats {
    /// Redundant edges: those of the full-redundant DAG that the non-redundant one
    /// lacks. `None` without the non-redundant DAG.
    pub fn redundant_edges(&self) -> Option<usize> {
        self.non.as_ref().map(|non| self.full.edges - non.edges)
    }

    /// The share (0–1) of the redundant edges that the mini-redundant construction
    /// removes (the thesis's "Effi. of Mini.", 83 %); 1 when there are none.
    pub fn redundant_removed(&self) -> Option<f64> {
        let redundant = self.redundant_edges()?;
        if redundant == 0 {
            return Some(1.0);
        }
        Some((self.full.edges - self.mini.edges) as f64 / redundant as f64)
    }

    /// The mini-redundant DAG in memory with its splits, per vertex of the full mesh:
    /// the thesis's "Mem. of Mini." per vertex (about 84 bytes).
    pub fn memory_per_vertex(&self) -> f64 {
        self.bytes_per_vertex(&self.mini)
    }

    /// `construction`'s DAG in memory with the splits, per vertex of the full mesh: what
    /// [`DagStats::memory_per_vertex`] gives for the mini-redundant one.
    pub fn bytes_per_vertex(&self, construction: &ConstructionStats) -> f64 {
        (construction.memory_bytes + self.split_bytes) as f64 / self.vertices.max(1) as f64
    }

    /// The encoded mini-redundant DAG per vertex of the full mesh, splits not included.
    pub fn encoded_per_vertex(&self) -> f64 {
        self.mini.encoded_bytes as f64 / self.vertices.max(1) as f64
    }
}

/// Builds the DAG of `pm` by each construction and measures it (the figures of Zheng
/// Tables 3.2 and 3.3), the non-redundant one only when `with_non_redundant` is set.
///
/// An `Err` as for [`Dag::build`].
///
/// ```
/// use flaneur::lod::ProgressiveMesh;
/// use flaneur_bench::lod_dag_stats::dag_stats;
/// let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
/// let stats = dag_stats(&pm, true)?;
/// assert!(stats.mini.edges < stats.full.edges);
/// println!(
///     "edges {} / {} / {}, {:.0} % of the redundant ones removed, {:.0} bytes per vertex",
///     stats.full.edges,
///     stats.non.as_ref().map_or(0, |n| n.edges),
///     stats.mini.edges,
///     100.0 * stats.redundant_removed().unwrap_or(0.0),
///     stats.memory_per_vertex(),
/// );
/// # Ok::<(), flaneur::Error>(())
/// ```
pub fn dag_stats(pm: &ProgressiveMesh, with_non_redundant: bool) -> Result<DagStats> {
    let mut constructions = vec![
        DagConstruction::FullRedundant,
        DagConstruction::MiniRedundant,
    ];
    if with_non_redundant {
        constructions.push(DagConstruction::NonRedundant);
    }
    let mut built = Vec::with_capacity(3);
    for c in constructions {
        let started = Instant::now();
        let edges = DagEdges::build(pm, c)?;
        let took = started.elapsed();
        built.push((c, took, edges));
    }
    let (_, _, mini) = &built[1];
    let started = Instant::now();
    let attrs = mini.attributes(pm)?;
    let attributes_took = started.elapsed();

    let mut stats = built
        .into_iter()
        .map(|(c, build, edges)| {
            let dag = Dag::assemble(edges, attrs.clone())?;
            Ok(ConstructionStats {
                construction: c,
                edges: dag.edge_count(),
                build,
                memory_bytes: dag.memory_bytes(),
                encoded_bytes: dag.encoded_len(),
            })
        })
        .collect::<Result<Vec<ConstructionStats>>>()?;
    let non = (stats.len() == 3).then(|| stats.remove(2));
    let mini = stats.remove(1);
    let full = stats.remove(0);
    Ok(DagStats {
        vertices: pm.vertex_count(),
        triangles: pm.triangles_after(pm.splits.len()),
        splits: pm.splits.len(),
        nodes: attrs.len(),
        full,
        non,
        mini,
        attributes: attributes_took,
        split_bytes: pm.splits.iter().map(|s| 40 + 4 * s.adjusted.len()).sum(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use flaneur::lod::bumpy_torus;

    fn report(name: &str, stats: &DagStats) {
        let non = stats.non.as_ref();
        eprintln!(
            "{name}: {} vertices, {} triangles, {} splits, {} nodes\n  \
             edges full / non / mini: {} / {} / {}; redundant removed by mini: {:.1} %\n  \
             build full / non / mini: {:.2} / {:.2} / {:.2} ms; attributes {:.2} ms\n  \
             memory per vertex (mini + splits): {:.1} B; encoded mini DAG per vertex: {:.1} B; \
             in memory full / mini: {} / {} B",
            stats.vertices,
            stats.triangles,
            stats.splits,
            stats.nodes,
            stats.full.edges,
            non.map_or(0, |n| n.edges),
            stats.mini.edges,
            100.0 * stats.redundant_removed().unwrap_or(f64::NAN),
            stats.full.build.as_secs_f64() * 1e3,
            non.map_or(f64::NAN, |n| n.build.as_secs_f64() * 1e3),
            stats.mini.build.as_secs_f64() * 1e3,
            stats.attributes.as_secs_f64() * 1e3,
            stats.memory_per_vertex(),
            stats.encoded_per_vertex(),
            stats.full.memory_bytes,
            stats.mini.memory_bytes,
        );
    }

    #[test]
    fn bunny_mini_removes_most_redundant_edges() {
        let pm = ProgressiveMesh::build(&flaneur::scene::bunny()).unwrap();
        let stats = dag_stats(&pm, true).unwrap();
        report("bunny", &stats);
        let non = stats.non.as_ref().unwrap();
        assert!(non.edges < stats.mini.edges && stats.mini.edges < stats.full.edges);
        let removed = stats.redundant_removed().unwrap();
        assert!(removed >= 0.80, "{removed}");
        for c in DagConstruction::ALL {
            let dag = Dag::build(&pm, c).unwrap();
            let s = [&stats.full, non, &stats.mini]
                .into_iter()
                .find(|s| s.construction == c)
                .unwrap();
            assert_eq!(
                (s.edges, s.memory_bytes, s.encoded_bytes),
                (dag.edge_count(), dag.memory_bytes(), dag.to_bytes().len())
            );
        }
        assert_eq!(stats.nodes, pm.splits.len());
        assert_eq!(stats.triangles, 3674);
    }

    /// Models of the thesis's sizes (Table 3.1): about 70k triangles, and the
    /// largest, about 1.1M. Seconds even optimised; run with `--ignored` for the figures.
    #[test]
    #[ignore]
    fn thesis_sized_models() {
        for (name, mesh) in [
            ("bumpy torus", bumpy_torus(69_451)),
            (
                "bunny subdivided twice",
                flaneur::scene::bunny().subdivide().subdivide(),
            ),
            ("large bumpy torus", bumpy_torus(1_087_474)),
        ] {
            let started = Instant::now();
            let pm = ProgressiveMesh::build(&mesh).unwrap();
            eprintln!(
                "{name}: progressive mesh in {:.2} s",
                started.elapsed().as_secs_f64()
            );
            let stats = dag_stats(&pm, true).unwrap();
            report(name, &stats);
            assert!(stats.redundant_removed().unwrap() >= 0.80);
        }
    }
}
