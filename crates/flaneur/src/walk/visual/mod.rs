//! The VISUAL walkthrough (Shou 2002 §5.8.5, `flaneur walk DB --mode visual`): a camera
//! path over a database built with `--visibility --hdov`, each frame drawing what the
//! HDoV-tree finds from the eye's viewcell under the DoV threshold η, each object or
//! group of objects at the detail its DoV deserves; every page read counted.
//!
//! Each frame the eye's viewcell is found. On a change of cell the tree is searched
//! (Fig. 5.4, through a node cache) and the search's finds are loaded by **delta**: a
//! find already in the object buffer at the level it now deserves is not read again
//! (the thesis's hash set of buffered models), one at another level is read at that
//! level, and what the new cell does not find is dropped. Objects keep their ids;
//! nodes drawn at an internal LOD are held under ids that carry
//! [`GROUP_ID`](super::GROUP_ID), so that the two never meet. A frame draws its cell's
//! finds within the frustum.
//!
//! Named departures and choices:
//! - **Outside every viewcell** (over a building, off the grid, or above the cells' eye
//!   heights: a viewcell is a box, and its PVS holds for eyes within it) the walk falls back to
//!   REVIEW's spatial query: a BOX query of the disk cell SF times the frustum's box,
//!   asked again when the frustum leaves it, its objects loaded at full detail (delta
//!   too); those frames are counted ([`VisualSummary::frames_outside`]).
//! - **Next-cell prefetch** ([`VisualConfig::prefetch_k`]) is ours, not the thesis's
//!   (its VISUAL has none): a thread searches and loads the viewcell the eye will be in
//!   k seconds on, along its motion, so that entering it reads nothing on the viewer's
//!   thread. Off by default; `bench visual-vs-review` measures it on and off.
//! - A walk is paced to the path's clock ([`VisualConfig::pace`]), with or without the
//!   prefetch: frames back to back run with caches a viewer's frames would not have
//!   (warm from the frame before), which flatters the steady frames about 4× here, and a
//!   prefetch thread would not get a viewer's time. The pages a frame counts are those
//!   read on both threads from the start of its retrieval, its wait for the clock
//!   included (where a prefetch does most of its reading).
//! - The memory held is not capped: it is what the cell's finds take (and the
//!   prefetched cell's), reported as [`VisualSummary::peak_buffer_bytes`], the thesis's
//!   "maximum memory used".
//! - A find whose mesh or internal LOD cannot be read stops the walk with the error
//!   naming the page; for a viewer that [walks on](super::Viewer::skips_damaged) it is
//!   left out instead, counted and told of.
//!
//! Here: the settings, the walk [`walk::run`](super::run) walks and the figures it
//! reports. The frame loop
//! is the walk session's (`walk/session.rs`), the retrieval the VISUAL mode's
//! (`walk/visual/`: `run.rs` sets a walk up, `mode.rs` waits, `never_wait.rs` and
//! `loader.rs` never wait, and `search.rs` is what both search with).
//!
//! ```
//! # fn main() -> flaneur::Result<()> {
//! # let dir = tempfile::tempdir().unwrap();
//! # let (scene, file) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
//! # citygen::write_city(&citygen::CityConfig { objects: 40, ..Default::default() }, &scene)?;
//! # let opts = flaneur::BuildOptions {
//! #     visibility: Some(flaneur::visibility::VisibilityOptions {
//! #         resolution: 8, ..Default::default() }),
//! #     hdov: Some(Default::default()),
//! #     ..Default::default()
//! # };
//! # flaneur::build_from_scene(&scene, &file, &opts)?;
//! use flaneur::walk::{self, visual, Frames, Playback};
//! let db = flaneur::Database::open(&file)?;
//! let poses = flaneur::path::cell_walk(&db, 40, 0.5, 10.0, 3)?;
//! let cfg = visual::VisualConfig::default().into();
//! let viewer = &mut Playback::path(&poses);
//! let report: visual::VisualReport = walk::run(&db, &cfg, viewer, Frames::Keep)?.try_into()?;
//! assert_eq!(report.frames.len(), 40);
//! assert!(report.summary.searches >= 1);
//! # Ok(()) }
//! ```

mod config;
mod loader;
mod mode;
mod never_wait;
mod report;
mod run;
mod screen;
mod search;
mod tally;
mod walks;

pub use config::{VisualConfig, DEFAULT_ETA, DEFAULT_NODE_CACHE, FAINT_TAU_STRETCH};
pub use report::{VisualFrame, VisualReport, VisualSummary};
pub use screen::{faint_tau_scale, screen_test};
pub(crate) use walks::walk;
