//! View-dependent refinement through the DAG — Zheng 2007 ch. 4: the split and
//! collapse fronts (§4.2), the error criteria a view sets (§3.4), the traversal manager
//! and its three traversals (§4.3–4.4), and the selective mesh in compact arrays (§4.5),
//! wired into one [`Refiner`] that refines a mesh frame by frame.

mod criteria;
mod fronts;
mod mesh_update;
mod prefetch_hint;
mod refiner;
#[cfg(test)]
mod tests;
mod traversal;

pub use criteria::{Criteria, View};
pub(crate) use criteria::{NodeGeometry, ViewTest};
pub use fronts::Fronts;
pub use mesh_update::{CompactMesh, MeshChanges, MeshMemory};
pub use refiner::{
    FrameReport, FrameStats, NodeOperator, RefineParams, Refiner, THESIS_BUDGET, THESIS_MAX_WORK,
    THESIS_TAU,
};
pub use traversal::{PassStats, Traversal};
