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
//! Here: the settings, the entry points and the figures a walk reports. The frame loop
//! is the walk session's (`walk/session.rs`), the retrieval the VISUAL mode's
//! (`walk/mode/visual.rs`).
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
//! use flaneur::{path, walk::visual};
//! let db = flaneur::Database::open(&file)?;
//! let poses = path::cell_walk(&db, 40, 0.5, 10.0, 3)?;
//! let report = visual::walk(&db, &poses, &visual::VisualConfig::default(), |_| {})?;
//! assert_eq!(report.frames.len(), 40);
//! assert!(report.summary.searches >= 1);
//! # Ok(()) }
//! ```

use serde::Serialize;

use super::sink::{FrameSink, NoSink, Played, Viewer};
use super::visual_tally::VisualTally;
use super::walk_lods::WalkLods;
use crate::cache::CacheStats;
use crate::database::Database;
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::hdov::{Scheme, ScreenTest, Selection};
use crate::path::{CameraPath, Pose};

/// The thesis's threshold for VISUAL's walks (Table 5.3, Figs. 5.24–5.26).
pub const DEFAULT_ETA: f32 = 0.001;
/// The factor our screen rule stretches τ by for an object whose DoV from the viewcell
/// is at most η ([`VisualConfig::faint_tau`]). Chosen on the 3,000-object city (seed 1;
/// `bench fidelity --mode visual --frames 40 --size 640x360 --lod-tau 0.001`): 2 gave
/// 49.9 dB at 32,382 triangles a frame, 2.5 49.7 dB at 30,006, 2.8 and 3 43.4 dB
/// (a cliff: coarser levels of the near, faint objects begin to show); 1 (no stretch)
/// 59.5 dB at 45,017.
pub const FAINT_TAU_STRETCH: f32 = 2.5;
/// The node cache's default size: the 400 pages the thesis's caches stay within
/// (§5.8.3), of 4 KiB.
pub const DEFAULT_NODE_CACHE: usize = 400 * 4096;

/// Everything a VISUAL walk can vary.
#[derive(Clone, Debug, Serialize)]
pub struct VisualConfig {
    /// The DoV threshold η of the search: 0 finds every visible object at the detail
    /// of its DoV; larger draws more of the city at nodes' internal LODs.
    pub eta: f32,
    /// The storage scheme searched; `None`: the smallest one built.
    pub scheme: Option<Scheme>,
    /// The node cache: policy name (`lru`, `dov`, `dovtime`, …) and bytes; `None`: nodes
    /// read from the store every time.
    pub node_cache: Option<(String, usize)>,
    /// Next-cell prefetch, ours (the thesis's VISUAL has none): search and load, on a
    /// thread, the viewcell the eye will be in this many seconds on. `None`: off.
    pub prefetch_k: Option<f32>,
    /// Depth of the view frustum, metres.
    pub far: f32,
    /// The fallback's disk cell outside every viewcell: SF times the frustum's box.
    pub fallback_sf: f32,
    /// Which rule picks what is drawn: ours ([`Selection::Screen`], the default) holds a
    /// node's internal LOD to its stored error projecting under [`VisualConfig::tau`]
    /// from the viewcell, and draws each object at the finer of eq. 5.6's level and the
    /// screen-space one; the thesis's ([`Selection::Thesis`]) for the Table 5.3
    /// reproduction.
    pub selection: Selection,
    /// The screen-space threshold the screen rule holds nodes' internal LODs to, a
    /// fraction of the viewport within [0, 1): the viewer's LOD τ (the thesis's 0.1 %;
    /// 0, full detail, lets no internal LOD pass). The objects' levels are LOD
    /// selection's, under the τ the viewer asks for.
    pub tau: f32,
    /// Under the thesis's selection, each object still at the finer of eq. 5.6's level
    /// and LOD selection's screen-space one (ours, the object half of
    /// [`Selection::Screen`]): eq. 5.6 gives full detail only at a DoV of MAXDOV, half
    /// the view's sphere, so a near façade of DoV 0.1 would stay close to its coarsest
    /// level. The finer level is read by LOD selection when first wanted. Off by
    /// default; the screen rule implies it.
    pub finer_by_tau: bool,
    /// Objects refined view by view take a τ stretched by their DoV
    /// ([`dov_tau`](super::lod_select::dov_tau)): ours, not the thesis's. Off by
    /// default.
    pub dov_tau: bool,
    /// Under our screen rule, the factor τ is stretched by for an object whose DoV from
    /// the viewcell is at most η (ours; [`faint_tau_scale`]): eq. 5.6's reading of a
    /// small DoV (little of the object can be seen, so its detail matters little) with
    /// a bound on the error, where eq. 5.6 alone draws such an object at its coarsest
    /// level whatever the screen says. At least 1 (1: every object under τ, VISUAL η 0's
    /// picture); [`FAINT_TAU_STRETCH`] by default. Objects above η, nodes' internal LODs
    /// and the thesis's selection are untouched.
    pub faint_tau: f32,
    /// Play the path's clock this many times faster than real time, as REVIEW does
    /// with prefetching ([`ReviewConfig::pace`](super::review::ReviewConfig::pace));
    /// `None`: frames back to back.
    pub pace: Option<f32>,
    /// The viewer's thread never waits on a read (ours): the searches and the finds'
    /// meshes are read on a loader thread, coarsest levels first, and each frame draws
    /// what has arrived, its visual misses counted. Off by default (the thesis's walk).
    pub never_wait: bool,
}

