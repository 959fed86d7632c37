//! The PVS walk (`flaneur walk DB --mode pvs`): a camera path over a database built with
//! `--visibility`, the viewer drawing its current viewcell's PVS while a client
//! prefetches neighbours' PVS rows with SNP or PBNP (Zheng 2007 ch. 7) from the stored
//! table, every page read counted.
//!
//! A pose whose eye is in no walkable cell (above a roof, off the grid) draws nothing
//! new and asks for nothing: the client keeps what it holds and the frame counts as
//! outside. That is the walk's choice; the prefetcher itself refuses such positions.
//!
//! Drawn (a [`Playback`](super::Playback) to a renderer), the objects the client holds are loaded
//! into an object buffer as they arrive and dropped when it evicts them, and each frame
//! draws the current cell's PVS (the last cell's, outside cells) within the frustum.
//! Those mesh reads are the renderer's: a frame's page count is taken before them.
//!
//! Never waiting ([`PvsWalkConfig::never_wait`], ours): the client runs on a loader
//! thread of its own, which reads the rows and meshes it asks for while the viewer's
//! thread only takes what has arrived, so a slow disk or a round trip over HTTP shows as
//! visual misses, never as a long frame. The client's round trip is then measured in
//! frames, and LANP ([`PvsPrefetch::Lanp`]) looks as far ahead as the viewer may go in
//! it (`prefetch::pvs::Lanp`).
//!
//! Here: the settings, the walk [`walk::run`](super::run) walks and the figures it
//! reports. The frame loop
//! is the walk session's (`walk/session.rs`), the client the PVS mode's
//! (`walk/pvs/mode.rs`; never waiting, `never_wait.rs` and its `loader.rs`, the two
//! chosen by `run.rs`).

mod config;
mod index_entries;
mod loader;
mod mode;
mod never_wait;
mod report;
mod run;
mod tally;
mod walks;

pub use config::{PvsPrefetch, PvsWalkConfig};
pub use report::{PvsFrame, PvsWalkReport};
pub(crate) use walks::walk;
