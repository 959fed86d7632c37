//! Objects refined view by view somewhere else than in the walk: a stream server's
//! landmarks (Zheng 2007 ch. 5–6), whose selective meshes a client holds and the
//! server's batches change. A walk handed one ([`FrameSink::lod_remote`]) draws those
//! objects from it and the rest of the city as ever: their LOD selection, local
//! refinement and reads are skipped, the walk's retrieval still loads them (their boxes
//! and full meshes decide what is in view).
//!
//! [`FrameSink::lod_remote`]: super::FrameSink::lod_remote

use crate::error::Result;
use crate::geom::Camera;

use super::lod_select::RefinedView;

/// Selective meshes that another party refines, by object id.
pub trait RemoteRefinements {
    /// Whether object `id`'s selective mesh comes from here.
    fn refines(&self, id: u64) -> bool;

    /// A frame seen by `camera` begins, before any object of it is drawn: say where
    /// the viewer is, and take the updates that have arrived.
    fn frame(&mut self, camera: &Camera) -> Result<()>;

    /// Triangles of object `id`'s selective mesh now (0 when it is not refined here).
    fn triangles(&self, id: u64) -> usize;

    /// Object `id`'s selective mesh, its changes since the last call taken, as a
    /// renderer uploads it.
    fn refined(&mut self, id: u64) -> Option<RefinedView<'_>>;

    /// What it did lately, in a line for a display beside the picture; `None` for
    /// nothing to say.
    fn status(&self) -> Option<String> {
        None
    }
}
