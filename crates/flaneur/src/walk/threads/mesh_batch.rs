//! Reading a batch of full meshes, as each loader thread of a walk does: the batch's
//! pages asked for at once (over HTTP coalesced and in parallel rather than a round trip
//! each; a local store reads them as it goes), then each mesh read and checked. A
//! damaged mesh where the viewer walks on past damage is left out; every other failure
//! is the caller's to decide on: a network's is asked for again (the REVIEW loader, its
//! refining lane and the PVS loader each in their own way), and a file changed under
//! the walk stops it whatever the viewer would rather.

use std::sync::Mutex;

use crate::database::Database;
use crate::error::{Error, Result};
use crate::rtree::ObjectEntry;
use crate::walk::buffer::Loaded;
use crate::walk::sink::LeftOut;

/// The meshes of `batch` that could be read, in order. Damage is left out in
/// `left_out` when it is kept; a network failure (the file changed under the walk
/// included), or any failure when damage is not kept, goes to `failed`, which stops the
/// batch by returning its error.
pub(crate) fn read_meshes<'e>(
    db: &Database,
    batch: impl IntoIterator<Item = &'e ObjectEntry> + Clone,
    left_out: Option<&Mutex<LeftOut>>,
    mut failed: impl FnMut(&ObjectEntry, Error) -> Result<()>,
) -> Result<Vec<Loaded>> {
    // A failed fetch is the mesh read's to report, naming its page.
    let extents: Vec<_> = batch.clone().into_iter().map(|e| e.mesh).collect();
    let _ = db.store().prefetch(&extents);
    let mut loaded = Vec::with_capacity(extents.len());
    for e in batch {
        match (db.mesh(e), left_out) {
            (Ok(mesh), _) => loaded.push(Loaded::new(*e, mesh)),
            (Err(err @ (Error::Remote { .. } | Error::RemoteChanged { .. })), _)
            | (Err(err), None) => failed(e, err)?,
            (Err(err), Some(l)) => {
                if let Ok(mut l) = l.lock() {
                    l.leave_out(e.id, &err);
                }
            }
        }
    }
    Ok(loaded)
}
