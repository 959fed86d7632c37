//! A PVS walk set up: the stored table and the prefetching rule, then the walk that
//! waits (`mode.rs`) or the one that never does (`never_wait.rs`).

use super::report::PvsRun;
use crate::database::Database;
use crate::error::Result;
use crate::prefetch::pvs::StoredPvs;
use crate::walk::pvs::{PvsFrame, PvsWalkConfig};
use crate::walk::sink::Viewer;
use crate::walk::walk_lods::WalkLods;

/// A PVS walk over `db`'s precomputed visibility as `cfg` says, the poses coming from
/// `viewer`: the walk session with the PVS mode (or, never waiting, its form with a
/// loader thread). Each frame's figures and its time on the viewer's thread, ms, go to
/// `each` as the frame ends.
pub(crate) fn walk_live<'db>(
    db: &'db Database,
    cfg: PvsWalkConfig,
    lods: &mut WalkLods<'db>,
    viewer: &mut dyn Viewer,
    each: impl FnMut((PvsFrame, f64)) -> Result<()>,
) -> Result<PvsRun> {
    let source = StoredPvs::new(db)?;
    let rule = cfg.prefetch.rule()?;
    if cfg.never_wait {
        return super::never_wait::walk_live(db, &source, &*rule, cfg.pace, lods, viewer, each);
    }
    super::mode::walk_waiting(db, &source, &*rule, lods, viewer, each)?;
    Ok(PvsRun::default())
}
