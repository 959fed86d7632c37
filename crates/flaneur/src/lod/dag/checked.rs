//! What every encoding of the DAG shares: the magic its bytes begin with, and the check
//! of the content decoded from them. Version 1 (`codec`) and version 2 (`compact`) both
//! end their reading with it, so that bytes of either that pass are a DAG every
//! traversal can walk without an index check failing; it lies below both because `codec`
//! hands version-2 bytes on to `compact`.

use super::attrs::NodeAttrs;
use super::build::{Csr, DagConstruction, DagEdges};
use super::graph::Dag;

/// The first four bytes of an encoded DAG.
pub const DAG_MAGIC: [u8; 4] = *b"FDAG";

/// A DAG from its decoded parts, whatever their encoding, once its content is checked:
/// the runs cover the `s` splits, every node's parents ascend below it (acyclic, no
/// duplicate, node order topological), every attribute is in range.
pub(super) fn checked(
    construction: DagConstruction,
    run_starts: Vec<u32>,
    parents: Csr,
    attrs: Vec<NodeAttrs>,
    s: u32,
) -> std::result::Result<Dag, String> {
    let n = run_starts.len() - 1;
    if run_starts[n] != s {
        return Err(format!(
            "the runs cover {} splits, the header says {s}",
            run_starts[n]
        ));
    }
    let e = parents.items.len();
    if parents.starts[n] as usize != e {
        return Err(format!(
            "the parent lists hold {} edges, the header says {e}",
            parents.starts[n]
        ));
    }
    for k in 0..n {
        let row = parents.row(k);
        if row.iter().any(|&p| p as usize >= k) || row.windows(2).any(|w| w[0] >= w[1]) {
            return Err(format!(
                "node {k}'s parents {row:?} are not ascending below {k}"
            ));
        }
    }
    for (k, a) in attrs.iter().enumerate() {
        let ok = a.radius >= 0.0
            && a.radius.is_finite()
            && (0.0..=1.0).contains(&a.cone_sin)
            && a.error >= 0.0
            && a.error.is_finite();
        if !ok {
            return Err(format!("node {k}'s attributes {a:?} are out of range"));
        }
    }
    let children = parents.transpose();
    let edges = DagEdges {
        construction,
        run_starts,
        parents,
        children,
    };
    Dag::assemble(edges, attrs).map_err(|e| e.to_string())
}
