//! A session at the window: walks run one after another from where the viewer stands,
//! until the window closes. A key that changes the mode or the object buffer's budget
//! ends a walk and the next one starts with the change; a walk that fails is told of
//! and started again, so that a damaged page or a failing disk does not end the
//! session, unless it fails five times running. Apart from the window's workings
//! because it is the walk engine's side of the window: which walk runs, and with what.

use super::{Change, ViewMode, ViewOptions, ViewSummary, WalkWindow};
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::prefetch::pvs::DEFAULT_BORDER;
use flaneur::walk::lod_select::WalkLods;
use flaneur::walk::pvs_walk::{self, PvsPrefetch};
use flaneur::walk::review::{self, Preset, ReviewConfig};
use flaneur::walk::Pose;

/// Failed walks in a row that end the session: the walk is then not getting over it.
const FAILURES: usize = 5;

/// What a session at the window leaves: what it drew, and the poses walked (what
/// `--record` saves).
#[derive(Clone, Debug, Default)]
pub struct WindowSession {
    pub summary: ViewSummary,
    pub recorded: Vec<Pose>,
}

/// Opens the window on `db` as `opts` say and walks in `mode` until it closes: REVIEW
/// and BOX through [`review::walk_live_with`], PVS through [`pvs_walk::walk_pvs_live_with`] with
/// PBNP prefetching (REVIEW instead, said so, on a database without visibility).
/// `boxes` and `top_view` are how the window starts. `tell` is told each problem as it
/// happens (see [`WalkWindow::telling`]); `opened` is given the window once it is open,
/// before the first walk, to say what it draws on. An error when the window cannot
/// open, or when the walk failed five times running.
pub fn walk_at_window(
    db: &Database,
    opts: ViewOptions,
    mode: ViewMode,
    (boxes, top_view): (bool, bool),
    tell: impl FnMut(&str) + 'static,
    opened: impl FnOnce(&WalkWindow<'_>),
) -> Result<WindowSession> {
    let preset = |m: ViewMode| ReviewConfig {
        pace: None,
        ..ReviewConfig::preset(match m {
            ViewMode::Box => Preset::Box,
            _ => Preset::Optimal,
        })
    };
    let mut mode = mode;
    let mut cfg = preset(mode);
    let mut window = WalkWindow::open(db, opts, mode)?.telling(tell);
    window.boxes = boxes;
    window.top_view = top_view;
    opened(&window);
    // The walk's LOD selection, handed from walk to walk so that a restart keeps the
    // levels read and the objects refined.
    let mut lods = WalkLods::new(db);
    let mut failures = 0;
    loop {
        let walked = match mode {
            ViewMode::Pvs if !db.has_visibility() => {
                window.report(format!(
                    "{} has no visibility data (build it with --visibility): showing REVIEW",
                    db.store().path().display()
                ));
                mode = ViewMode::Review;
                window.mode = mode;
                continue;
            }
            ViewMode::Pvs => {
                let rule = PvsPrefetch::Pbnp {
                    border: DEFAULT_BORDER,
                };
                pvs_walk::walk_pvs_live_with(db, rule, &mut lods, |_| {}, &mut window).map(|_| ())
            }
            _ => review::walk_live_with(db, &cfg, &mut lods, |_| {}, &mut window).map(|_| ()),
        };
        match walked {
            Ok(()) => failures = 0,
            Err(e) => {
                failures += 1;
                window.report(format!(
                    "the walk stopped: {e}; going on from where you stand"
                ));
                if failures >= FAILURES {
                    return Err(Error::Invalid(format!(
                        "the walk failed five times running; last: {e}"
                    )));
                }
            }
        }
        if window.closed() {
            break;
        }
        match window.change {
            Some(Change::Mode(m)) => {
                cfg = ReviewConfig {
                    memory_budget: cfg.memory_budget,
                    ..preset(m)
                };
                mode = m;
                window.mode = m;
            }
            Some(Change::Budget(f)) => {
                cfg.memory_budget = ((cfg.memory_budget as f32 * f) as usize).max(1 << 20);
                window.report(format!(
                    "object buffer budget {:.0} MiB",
                    cfg.memory_budget as f64 / 1048576.0
                ));
            }
            None => {}
        }
        window.resume();
    }
    Ok(WindowSession {
        summary: std::mem::take(&mut window.summary),
        recorded: std::mem::take(&mut window.recorded),
    })
}