impl Default for VisualConfig {
    /// The thesis's VISUAL: η = 0.001, the smallest scheme, a DoV-Time node cache of
    /// 400 pages, no prefetch, REVIEW's frustum depth and SF; with our screen-space
    /// selection under the thesis's τ of 0.1 %.
    fn default() -> VisualConfig {
        VisualConfig {
            eta: DEFAULT_ETA,
            scheme: None,
            node_cache: Some(("dovtime".into(), DEFAULT_NODE_CACHE)),
            prefetch_k: None,
            far: super::settings::DEFAULT_FAR,
            fallback_sf: super::settings::DEFAULT_SF,
            dov_tau: false,
            selection: Selection::Screen,
            tau: super::lod_select::DEFAULT_TAU,
            finer_by_tau: false,
            faint_tau: FAINT_TAU_STRETCH,
            pace: Some(super::settings::DEFAULT_PACE),
            never_wait: false,
        }
    }
}

impl VisualConfig {
    /// Whether objects are drawn at the finer of eq. 5.6's level and the screen-space
    /// one: the screen rule, or the thesis's with [`VisualConfig::finer_by_tau`].
    pub fn finer_of(&self) -> bool {
        self.selection == Selection::Screen || self.finer_by_tau
    }

    pub(crate) fn validate(&self) -> Result<()> {
        if !(self.eta.is_finite() && self.eta >= 0.0) {
            return Err(Error::Invalid(format!(
                "a DoV threshold η of {}: give a number ≥ 0",
                self.eta
            )));
        }
        check_screen_tau(self.tau)?;
        if !(self.faint_tau.is_finite() && self.faint_tau >= 1.0) {
            return Err(Error::Invalid(format!(
                "a faint object's τ stretch of {}: give a number ≥ 1 (1: no stretch)",
                self.faint_tau
            )));
        }
        if let Some(k) = self.prefetch_k {
            super::settings::check_k(k)?;
        }
        super::settings::check_far(self.far)?;
        super::settings::check_sf(self.fallback_sf)?;
        if let Some(p) = self.pace {
            super::settings::check_pace(p)?;
        }
        Ok(())
    }
}

/// One frame of a VISUAL walk. Times in milliseconds.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct VisualFrame {
    /// The frame's index, from 0.
    pub frame: usize,
    /// Its pose's time on the path, seconds.
    pub time: f64,
    /// The viewcell the eye is in; `None` outside every one (the fallback's frame).
    pub cell: Option<u32>,
    /// The tree was searched for this frame's cell on the viewer's thread.
    pub searched: bool,
    /// The new cell's finds were a prefetch's, already loaded.
    pub prefetch_used: bool,
    /// A prefetch's finds reached the buffer on this frame.
    pub prefetch_adopted: bool,
    /// Outside every viewcell, the fallback's spatial query ran on this frame.
    pub fallback_query: bool,
    /// Objects the current cell's search found (or the fallback's query).
    pub objects_found: usize,
    /// Nodes it found at an internal LOD.
    pub nodes_found: usize,
    /// Finds read on this frame's thread (new, or at another level).
    pub loaded: usize,
    /// Finds the cell wanted that the buffer already held at their level (delta).
    pub reused: usize,
    /// Finds dropped, the new cell not finding them.
    pub dropped: usize,
    /// Finds left out, their pages unreadable (a viewer that walks on).
    pub left_out: usize,
    /// What the frame draws: finds in the frustum.
    pub drawn: usize,
    /// Their triangles.
    pub triangles_drawn: u64,
    /// Searching the tree on this thread.
    pub search_ms: f64,
    /// Reading and decoding finds' meshes on this thread.
    pub load_ms: f64,
    /// Culling against the frustum.
    pub cull_ms: f64,
    /// The walk's whole time for the frame (not drawing it, nor waiting for the clock).
    pub frame_ms: f64,
    /// Pages of the tree read this frame (nodes and V-pages), on both threads.
    pub tree_pages: u64,
    /// Pages of models read (meshes, LOD levels and internal LODs), on both threads.
    pub model_pages: u64,
    /// Other pages (the viewcells' table, the fallback's R-tree), on both threads.
    pub other_pages: u64,
    /// Bytes the buffer holds at the end of the frame.
    pub buffer_bytes: usize,
    /// A walk that never waits: the cell's finds the buffer held at no level (all of
    /// them while its search had not come back); 0 outside every viewcell.
    pub visual_misses: usize,
    /// A walk that never waits: the cell's finds held coarser than they deserve.
    pub coarse: usize,
}

