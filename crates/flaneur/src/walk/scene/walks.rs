//! The scene-tree walks as [`walk::run`](crate::walk::run) walks them: the run, each
//! frame tallied and handed on, none kept.

use super::config::SceneConfig;
use super::report::SceneFrame;
use super::report::SceneReport;
use super::tally::SceneTally;
use crate::database::Database;
use crate::error::Result;
use crate::walk::scene::SceneTree;
use crate::walk::sink::Viewer;
use crate::walk::walk_lods::WalkLods;

/// Walks `viewer`'s poses over `tree` (loaded from `db`) under `cfg`, each frame handed
/// to `each` as it ends; the report's `frames` is empty, its summary whole.
pub(crate) fn walk<'db>(
    db: &'db Database,
    tree: &mut SceneTree,
    cfg: &SceneConfig,
    lods: &mut WalkLods<'db>,
    viewer: &mut dyn Viewer,
    each: &mut dyn FnMut(&SceneFrame) -> Result<()>,
) -> Result<SceneReport> {
    cfg.validate()?;
    let mut tally = SceneTally::default();
    super::mode::walk_live(db, tree, cfg, lods, viewer, |f| {
        tally.add(&f, cfg.traversal);
        each(&f)
    })?;
    Ok(SceneReport {
        config: *cfg,
        frames: Vec::new(),
        summary: tally.summary(),
    })
}
