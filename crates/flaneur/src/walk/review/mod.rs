//! The REVIEW walkthrough (Shou 2002 §4.1–4.4), headless: a camera path in, per-frame
//! figures out.
//!
//! Each frame: the frustum cell (the box around the view frustum) is tested against
//! the disk cell; when it leaves, a new disk cell — the frustum cell scaled by SF on
//! the ground, centred on it — is queried with BOX or CSearch, and the meshes it
//! returns are loaded into the object buffer (evicting by Fig. 4.8 when over budget).
//! The buffer is then culled against the frustum (ViewCulling, Fig. 4.15) and the
//! drawn objects' triangles gathered. With prefetching, a background thread queries
//! the cell predicted at F' = F + k·velocity (F: centre of the far clip plane, §4.2.5:
//! the disk cell of the frustum moved by k seconds of the viewer's motion) before the
//! viewer gets there; index pages go through the index cache when one is
//! configured. The four configurations of §4.4 are presets.
//!
//! Here: REVIEW's settings, the walk [`walk::run`](super::run) walks and the figures it
//! reports; the
//! defaults and checks every walk shares are `walk::settings`'.
//! The frame loop is the walk session's (`walk/session.rs`), the retrieval the REVIEW
//! mode's (`walk/review/mode.rs`, set up with its threads by `run.rs`), the motion
//! prediction `prefetch::motion`'s.
//!
//! Prefetching follows Fig. 4.11: the prefetched cell C2 is searched (CSearch against
//! the history) while the viewer is still in C1, and its objects go into the buffer as
//! soon as they arrive, its cell into the history; when the frustum cell leaves C1 and
//! C2 holds it, C2 becomes the disk cell with no I/O on the viewer's thread. If the
//! prediction was wrong, the viewer's own query is a CSearch against C1 and C2 both.
//!
//! Departures, named: a prefetch is started when the frustum cell, grown by one
//! second of motion, would leave the disk cell (the thesis says "when approaching the
//! boundary"); the predicted cell holds the frusta from now to k seconds ahead, and
//! the frusta the viewer turns through on the way when it is turning (the thesis
//! predicts the translation only, and a turning viewer leaves such a cell every few
//! degrees); it is asked again from the same disk cell only when the prediction has
//! moved by a quarter of a cell; a prefetched result is dropped if an eviction happened
//! since it was asked for (an eviction restarts the CSearch history, so an older
//! complement could miss objects); BOX reloads every object of its cell (the thesis's
//! BOX has "no optimization") and has no prefetching. A walk with prefetching is paced
//! to the path's clock (by default four times faster than real time, see
//! [`ReviewConfig::pace`]): unpaced, the frames of a headless walk take microseconds and
//! the prefetch thread never gets the time a viewer would give it. Frame 0 loads the
//! first cell from nothing and is reported apart from the walk's frame times.

mod config;
mod counts;
mod loader;
mod mode;
mod report;
mod run;
mod tally;

pub use config::{Preset, Retrieval, ReviewConfig, DEFAULT_INDEX_CACHE};
pub use report::{FrameStats, WalkReport, WalkSummary};
pub(crate) use run::walk;
