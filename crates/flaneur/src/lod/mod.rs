//! The LOD core: progressive meshes built by quadric-ordered half-edge collapses, their
//! vertex splits in the thesis's implicit-index form, discrete levels cut from them, and
//! a sampled Hausdorff distance to measure the levels by.
//!
//! Zheng 2007 ch. 2 (§2.1.1 the half-edge collapse, §2.1.2 the quadric error metric,
//! §2.2.1 the progressive mesh) and §3.2 (the vertex split's content, Fig. 3.5). The
//! choices the thesis leaves open — creases and seams, boundaries, normals, the error's
//! unit — are named in `pm::simplify`'s top comment.
//!
//! - [`ProgressiveMesh::build`] simplifies one mesh; [`simplify_all`] many, on all cores;
//!   [`ProgressiveMesh::build_parallel`] one large mesh on all cores (El-Sana–Varshney).
//! - [`VertexSplit`] is the record; [`SelectiveMesh`] applies splits and collapses in place.
//! - [`PmCursor`], [`ProgressiveMesh::mesh_at_triangles`], [`ProgressiveMesh::mesh_at_error`]
//!   and [`ProgressiveMesh::levels`] give levels as plain meshes.
//! - [`hausdorff`] compares two meshes.
//! - [`bumpy_torus`] is a procedural model of any size, for tests and experiments.
//! - [`Dag`] orders the splits by what each needs present (Zheng ch. 3: the legality
//!   condition, the full-, non- and mini-redundant constructions, the visibility
//!   attributes of §3.4, a checked byte format); [`DagEdges`] and [`Dag::assemble`]
//!   build one in two steps, for the experiments that time them apart.
//! - [`Refiner`] refines a mesh through its [`Dag`] for a [`View`], frame by frame (Zheng
//!   ch. 4: the fronts, the three traversals, the compact selective mesh).
//! - [`VertexHierarchy`] reads the splits as Kim & Lee's binary vertex hierarchy for
//!   truly selective refinement, named ⟨tree-id, node-id⟩ ([`NodeName`]); a [`Front`]
//!   of it is a mesh, a [`CutMesh`] the same mesh kept by a client from cut vertices
//!   alone (a [`LeafMesh`] from its triangles' leaves, where crease runs leave no cut
//!   vertex), and [`SelectiveServer`] and [`SelectiveClient`] stream it view by view
//!   (Kim–Lee–Kobbelt 2004); [`BlockServer`] and [`BlockClient`] stream it in El-Sana's
//!   view-dependence blocks.
//! - Stored LODs: `flaneur build` keeps each object's chain of coarse levels (coarsest
//!   first so a coarse level reads few pages; its bytes open with [`CHAIN_MAGIC`]), and
//!   for large objects its progressive mesh ([`ProgressiveMesh::to_bytes`]) and DAG,
//!   found by id through a table in the database ([`LodOptions`], [`LodStats`]);
//!   `Database::lod_levels` ([`LevelInfo`]), `lod_mesh` and `progressive` read them
//!   back, and [`level_for`] is the criterion that picks a stored level for a view.
//!
//! The code is grouped by idea: `pm` (the progressive mesh, its levels and codec), `dag`
//! (the hierarchy of its splits), `refine` (view-dependent refinement through the DAG),
//! `selective` (truly selective refinement and its streaming) and `stored` (the LODs a build writes into the database and reads back).

mod dag;
#[cfg(test)]
pub(crate) mod fixtures;
mod hausdorff;
mod pm;
mod refine;
mod selective;
pub(crate) mod stored;
mod torus;

pub use dag::{Dag, DagConstruction, DagEdges, NodeAttrs};
pub use hausdorff::hausdorff;
pub(crate) use hausdorff::{hausdorff_above, Measured};
pub use pm::{
    simplify_all, Level, LevelReport, ParallelOptions, ParallelReport, PmCursor, ProgressiveMesh,
    SelectiveMesh, SplitIds, VertexSplit, NO_TRIANGLE,
};
pub use refine::{
    CompactMesh, Criteria, FrameReport, FrameStats, Fronts, MeshChanges, MeshMemory, NodeOperator,
    PassStats, RefineParams, Refiner, Traversal, View, THESIS_BUDGET, THESIS_MAX_WORK, THESIS_TAU,
};
pub use selective::{
    block_of, Block, BlockClient, BlockServer, CutMesh, CutVertexClient, Front, HeapIndex,
    LeafMesh, NodeName, Placement, RefineInfo, SelectiveBase, SelectiveClient, SelectiveServer,
    SelectiveSource, SwitchDown, VertexHierarchy, VsplitPacket,
};
pub(crate) use stored::LodWriter;
pub use stored::{
    distance_to, level_for, LevelInfo, LodOptions, LodReport, LodStats, CHAIN_MAGIC,
    DEFAULT_PM_THRESHOLD,
};
pub use torus::bumpy_torus;
