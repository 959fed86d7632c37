//! A VISUAL walk set up: the HDoV-tree's scheme, the node cache and the searcher, then
//! the walk that waits (`mode.rs`) or the one that never does (`never_wait.rs`).

use super::never_wait::NeverWaitRun;
use super::search::Searcher;
use crate::cache::{policy_by_name, BufferPool, CacheStats};
use crate::database::Database;
use crate::error::{Error, Result};
use crate::hdov::NodeErrors;
use crate::walk::sink::Viewer;
use crate::walk::visual::{VisualConfig, VisualFrame};
use crate::walk::walk_lods::WalkLods;

/// A VISUAL walk under `cfg` with the poses coming from `viewer`: the walk session with
/// the VISUAL mode. Each frame's figures go to `each` as the frame ends (a never-wait
/// walk's at its end, their misses counted then); the node cache's figures are returned.
pub(crate) fn walk_live<'db>(
    db: &'db Database,
    cfg: &VisualConfig,
    lods: &mut WalkLods<'db>,
    viewer: &mut dyn Viewer,
    mut each: impl FnMut(VisualFrame) -> Result<()>,
) -> Result<(Option<CacheStats>, NeverWaitRun)> {
    cfg.validate()?;
    let head = db.hdov_head()?;
    let scheme = match cfg.scheme {
        Some(s) if head.schemes.iter().any(|t| t.0 == s) => s,
        Some(s) => {
            return Err(Error::Invalid(format!(
                "{} has no {} scheme of its HDoV-tree (rebuild with --hdov {})",
                db.store().path().display(),
                s.name(),
                s.name()
            )))
        }
        None => head.smallest_scheme()?,
    };
    let pool = match &cfg.node_cache {
        Some((policy, bytes)) => Some(BufferPool::new(
            db.store(),
            *bytes,
            policy_by_name(policy)?,
        )?),
        None => None,
    };
    let tolerant = viewer.skips_damaged();
    let search = Searcher {
        db,
        eta: cfg.eta,
        scheme,
        pool: pool.as_ref(),
        tolerant,
        dov_tau: cfg.dov_tau,
        finer_of: cfg.finer_of(),
        selection: cfg.selection,
        tau: cfg.tau,
        faint_tau: cfg.faint_tau,
        errors: NodeErrors::default(),
    };
    let search = &search;
    db.reset_io();
    let mut walked = 0;
    let mut counted = |f: VisualFrame| {
        walked += 1;
        each(f)
    };
    let run = if cfg.never_wait {
        super::never_wait::walk_live(db, cfg, search, lods, viewer, &mut counted)?
    } else {
        super::mode::walk_waiting(db, cfg, search, lods, viewer, &mut counted)?;
        NeverWaitRun::default()
    };
    if walked == 0 {
        return Err(Error::Invalid("the walk had no poses".into()));
    }
    Ok((pool.as_ref().map(BufferPool::stats), run))
}
