//! The VISUAL walk as [`walk::run`](crate::walk::run) walks it: the run, each frame
//! tallied and handed on, none kept.

use super::config::VisualConfig;
use super::report::VisualFrame;
use super::report::VisualReport;
use super::tally::VisualTally;
use crate::database::Database;
use crate::error::Result;
use crate::walk::sink::Viewer;
use crate::walk::walk_lods::WalkLods;

/// Walks `viewer`'s poses over `db`'s HDoV-tree under `cfg`, each frame handed to
/// `each` as it ends (a never-wait walk's at its end: a frame's misses are known only
/// once its cell's finds have come); the report's `frames` is empty, its summary whole.
/// An error for a database without an HDoV-tree.
pub(crate) fn walk<'db>(
    db: &'db Database,
    cfg: &VisualConfig,
    lods: &mut WalkLods<'db>,
    viewer: &mut dyn Viewer,
    each: &mut dyn FnMut(&VisualFrame) -> Result<()>,
) -> Result<VisualReport> {
    let mut tally = VisualTally::default();
    let (node_cache, run) = super::run::walk_live(db, cfg, lods, viewer, |f| {
        tally.add(&f);
        each(&f)
    })?;
    let mut summary = tally.summary(node_cache);
    summary.failed_loads = run.failures.count;
    summary.last_load_error = run.failures.last;
    Ok(VisualReport {
        config: cfg.clone(),
        frames: Vec::new(),
        summary,
    })
}
