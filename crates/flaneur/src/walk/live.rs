//! Walks at a live viewer (a person at a window): walks run one after another from
//! where the viewer stands, until the viewer closes. A change the viewer asks for (the
//! mode, the object buffer's budget) ends a walk and the next one starts with it; a
//! walk that fails is told of and started again, so that a damaged page or a failing
//! disk does not end the session, unless it fails five times running. Here rather than
//! in the window because it is the walk engine's side of the window: which walk runs,
//! and with what; the window only supplies poses and draws frames.

use super::config::{WalkConfig, DEFAULT_BUDGET};
use super::review::{Preset, ReviewConfig};
use super::run::{Frames, WalkState};
use super::visual::{VisualConfig, DEFAULT_ETA};
use super::walk_mode::WalkMode;
use super::Viewer;
use crate::database::Database;
use crate::error::{Error, Result};
use crate::hdov::Selection;
use crate::prefetch::pvs::DEFAULT_BORDER;
use crate::walk::pvs::{PvsPrefetch, PvsWalkConfig};
use crate::walk::scene::{SceneConfig, SceneTree, Traversal};

/// Failed walks in a row that end the session: the walk is then not getting over it.
const FAILURES: usize = 5;

/// What a live viewer asks the walk to change: the walk ends its run and starts again
/// from where the viewer stands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Change {
    /// Another mode.
    Mode(WalkMode),
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
    fn show_mode(&mut self, mode: WalkMode);

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

