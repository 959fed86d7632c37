//! Walks at a live viewer (a person at a window): walks run one after another from
//! where the viewer stands, until the viewer closes. A change the viewer asks for (the
//! mode, the object buffer's budget) ends a walk and the next one starts with it; a
//! walk that fails is told of and started again, so that a damaged page or a failing
//! disk does not end the session, unless it fails five times running. Here rather than
//! in the window because it is the walk engine's side of the window: which walk runs,
//! and with what; the window only supplies poses and draws frames.

use super::review::{self, Preset, ReviewConfig};
use super::visual::{self, VisualConfig, DEFAULT_ETA};
use super::walk_lods::WalkLods;
use super::Viewer;
use crate::database::Database;
use crate::error::{Error, Result};
use crate::hdov::Selection;
use crate::prefetch::pvs::DEFAULT_BORDER;
use crate::walk::pvs::{self, PvsPrefetch, PvsWalkConfig};
use crate::walk::scene::{self, SceneConfig};
use crate::walk::scene::{SceneTree, Traversal};

/// Failed walks in a row that end the session: the walk is then not getting over it.
const FAILURES: usize = 5;

/// The walk modes a live viewer can show so far.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewMode {
    /// CSearch over disk cells with the index cache and prefetching (Shou 2002 §4.4).
    Review,
    /// Plain BOX queries over disk cells.
    Box,
    /// The current viewcell's PVS, neighbours prefetched (a database built with
    /// visibility).
    Pvs,
    /// The HDoV-tree searched from the current viewcell under the viewer's η (a
    /// database built with visibility and the tree).
    Visual,
    /// The memory scene tree traversed by VSC under the viewer's η (a database built
    /// with visibility; the tree is loaded when first shown).
    Vsc,
    /// The memory scene tree under the viewer's polygon budget (PB).
    Pb,
    /// The memory scene tree with view frustum culling only (CONV).
    Conv,
}

impl ViewMode {
    /// The mode's name, as the CLI's `--mode` spells it.
    pub fn name(self) -> &'static str {
        match self {
            ViewMode::Review => "review",
            ViewMode::Box => "box",
            ViewMode::Pvs => "pvs",
            ViewMode::Visual => "visual",
            ViewMode::Vsc => "vsc",
            ViewMode::Pb => "pb",
            ViewMode::Conv => "conv",
        }
    }
}

/// What a live viewer asks the walk to change: the walk ends its run and starts again
/// from where the viewer stands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Change {
    /// Another mode.
    Mode(ViewMode),
    /// The object buffer's budget, times this factor.
    Budget(f32),
}

/// A viewer that walks live: besides poses and frames ([`Viewer`]), it says when it is
/// closed and what change it asks for, shows the mode walked, and is told what went
/// wrong.
pub trait LiveViewer: Viewer {
    /// Whether the person ended the session.
    fn closed(&self) -> bool;

    /// The change asked for during the walk that just ended, if any.
    fn change(&self) -> Option<Change>;

    /// The mode walked from now on.
    fn show_mode(&mut self, mode: ViewMode);

    /// A problem met and got over, or a setting changed, in words.
    fn report(&mut self, what: String);

    /// Readies the viewer for the next walk, from where this one stopped.
    fn resume(&mut self);

    /// The DoV threshold η a VISUAL or VSC walk searches under.
    fn eta(&self) -> f32 {
        DEFAULT_ETA
    }

    /// The polygon budget a PB walk draws under, triangles a frame.
    fn polygon_budget(&self) -> u64 {
        DEFAULT_BUDGET
    }

    /// The rule that picks a VISUAL, VSC or PB walk's internal LODs and levels, under
    /// the viewer's LOD τ: ours by default.
    fn selection(&self) -> Selection {
        Selection::Screen
    }
}

/// The polygon budget a live PB walk draws under unless the viewer says otherwise:
/// Fig. 6.7's smallest, 20,000 triangles.
pub const DEFAULT_BUDGET: u64 = 20_000;