/// A VISUAL walk in all. Frame 0 loads the first cell cold and is left out of the
/// frame-time figures, as REVIEW's is.
#[derive(Clone, Debug, Default, Serialize)]
pub struct VisualSummary {
    /// Frames walked, frame 0 included.
    pub frames: usize,
    /// Frame 0's time, ms.
    pub initial_load_ms: f64,
    /// Mean frame time from frame 1 on, ms.
    pub mean_frame_ms: f64,
    /// Longest frame from frame 1 on, ms.
    pub max_frame_ms: f64,
    /// Frame time's variance from frame 1 on, ms².
    pub frame_ms_variance: f64,
    /// Frames from 1 on over 50 ms.
    pub frames_over_50ms: usize,
    /// Moves into another viewcell.
    pub cells_entered: usize,
    /// Searches on the viewer's thread.
    pub searches: usize,
    /// Searches the prefetch thread ran.
    pub prefetches: usize,
    /// Cells entered whose finds a prefetch had loaded.
    pub prefetches_used: usize,
    /// Mean time of a search on the viewer's thread, ms (Fig. 5.27a).
    pub mean_search_ms: f64,
    /// Frames outside every viewcell, drawn by the fallback.
    pub frames_outside: usize,
    /// The fallback's spatial queries.
    pub fallback_queries: usize,
    /// Pages read, by kind, over the walk.
    pub tree_pages: u64,
    /// Model pages (meshes, levels, internal LODs).
    pub model_pages: u64,
    /// Other pages (viewcells' table, the fallback's R-tree).
    pub other_pages: u64,
    /// Finds loaded on the viewer's thread, and reused from the buffer.
    pub loaded: usize,
    /// Finds reused, summed over cell changes.
    pub reused: usize,
    /// Finds left out as unreadable.
    pub left_out: usize,
    /// Objects and groups drawn per frame, on average.
    pub mean_drawn: f64,
    /// Triangles drawn per frame, on average.
    pub mean_triangles: f64,
    /// The most bytes the buffer held at a frame's end.
    pub peak_buffer_bytes: usize,
    /// The node cache's figures, when it had one.
    pub node_cache: Option<CacheStats>,
    /// A walk that never waits: frames' visual misses, summed over the walk.
    pub visual_misses: usize,
    /// The first frame in a viewcell that misses nothing (a walk that never waits).
    pub first_complete_frame: Option<usize>,
    /// Visual misses from the first complete frame on.
    pub visual_misses_after_start: usize,
    /// Finds drawn coarser than they deserve, summed over frames.
    pub coarse_draws: usize,
    /// Reads the network failed, each asked for again (a walk that never waits).
    pub failed_loads: usize,
    /// The last failed read's words.
    pub last_load_error: Option<String>,
}

/// What a VISUAL walk did: its settings, every frame's figures, their summary.
#[derive(Clone, Debug, Serialize)]
pub struct VisualReport {
    /// The settings walked.
    pub config: VisualConfig,
    /// Every frame's figures, in order.
    pub frames: Vec<VisualFrame>,
    /// The walk in all.
    pub summary: VisualSummary,
}

impl VisualReport {
    /// One row per frame, under [`VisualFrame::CSV_HEADER`].
    pub fn to_csv(&self) -> String {
        super::frame_csv::table(VisualFrame::CSV_HEADER, &self.frames, VisualFrame::csv_row)
    }
}

