//! The PVS walk as [`walk::run`](crate::walk::run) walks it: the run, each frame
//! numbered, tallied and handed on, none kept.

use super::config::PvsWalkConfig;
use super::report::PvsFrame;
use super::report::PvsWalkReport;
use super::tally::PvsTally;
use crate::database::Database;
use crate::error::Result;
use crate::walk::sink::Viewer;
use crate::walk::walk_lods::WalkLods;

/// Walks `viewer`'s poses over `db`'s precomputed visibility as `cfg` says, each frame
/// handed to `each` as it ends; the report's `frames` is empty, its figures whole.
pub(crate) fn walk<'db>(
    db: &'db Database,
    cfg: PvsWalkConfig,
    lods: &mut WalkLods<'db>,
    viewer: &mut dyn Viewer,
    each: &mut dyn FnMut(&PvsFrame) -> Result<()>,
) -> Result<PvsWalkReport> {
    cfg.validate()?;
    let mut tally = PvsTally::default();
    let mut index = 0;
    let run = super::run::walk_live(db, cfg, lods, viewer, |(mut f, ms)| {
        f.frame = index;
        tally.add(&f, ms);
        each(&f)?;
        index += 1;
        Ok(())
    })?;
    Ok(tally.report(cfg, run))
}