/// The REVIEW settings a live walk in `mode` takes: Optimal (BOX for [`ViewMode::Box`]),
/// unpaced, and over HTTP (`remote`) never waiting on a read, so that a round trip never
/// holds up a frame at the window (the missing objects are counted and drawn when they
/// come, coarse levels first).
fn review_config(mode: ViewMode, remote: bool) -> ReviewConfig {
    ReviewConfig {
        pace: None,
        never_wait: remote,
        ..ReviewConfig::preset(match mode {
            ViewMode::Box => Preset::Box,
            _ => Preset::Optimal,
        })
    }
}

/// The VISUAL settings a live walk under `eta` takes: the thesis's, unpaced, and over
/// HTTP (`remote`) never waiting on a read, the searches and meshes read on a loader
/// thread, the next viewcell's too.
fn visual_config(eta: f32, remote: bool) -> VisualConfig {
    VisualConfig {
        eta,
        pace: None,
        never_wait: remote,
        prefetch_k: remote.then_some(crate::walk::settings::DEFAULT_K),
        ..VisualConfig::default()
    }
}

/// Tells `viewer` `what` and shows it mode `to`, which the session walks from now on.
fn fall_back<V: LiveViewer>(viewer: &mut V, what: String, to: ViewMode) -> ViewMode {
    viewer.report(what);
    viewer.show_mode(to);
    to
}

/// A mode's name as a report says it: REVIEW, PVS.
fn shown(mode: ViewMode) -> String {
    mode.name().to_uppercase()
}

/// Walks `db` at `viewer`, starting in `mode`, until the viewer closes: REVIEW and BOX
/// as [`review::walk_live`] walks them (unpaced: a person sets the pace; over HTTP never
/// waiting on a read, [`ReviewConfig::never_wait`]), PVS as
/// [`pvs::walk_pvs_live`] does with PBNP prefetching (over HTTP LANP, never
/// waiting; REVIEW instead, said so, on a database without visibility), VISUAL as [`visual::walk_live`] does under the
/// viewer's [η](LiveViewer::eta) (over HTTP never waiting, the next viewcell prefetched; PVS instead, said so, on a database without the
/// HDoV-tree), VSC, PB and CONV as [`scene::walk_live`] does over the memory scene
/// tree, loaded when first shown (REVIEW instead, said so, without visibility).
/// LOD selection's state is kept from walk to walk, so that a restart keeps the levels
/// read and the objects refined. An error when the walk failed five times running.
///
/// ```no_run
/// # fn run(db: &flaneur::Database, window: &mut impl flaneur::walk::live::LiveViewer) -> flaneur::Result<()> {
/// use flaneur::walk::live::{self, ViewMode};
/// live::run(db, ViewMode::Review, window)?;
/// # Ok(()) }
/// ```
pub fn run<V: LiveViewer>(db: &Database, mode: ViewMode, viewer: &mut V) -> Result<()> {
    let remote = db.remote_stats().is_some();
    let preset = |m: ViewMode| review_config(m, remote);
    let mut mode = mode;
    let mut cfg = preset(mode);
    viewer.show_mode(mode);
    let mut lods = WalkLods::new(db);
    let mut tree: Option<SceneTree> = None;
    let mut failures = 0;
    loop {
        if let Some((what, to)) = lacking(db, mode)? {
            let path = db.store().path().display();
            mode = fall_back(
                viewer,
                format!("{path} has {what}: showing {}", shown(to)),
                to,
            );
            continue;
        }
        let walked = match mode {
            ViewMode::Vsc | ViewMode::Pb | ViewMode::Conv => {
                if tree.is_none() {
                    viewer.report("loading the scene tree: every object and its LODs".into());
                    match SceneTree::load(db, &crate::progress::Silent) {
                        Ok(t) => tree = Some(t),
                        Err(e) => {
                            let what = format!(
                                "the scene tree could not be loaded: {e}; showing {}",
                                shown(ViewMode::Review)
                            );
                            mode = fall_back(viewer, what, ViewMode::Review);
                            continue;
                        }
                    }
                }
                let how = match mode {
                    ViewMode::Vsc => Traversal::Vsc { eta: viewer.eta() },
                    ViewMode::Pb => Traversal::Pb {
                        budget: viewer.polygon_budget(),
                    },
                    _ => Traversal::Conv,
                };
                let tree = tree.as_mut().expect("loaded above");
                let cfg = SceneConfig {
                    selection: viewer.selection(),
                    tau: viewer.lod_tau().unwrap_or(0.0),
                    ..SceneConfig::new(how)
                };
                scene::walk_live_with(db, tree, &cfg, &mut lods, |_| {}, viewer).map(|_| ())
            }
            ViewMode::Visual => {
                let cfg = VisualConfig {
                    selection: viewer.selection(),
                    tau: viewer.lod_tau().unwrap_or(0.0),
                    ..visual_config(viewer.eta(), remote)
                };
                visual::walk_live_with(db, &cfg, &mut lods, |_| {}, viewer).map(|_| ())
            }
            ViewMode::Pvs => {
                // Over HTTP the client looks as far ahead as the round trip asks, and
                // the viewer never waits on it.
                let border = DEFAULT_BORDER;
                let cfg = PvsWalkConfig {
                    prefetch: if remote {
                        PvsPrefetch::Lanp { border }
                    } else {
                        PvsPrefetch::Pbnp { border }
                    },
                    never_wait: remote,
                    pace: None,
                };
                pvs::walk_pvs_live_with(db, cfg, &mut lods, |_| {}, viewer).map(|_| ())
            }
            _ => review::walk_live_with(db, &cfg, &mut lods, |_| {}, viewer).map(|_| ()),
        };
        match walked {
            Ok(()) => failures = 0,
            Err(e) => {
                failures += 1;
                viewer.report(format!(
                    "the walk stopped: {e}; going on from where you stand"
                ));
                if failures >= FAILURES {
                    return Err(Error::Invalid(format!(
                        "the walk failed five times running; last: {e}"
                    )));
                }
            }
        }
        if viewer.closed() {
            return Ok(());
        }
        match viewer.change() {
            Some(Change::Mode(m)) => {
                cfg = ReviewConfig {
                    memory_budget: cfg.memory_budget,
                    ..preset(m)
                };
                mode = m;
                viewer.show_mode(m);
            }
            Some(Change::Budget(f)) => {
                cfg.memory_budget = ((cfg.memory_budget as f32 * f) as usize).max(1 << 20);
                viewer.report(format!(
                    "object buffer budget {:.0} MiB",
                    cfg.memory_budget as f64 / 1048576.0
                ));
            }
            None => {}
        }
        viewer.resume();
    }
}

