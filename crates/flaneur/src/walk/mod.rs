//! The walkthrough engine: a viewer's poses in; for each frame, the objects it sees read
//! from the database, kept in an object buffer, culled, selected at a level of detail
//! and handed to whoever draws them, every page counted.
//!
//! The one way to walk is [`run`]: a [`WalkConfig`] (which mode, with its settings), a
//! [`Viewer`] giving the poses and drawing the frames (a [`Playback`] of a camera path or
//! of generated poses to a [`FrameSink`], or a person at a window), and [`Frames`]: kept
//! in the [`Report`], or each [`Frame`] handed on as it ends for a walk of any length.
//! A [`WalkState`] keeps what walks at one viewer share (LOD selection's levels, the
//! memory scene tree) from one to the next.
//!
//! ```
//! # fn main() -> flaneur::Result<()> {
//! # let dir = tempfile::tempdir().unwrap();
//! # let (scene, file) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
//! # citygen::write_city(&citygen::CityConfig { objects: 60, ..Default::default() }, &scene)?;
//! # let opts = flaneur::BuildOptions { lod: None, ..Default::default() };
//! # flaneur::build_from_scene(&scene, &file, &opts)?;
//! use flaneur::walk::{self, review, Frames, Playback, WalkConfig};
//! let db = flaneur::Database::open(&file)?;
//! let poses = flaneur::path::street_walk(&db.bounds(), 30, 5.0, 10, 7)?;
//! // CSearch through the index cache, without prefetching (so unpaced).
//! let cfg = WalkConfig::Review(review::ReviewConfig::preset(review::Preset::Np));
//! let mut rows = 0;
//! let viewer = &mut Playback::path(&poses);
//! let report = walk::run(&db, &cfg, viewer, Frames::Each(&mut |f| {
//!     assert_eq!(f.index(), rows);
//!     rows += 1;
//!     Ok(())
//! }))?;
//! assert_eq!((report.frames_walked(), rows), (30, 30));
//! let review: review::WalkReport = report.try_into()?;
//! assert!(review.frames.is_empty() && review.summary.queries >= 1);
//! # Ok(()) }
//! ```
//!
//! Underneath, one walk session (`session.rs`) is the frame loop every mode shares. Each
//! frame the viewer gives a pose; the mode retrieves for it (brings the object buffer to
//! what the mode holds: loads, drops, evicts); the objects it offers are culled against
//! the frustum; the mode finishes its figures; [`lod_select`] picks each object's level
//! under the τ the viewer wants; the viewer is handed the frame, then its figures. The
//! modes (a folder each) are the session's retrieval strategies: REVIEW and BOX over disk
//! cells (Shou 2002 §4.1–4.4), the PVS client (Zheng 2007 ch. 7), VISUAL over the
//! HDoV-tree (Shou 2002 §5.8.5) and VSC, PB and CONV over the memory scene tree (ch. 6).
//! The loop and the modes are crate-private.
//!
//! One folder per walk mode, each with the same parts: `config.rs` (what the walk can
//! vary), `report.rs` (a frame's figures and the walk's), `walks.rs` (the walk [`run`]
//! calls, each frame tallied and handed on), `mode.rs` (the retrieval strategy the
//! session plays), `tally.rs` (the summary tallied a frame at a time, so that a walk that
//! hands its frames on reports what one that keeps them does) and, where the mode has
//! them, `run.rs` (the walk's setup: a waiting walk or a never-wait one),
//! `never_wait.rs` and `loader.rs`:
//! - [`review`]: REVIEW and BOX, their settings ([`review::ReviewConfig`], the presets
//!   of §4.4) and figures ([`review::WalkReport`]);
//! - [`pvs`]: the PVS walk, its prefetching rule ([`pvs::PvsPrefetch`]) and figures;
//! - [`visual`]: VISUAL over the HDoV-tree, its settings ([`visual::VisualConfig`]) and
//!   figures ([`visual::VisualReport`]);
//! - [`scene`]: the memory scene tree of Shou 2002 ch. 6 ([`scene::SceneTree`],
//!   [`scene::traverse`]) and the VSC, PB and CONV walks over it ([`scene::SceneConfig`],
//!   [`scene::SceneReport`]).
//!
//! Adding a mode, step by step:
//! 1. a folder `walk/<mode>/` with its `config.rs`, `report.rs` (its frame and its
//!    report), `mode.rs` (a `session::Mode`), `tally.rs` and `walks.rs` (its
//!    `pub(crate) fn walk(db, cfg, lods, viewer, each)`);
//! 2. a variant of [`WalkConfig`], of [`Frame`] and of [`Report`] (each a line per
//!    method: the compiler names every match that lacks it), and its arm in
//!    `WalkState::run` (`run.rs`);
//! 3. its name in [`WalkMode`] (what the CLI's `--mode` and the window's keys read).
//!
//! The CLI, the window and the benches need nothing more: they say which walk with a
//! [`WalkConfig`] and print or plot its [`Report`].
//!
//! Beside the modes:
//! - [`live`]: walks one after another at a live viewer (a window) as its person changes
//!   the mode or the budget ([`live::run`], [`live::LiveViewer`]);
//! - `walk_mode.rs`, `config.rs`, `frame.rs`, `report.rs`, `run.rs`, `playback.rs`: the
//!   mode names ([`WalkMode`]), the walk asked for ([`WalkConfig`]), a frame's and a
//!   walk's figures ([`Frame`], [`Report`]), the entry point ([`run`], [`Frames`],
//!   [`WalkState`]) and the viewer of given poses ([`Playback`]);
//! - [`lod_select`]: LOD selection, what each object is drawn at ([`lod_select::Drawn`],
//!   [`lod_select::REFINED`]) and its selector, counts and threshold;
//! - [`settings`]: the defaults and checks every walk mode shares (the frustum's depth,
//!   SF, k, the playback speed, the buffer's budget, the screen rule's τ);
//! - `threads/`: what the modes' loader threads share: the viewer's latest position
//!   handed over (a mailbox), a paced walk's clock, the order loads come in, batches of
//!   meshes read together, a prefetch's answer taken in time, coarse objects refined,
//!   and what loaders could not read.
//!
//! Camera paths, the poses a walk is given, are a module below the walk and the
//! prefetchers that predict from them: [`crate::path`].
//!
//! Re-exported here, flat, one idea per file:
//! - `sink.rs`: what a walk hands whoever draws it: [`FrameSink`] (a frame's
//!   [`Selection`]; [`NoSink`] draws nothing), [`Viewer`] (a sink that also gives the
//!   poses), [`FrameFigures`] (what a frame cost);
//! - `buffer.rs`: [`ObjectBuffer`], the object buffer and its eviction (Shou 2002
//!   §4.2.2, Fig. 4.8), of [`Loaded`] objects ([`mesh_bytes`] each), an eviction's
//!   [`Eviction`];
//! - `cells.rs`: the disk cells of Shou 2002 §4.1: [`disk_cell`] around an eye,
//!   [`scaled_cell`] (REVIEW's, SF times the frustum cell) and [`contains_ground`];
//! - `start.rs`: [`busiest_street`], where a viewer starts;
//! - `steer.rs`: [`Steer`], a person steering the camera with [`Move`] keys and the
//!   mouse, at [`WALK_SPEED`].
//!
//! Private beside them: the frame-time and cells-entered tallies every mode's
//! summary is made of (`frame_times.rs`, `cells_entered.rs`), and `frame_csv.rs`, the
//! frames of a report that keeps them as one CSV text.

mod buffer;
mod cells;
mod cells_entered;
mod config;
mod frame;
mod frame_csv;
mod frame_times;
pub mod live;
pub mod lod_select;
mod looked_at;
mod playback;
pub mod pvs;
mod remote;
mod report;
pub mod review;
mod run;
pub mod scene;
mod session;
pub mod settings;
mod sink;
mod start;
mod steer;
mod threads;
pub mod visual;
mod walk_lods;
mod walk_mode;

pub use buffer::{mesh_bytes, Eviction, Loaded, ObjectBuffer, GROUP_ID};
pub use cells::{contains_ground, disk_cell, scaled_cell};
pub use config::{WalkConfig, DEFAULT_BUDGET};
pub use frame::Frame;
pub use playback::{PathPoses, Playback};
pub use remote::RemoteRefinements;
pub use report::Report;
pub use run::{run, Frames, WalkState};
pub use sink::{FrameFigures, FrameSink, NoSink, Selection, Viewer};
pub use start::busiest_street;
pub use steer::{Move, Steer, WALK_SPEED};
pub use walk_mode::WalkMode;