/// The REVIEW settings a live walk in `mode` takes: Optimal (BOX for [`WalkMode::Box`]),
/// unpaced, and over HTTP (`remote`) never waiting on a read, so that a round trip never
/// holds up a frame at the window (the missing objects are counted and drawn when they
/// come, coarse levels first).
fn review_config(mode: WalkMode, remote: bool) -> ReviewConfig {
    ReviewConfig {
        pace: None,
        never_wait: remote,
        ..ReviewConfig::preset(match mode {
            WalkMode::Box => Preset::Box,
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
fn fall_back<V: LiveViewer>(viewer: &mut V, what: String, to: WalkMode) -> WalkMode {
    viewer.report(what);
    viewer.show_mode(to);
    to
}

/// A mode's name as a report says it: REVIEW, PVS.
fn shown(mode: WalkMode) -> String {
    mode.name().to_uppercase()
}

/// Walks `db` at `viewer`, starting in `mode`, until the viewer closes, each walk by
/// [`WalkState::run`]: REVIEW and BOX unpaced (a person sets the pace; over HTTP never
/// waiting on a read, [`ReviewConfig::never_wait`]), PVS with PBNP prefetching (over
/// HTTP LANP, never waiting; REVIEW instead, said so, on a database without
/// visibility), VISUAL under the viewer's [η](LiveViewer::eta) (over HTTP never
/// waiting, the next viewcell prefetched; PVS instead, said so, on a database without
/// the HDoV-tree), VSC, PB and CONV over the memory scene tree, loaded when first shown
/// (REVIEW instead, said so, without visibility). LOD selection's state and the scene
/// tree are kept from walk to walk, so that a restart keeps the levels read and the
/// objects refined. An error when the walk failed five times running.
///
/// ```no_run
/// # fn run(db: &flaneur::Database, window: &mut impl flaneur::walk::live::LiveViewer) -> flaneur::Result<()> {
/// use flaneur::walk::{live, WalkMode};
/// live::run(db, WalkMode::Review, window)?;
/// # Ok(()) }
/// ```
pub fn run<V: LiveViewer>(db: &Database, mode: WalkMode, viewer: &mut V) -> Result<()> {
    let remote = db.remote_stats().is_some();
    let preset = |m: WalkMode| review_config(m, remote);
    let mut mode = mode;
    let mut review = preset(mode);
    viewer.show_mode(mode);
    let mut state = WalkState::new(db);
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
        if mode.over_scene_tree() && !state.has_scene_tree() {
            viewer.report("loading the scene tree: every object and its LODs".into());
            match SceneTree::load(db, &crate::progress::Silent) {
                Ok(t) => state = state.with_scene_tree(t),
                Err(e) => {
                    let what = format!(
                        "the scene tree could not be loaded: {e}; showing {}",
                        shown(WalkMode::Review)
                    );
                    mode = fall_back(viewer, what, WalkMode::Review);
                    continue;
                }
            }
        }
        let cfg = live_config(mode, &review, &*viewer, remote);
        // A live walk hands its frames on: a session of any length in constant memory.
        let walked = state.run(&cfg, viewer, Frames::Each(&mut |_| Ok(())));
        match walked {
            Ok(_) => failures = 0,
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
                review = ReviewConfig {
                    memory_budget: review.memory_budget,
                    ..preset(m)
                };
                mode = m;
                viewer.show_mode(m);
            }
            Some(Change::Budget(f)) => {
                review.memory_budget = ((review.memory_budget as f32 * f) as usize).max(1 << 20);
                viewer.report(format!(
                    "object buffer budget {:.0} MiB",
                    review.memory_budget as f64 / 1048576.0
                ));
            }
            None => {}
        }
        viewer.resume();
    }
}

/// The walk a live `viewer` in `mode` takes: REVIEW and BOX under `review` (its budget
/// the person's), the others as the viewer's η, polygon budget, selection rule and LOD
/// τ say, over HTTP (`remote`) never waiting where the mode can.
fn live_config<V: LiveViewer>(
    mode: WalkMode,
    review: &ReviewConfig,
    viewer: &V,
    remote: bool,
) -> WalkConfig {
    let tau = viewer.lod_tau().unwrap_or(0.0);
    let scene = |how| {
        WalkConfig::Scene(SceneConfig {
            selection: viewer.selection(),
            tau,
            ..SceneConfig::new(how)
        })
    };
    match mode {
        WalkMode::Review | WalkMode::Box => WalkConfig::Review(review.clone()),
        WalkMode::Vsc => scene(Traversal::Vsc { eta: viewer.eta() }),
        WalkMode::Pb => scene(Traversal::Pb {
            budget: viewer.polygon_budget(),
        }),
        WalkMode::Conv => scene(Traversal::Conv),
        WalkMode::Visual => WalkConfig::Visual(VisualConfig {
            selection: viewer.selection(),
            tau,
            ..visual_config(viewer.eta(), remote)
        }),
        WalkMode::Pvs => {
            // Over HTTP the client looks as far ahead as the round trip asks, and the
            // viewer never waits on it.
            let border = DEFAULT_BORDER;
            WalkConfig::Pvs(PvsWalkConfig {
                prefetch: if remote {
                    PvsPrefetch::Lanp { border }
                } else {
                    PvsPrefetch::Pbnp { border }
                },
                never_wait: remote,
                pace: None,
            })
        }
    }
}

/// What `db` lacks to show `mode`, and the mode it falls back to; `None` when it can.
fn lacking(db: &Database, mode: WalkMode) -> Result<Option<(&'static str, WalkMode)>> {
    Ok(match mode {
        WalkMode::Pvs | WalkMode::Vsc | WalkMode::Pb | WalkMode::Conv if !db.has_visibility() => {
            Some((
                "no visibility data (build it with --visibility)",
                WalkMode::Review,
            ))
        }
        WalkMode::Visual if db.hdov()?.is_none() => Some((
            "no HDoV-tree (build it with --visibility --hdov)",
            WalkMode::Pvs,
        )),
        _ => None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_live_walk_over_http_never_waits_and_a_local_one_walks_as_the_thesis() {
        for mode in [WalkMode::Review, WalkMode::Box] {
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
        assert_eq!(
            retrieval(WalkMode::Box),
            crate::walk::review::Retrieval::Box
        );
        assert_eq!(
            retrieval(WalkMode::Review),
            crate::walk::review::Retrieval::CSearch
        );
    }
}