impl VisualFrame {
    /// The columns of [`VisualFrame::csv_row`].
    pub const CSV_HEADER: &'static str = "frame,time,cell,searched,prefetch_used,prefetch_adopted,fallback_query,objects_found,nodes_found,loaded,reused,dropped,left_out,drawn,triangles_drawn,search_ms,load_ms,cull_ms,frame_ms,tree_pages,model_pages,other_pages,buffer_bytes,visual_misses,coarse";

    /// The frame as one CSV row (no line end), its columns [`VisualFrame::CSV_HEADER`].
    pub fn csv_row(&self) -> String {
        let f = self;
        format!(
            "{},{:.4},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.3},{:.3},{:.3},{:.3},{},{},{},{},{},{}",
            f.frame,
            f.time,
            f.cell.map_or(String::new(), |c| c.to_string()),
            f.searched as u8,
            f.prefetch_used as u8,
            f.prefetch_adopted as u8,
            f.fallback_query as u8,
            f.objects_found,
            f.nodes_found,
            f.loaded,
            f.reused,
            f.dropped,
            f.left_out,
            f.drawn,
            f.triangles_drawn,
            f.search_ms,
            f.load_ms,
            f.cull_ms,
            f.frame_ms,
            f.tree_pages,
            f.model_pages,
            f.other_pages,
            f.buffer_bytes,
            f.visual_misses,
            f.coarse
        )
    }
}

/// Walks `path` over `db`'s HDoV-tree under `cfg`; `progress` is told each finished
/// frame. An error for a database without an HDoV-tree.
pub fn walk(
    db: &Database,
    path: &CameraPath,
    cfg: &VisualConfig,
    progress: impl FnMut(usize),
) -> Result<VisualReport> {
    walk_into(db, path, cfg, progress, &mut NoSink)
}

/// [`walk`], handing each frame to `sink` (a renderer) once its figures are taken.
pub fn walk_into(
    db: &Database,
    path: &CameraPath,
    cfg: &VisualConfig,
    progress: impl FnMut(usize),
    sink: &mut dyn FrameSink,
) -> Result<VisualReport> {
    if path.poses.is_empty() {
        return Err(Error::Invalid("the camera path has no poses".into()));
    }
    walk_live(db, cfg, progress, &mut Played::path(path, sink))
}

/// [`walk_into`] with the poses coming from `viewer` frame by frame, until it has no
/// more. Poses must come in time order.
pub fn walk_live(
    db: &Database,
    cfg: &VisualConfig,
    progress: impl FnMut(usize),
    viewer: &mut dyn Viewer,
) -> Result<VisualReport> {
    walk_live_with(db, cfg, &mut WalkLods::new(db), progress, viewer)
}

/// [`walk_into`] in constant memory, for a walk of any length: the poses come from
/// `poses` as the walk needs them (each checked as a [`CameraPath`]'s are), and each
/// frame's figures go to `each` as the frame ends, and are not kept. The report's
/// `frames` is empty; its summary is whole, and the same as [`walk_into`]'s. A walk that
/// never waits ([`VisualConfig::never_wait`]) is the exception: a frame's misses are
/// known only once its cell's finds have come, so it keeps its frames, and hands them
/// to `each` as it ends.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # citygen::write_city(&citygen::CityConfig { objects: 40, ..Default::default() }, &scene)?;
/// # let mut opts = flaneur::BuildOptions::default();
/// # opts.visibility = Some(flaneur::visibility::VisibilityOptions { cell_size: 40.0, ..Default::default() });
/// # opts.hdov = Some(flaneur::hdov::HdovOptions::default());
/// # flaneur::build_from_scene(&scene, &path, &opts)?;
/// use flaneur::{path::cell_poses, walk::{visual, NoSink}};
/// let db = flaneur::Database::open(&path)?;
/// let poses = cell_poses(&db, 100, 0.5, 30.0, 1)?;
/// let mut rows = 0;
/// let cfg = visual::VisualConfig::default();
/// let report = visual::walk_streamed(&db, poses, &cfg, |_| {}, &mut NoSink, &mut |_| {
///     rows += 1;
///     Ok(())
/// })?;
/// assert!(report.frames.is_empty());
/// assert_eq!((report.summary.frames, rows), (100, 100));
/// # Ok(()) }
/// ```
pub fn walk_streamed(
    db: &Database,
    poses: impl Iterator<Item = Pose>,
    cfg: &VisualConfig,
    progress: impl FnMut(usize),
    sink: &mut dyn FrameSink,
    each: &mut dyn FnMut(&VisualFrame) -> Result<()>,
) -> Result<VisualReport> {
    walk_each(
        db,
        cfg,
        &mut WalkLods::new(db),
        progress,
        &mut Played::streamed(poses, sink),
        each,
    )
}