/// What `db` lacks to show `mode`, and the mode it falls back to; `None` when it can.
fn lacking(db: &Database, mode: ViewMode) -> Result<Option<(&'static str, ViewMode)>> {
    Ok(match mode {
        ViewMode::Pvs | ViewMode::Vsc | ViewMode::Pb | ViewMode::Conv if !db.has_visibility() => {
            Some((
                "no visibility data (build it with --visibility)",
                ViewMode::Review,
            ))
        }
        ViewMode::Visual if db.hdov()?.is_none() => Some((
            "no HDoV-tree (build it with --visibility --hdov)",
            ViewMode::Pvs,
        )),
        _ => None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_live_walk_over_http_never_waits_and_a_local_one_walks_as_the_thesis() {
        for mode in [ViewMode::Review, ViewMode::Box] {
            let local = review_config(mode, false);
            let remote = review_config(mode, true);
            assert!(!local.never_wait && remote.never_wait, "{mode:?}");
            assert_eq!((local.pace, remote.pace), (None, None));
            assert_eq!(local.retrieval, remote.retrieval);
            assert_eq!(local.index_cache, remote.index_cache);
            assert_eq!(local.prefetch_k, remote.prefetch_k);
        }
        let (local, remote) = (visual_config(0.01, false), visual_config(0.01, true));
        assert!(!local.never_wait && remote.never_wait);
        assert_eq!((local.prefetch_k, local.pace), (None, None));
        assert!(remote.prefetch_k.is_some() && remote.pace.is_none());
        assert_eq!((local.eta, remote.eta), (0.01, 0.01));
        let retrieval = |m| review_config(m, false).retrieval;
        assert_eq!(retrieval(ViewMode::Box), review::Retrieval::Box);
        assert_eq!(retrieval(ViewMode::Review), review::Retrieval::CSearch);
    }
}
