//! Progressive meshes — Zheng 2007 ch. 2 (§2.1.1 the half-edge collapse, §2.1.2 the
//! quadric error metric, §2.2.1 the progressive mesh) and §3.2 (the vertex split's
//! content, Fig. 3.5): a mesh simplified into a base mesh and the vertex splits that
//! refine it back, serially or on all cores (El-Sana–Varshney), the discrete levels cut
//! from it, and its checked byte format.
//!
//! The choices the thesis leaves open — creases and seams, boundaries, normals, the
//! error's unit — are named in `simplify`'s top comment.

mod checked;
mod codec;
mod compact;
mod incidence;
mod levels;
mod parallel;
mod progressive;
mod quadric;
mod simplify;
mod topology;
mod vsplit;

use compact::PM_VERSION_QUANTISED;
pub use levels::{Level, PmCursor};
pub use parallel::{LevelReport, ParallelOptions, ParallelReport};
pub use progressive::{simplify_all, ProgressiveMesh};
#[cfg(test)]
pub(super) use topology::Adjacency;
pub use vsplit::{SelectiveMesh, SplitIds, VertexSplit, NO_TRIANGLE};
