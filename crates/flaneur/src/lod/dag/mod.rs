//! The DAG hierarchy of a progressive mesh's vertex splits — Zheng 2007 ch. 3: the
//! legality condition that orders them (§3.2), the full-, non- and mini-redundant
//! constructions of its edges (§3.3), the visibility attributes of its nodes (§3.4),
//! and its checked byte format.

mod attrs;
mod build;
mod codec;
mod graph;

pub(super) use attrs::attributes;
pub use attrs::NodeAttrs;
pub(super) use build::{choose_parents, potentials, run_starts};
pub use codec::{DAG_MAGIC, DAG_VERSION};
pub use graph::{Dag, DagConstruction};
