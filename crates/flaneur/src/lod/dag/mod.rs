//! The DAG hierarchy of a progressive mesh's vertex splits — Zheng 2007 ch. 3: the
//! legality condition that orders them (§3.2), the full-, non- and mini-redundant
//! constructions of its edges (§3.3), the visibility attributes of its nodes (§3.4),
//! and its checked byte format.
//!
//! The modules depend one way: `build` makes the edges ([`DagEdges`]), `attrs` computes
//! the attributes over finished edges, `graph` puts the two together as the [`Dag`] that
//! traversals walk, and `codec` reads and writes it (`compact` packs it for format
//! version 2; both check what they read with `checked`).

mod attrs;
mod build;
mod checked;
mod codec;
mod compact;
mod graph;
#[cfg(test)]
mod tests;

pub use attrs::NodeAttrs;
use compact::DAG_VERSION_PACKED;
pub use build::{DagConstruction, DagEdges};
pub use graph::Dag;