/// [`walk_live`] with LOD selection `lods` kept from an earlier walk.
pub(crate) fn walk_live_with<'db>(
    db: &'db Database,
    cfg: &VisualConfig,
    lods: &mut WalkLods<'db>,
    progress: impl FnMut(usize),
    viewer: &mut dyn Viewer,
) -> Result<VisualReport> {
    let mut frames = Vec::new();
    let mut report = walk_each(db, cfg, lods, progress, viewer, &mut |f| {
        frames.push(f.clone());
        Ok(())
    })?;
    report.frames = frames;
    Ok(report)
}

/// The walk, each frame handed to `each` and tallied, none kept.
fn walk_each<'db>(
    db: &'db Database,
    cfg: &VisualConfig,
    lods: &mut WalkLods<'db>,
    progress: impl FnMut(usize),
    viewer: &mut dyn Viewer,
    each: &mut dyn FnMut(&VisualFrame) -> Result<()>,
) -> Result<VisualReport> {
    let mut tally = VisualTally::default();
    let (node_cache, run) = super::mode::visual::walk_live(db, cfg, lods, progress, viewer, |f| {
        tally.add(&f);
        each(&f)
    })?;
    let mut summary = tally.summary(node_cache);
    summary.failed_loads = run.failures.count;
    summary.last_load_error = run.failures.last;
    Ok(VisualReport {
        config: cfg.clone(),
        frames: Vec::new(),
        summary,
    })
}

/// The factor LOD selection stretches τ by for an object found with DoV `dov` under the
/// threshold `eta`, by our screen rule with stretch `stretch` ([`VisualConfig::faint_tau`]):
/// `stretch` where the DoV is at most η, 1 above it. An object found has a DoV above 0
/// (a DoV of 0 prunes it), so under η = 0 none is stretched.
///
/// ```
/// use flaneur::walk::visual::faint_tau_scale;
/// assert_eq!(faint_tau_scale(0.0005, 0.001, 2.5), 2.5);
/// assert_eq!(faint_tau_scale(0.001, 0.001, 2.5), 2.5);
/// assert_eq!(faint_tau_scale(0.002, 0.001, 2.5), 1.0);
/// assert_eq!(faint_tau_scale(0.0005, 0.0, 2.5), 1.0);
/// ```
pub fn faint_tau_scale(dov: f32, eta: f32, stretch: f32) -> f32 {
    if dov > 0.0 && dov <= eta {
        stretch
    } else {
        1.0
    }
}

/// Whether `tau` can be the screen rule's threshold: a fraction of the viewport within
/// [0, 1), 0 letting no internal LOD pass.
pub(crate) fn check_screen_tau(tau: f32) -> Result<()> {
    if !(0.0..1.0).contains(&tau) {
        return Err(Error::Invalid(format!(
            "the screen rule's τ = {tau}: give a fraction of the viewport within [0, 1) (0: no internal LOD passes)"
        )));
    }
    Ok(())
}

/// The screen-space test of the screen rule from viewcell `cell` of `db` under `tau` for
/// a vertical field of view `fov_y` (radians): from the cell's box, its eye heights
/// widened by the step an eye may take and stay in it
/// ([`viewcell_holding`](super::cells)), so that what passes it passes from every eye
/// the cell's finds are drawn for. An error for a database without visibility, or a τ
/// outside [0, 1).
pub fn screen_test(db: &Database, cell: u32, tau: f32, fov_y: f32) -> Result<ScreenTest> {
    check_screen_tau(tau)?;
    let vis = db.visibility()?.ok_or_else(|| {
        Error::Invalid(format!(
            "{} has no visibility: build it with --visibility",
            db.store().path().display()
        ))
    })?;
    let (row, column) = vis.grid.place(cell);
    let b = vis.grid.cell_bounds(row, column);
    let slack = glam::Vec3::new(0.0, super::cells::EYE_SLACK, 0.0);
    Ok(ScreenTest {
        from: Aabb {
            min: b.min - slack,
            max: b.max + slack,
        },
        fov_y,
        tau,
    })
}
