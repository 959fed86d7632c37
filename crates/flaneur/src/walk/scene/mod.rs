//! The memory HDoV scene tree (Shou 2002 ch. 6): the whole city in memory as a k-D tree
//! whose nodes carry internal LODs and one VD each ([`SceneTree`], `tree.rs`), and its
//! three traversals, CONV, VSC(η) and PB(n) ([`traverse`], `traverse.rs`). The walk
//! modes `vsc`, `pb` and `conv` draw with it (`flaneur::walk::scene`), which is why
//! it lives with the walk: it loads the whole city from a [`Database`](crate::Database),
//! above the HDoV-tree's pages, whose internal LODs and VDs it shares (`crate::hdov`).
//!
//! ```
//! # fn main() -> flaneur::Result<()> {
//! # let dir = tempfile::tempdir().unwrap();
//! # let (scene, file) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
//! # citygen::write_city(&citygen::CityConfig { objects: 40, ..Default::default() }, &scene)?;
//! # let opts = flaneur::BuildOptions {
//! #     visibility: Some(flaneur::visibility::VisibilityOptions {
//! #         resolution: 8, ..Default::default() }),
//! #     ..Default::default()
//! # };
//! # flaneur::build_from_scene(&scene, &file, &opts)?;
//! use flaneur::walk::scene::{traverse, SceneTree, Traversal};
//! let db = flaneur::Database::open(&file)?;
//! let mut tree = SceneTree::load(&db, &flaneur::progress::Silent)?;
//! let cells = db.visibility()?.unwrap();
//! let cell = cells.cells[0].id;
//! tree.enter(&db, cell)?;
//! let (row, column) = cells.grid.place(cell);
//! let eye = flaneur::path::Pose {
//!     time: 0.0,
//!     position: cells.grid.cell_bounds(row, column).center(),
//!     yaw: 0.0,
//!     pitch: 0.0,
//! };
//! let frustum = eye.camera()?.frustum();
//! let conv = traverse(&tree, Traversal::Conv, &frustum)?;
//! let vsc = traverse(&tree, Traversal::Vsc { eta: 0.001 }, &frustum)?;
//! assert!(vsc.triangles <= conv.triangles);
//! # Ok(()) }
//! ```
//!
//! Walks over the memory HDoV scene tree (Shou 2002 ch. 6, `flaneur walk DB --mode
//! vsc|pb|conv`): the whole city loaded into a [`SceneTree`] once, then each frame the
//! eye's viewcell found (its VDs brought in through the tree's hash table on a change
//! of cell) and the tree traversed by VSC(η), PB(n) or CONV, view frustum culling in
//! all three; what the traversal chose is what the frame draws.
//!
//! A viewpoint outside every viewcell keeps the VDs of the last cell it was in (the
//! thesis's run-time phase is for viewpoints within the cells); one before any cell
//! is drawn by CONV. Both are counted ([`SceneSummary::frames_outside`],
//! [`SceneSummary::frames_conv`]). Frame time is the walk's own: the VD update, the
//! traversal, bringing the object buffer to what it chose, and culling.
//!
//! ```
//! # fn main() -> flaneur::Result<()> {
//! # let dir = tempfile::tempdir().unwrap();
//! # let (scene, file) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
//! # citygen::write_city(&citygen::CityConfig { objects: 40, ..Default::default() }, &scene)?;
//! # let opts = flaneur::BuildOptions {
//! #     visibility: Some(flaneur::visibility::VisibilityOptions {
//! #         resolution: 8, ..Default::default() }),
//! #     ..Default::default()
//! # };
//! # flaneur::build_from_scene(&scene, &file, &opts)?;
//! use flaneur::walk::scene::{SceneConfig, SceneReport, SceneTree, Traversal};
//! use flaneur::walk::{Frames, Playback, WalkState};
//! let db = flaneur::Database::open(&file)?;
//! // Loaded once (with a progress bar, say), for as many walks as the state runs.
//! let tree = SceneTree::load(&db, &flaneur::progress::Silent)?;
//! let mut state = WalkState::new(&db).with_scene_tree(tree);
//! let poses = flaneur::path::cell_walk(&db, 30, 0.5, 10.0, 3)?;
//! let cfg = SceneConfig::new(Traversal::Vsc { eta: 0.001 }).into();
//! let viewer = &mut Playback::path(&poses);
//! let report: SceneReport = state.run(&cfg, viewer, Frames::Keep)?.try_into()?;
//! assert_eq!(report.frames.len(), 30);
//! # Ok(()) }
//! ```

mod config;
mod mode;
mod report;
mod tally;
mod traverse;
mod tree;
mod walks;

pub use config::SceneConfig;
pub use report::{SceneFrame, SceneReport, SceneSummary};
pub use traverse::{
    traverse, traverse_screened, Active, SceneErrors, ScreenView, Traversal, Traversed,
    MAX_ATTEMPTS, PB_TAU_STEP,
};
pub use tree::{SceneNode, SceneTree};
pub(crate) use walks::walk;
