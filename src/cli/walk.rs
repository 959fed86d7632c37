//! `flaneur walk`: a headless walk along a camera path (REVIEW, Shou 2002 ch. 4, or
//! the viewcells' PVS), its per-frame figures, and its frames drawn when asked.

use crate::cli::args::{
    border, eta, finite_f32, frame_rate, lod_tau, pace_factor, seconds_ahead, selection,
};
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use super::args::parse_size;
use super::source::SourceArgs;
use flaneur::path::motion::{self, Motion};
use flaneur::path::{cell_poses, CameraPath, Pose};
use flaneur::walk::review::{self, Preset, ReviewConfig};
use flaneur::walk::scene::SceneTree;
use flaneur::walk::settings;
use flaneur::walk::visual::{self, VisualConfig};
use flaneur::walk::{Frame, Frames, Playback, WalkConfig, WalkMode, WalkState};
use flaneur::Database;

mod csv_rows;
mod gaps;
mod render;
mod summary;
mod visual_args;
mod walk_config;

use csv_rows::{write_row, CsvRows};

use render::{print_render, rendered, RenderOpts};
pub use summary::print_walk;
use summary::{print_remote, print_report};
use visual_args::VisualArgs;

/// `flaneur walk`'s arguments.
#[derive(clap::Args)]
pub struct WalkArgs {
    /// The database: a file, or a URL (http://… or https://…) on any HTTP server.
    db: PathBuf,
    /// `review` (CSearch with index cache and prefetching), `box` (plain range
    /// queries), `pvs` (the current viewcell's PVS, neighbours prefetched; needs a
    /// database built with --visibility), `visual` (the HDoV-tree searched under
    /// --eta; needs one built with --visibility --hdov), or the memory scene tree of
    /// the whole city traversed by `vsc` (under --eta), `pb` (under --budget) or
    /// `conv` (frustum culling only; each needs --visibility).
    #[arg(long, default_value = "review")]
    mode: WalkMode,
    /// One of the thesis's configurations instead of --mode: optimal (review's
    /// default), nc (no index cache), np (no prefetching), box (neither, BOX queries).
    /// Default: none, --mode decides.
    #[arg(long)]
    config: Option<Preset>,
    /// A motion pattern (normal, fast, slow, turning, backward, random), `cells` (a
    /// walk through the walkable viewcells) or a path CSV file. Default: normal; cells
    /// for --mode pvs, visual, vsc, pb and conv.
    #[arg(long)]
    path: Option<String>,
    /// With --mode pvs: which neighbours' PVS the client prefetches, snp, pbnp or lanp
    /// (ours: PBNP's and every cell the viewer may reach in the measured round trip).
    #[arg(long, default_value = "pbnp")]
    prefetch: String,
    /// With --mode pvs and pbnp or lanp: the border regions' width, a share of the
    /// cell's side, within (0, 0.5].
    #[arg(long, default_value_t = flaneur::prefetch::pvs::DEFAULT_BORDER, value_parser = border, allow_negative_numbers = true)]
    border: f64,
    /// Frames to walk: of a motion pattern or `cells`, how many to make (default 600);
    /// of a path file, its first N poses (default: all of them; more than it holds is an
    /// error).
    #[arg(long, value_name = "N")]
    frames: Option<usize>,
    /// Frames a second of a generated path: its poses' times, which a paced walk
    /// plays at (within [0.1, 1000]).
    #[arg(long, default_value_t = 30.0, value_parser = frame_rate, allow_negative_numbers = true)]
    fps: f32,
    /// Seed of a generated path (a motion pattern or `cells`): the same seed, the same
    /// path.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[arg(long, value_name = "POLICY", help = format!(
        "Index cache policy: lru, dplru, dov, dovtime, path [default: {}; {} for --mode visual's node cache]",
        review::ReviewConfig::preset(Preset::Optimal).index_cache.map_or(String::new(), |c| c.0),
        VisualConfig::default().node_cache.map_or(String::new(), |c| c.0),
    ))]
    policy: Option<String>,
    #[arg(long, value_name = "BYTES", help = format!(
        "Index cache size in bytes, not MiB (0: no index cache) [default: {} ({} KiB) for --mode review, --config optimal and np; none for nc and box; {} ({} KiB) for --mode visual's node cache]",
        review::DEFAULT_INDEX_CACHE,
        review::DEFAULT_INDEX_CACHE >> 10,
        visual::DEFAULT_NODE_CACHE,
        visual::DEFAULT_NODE_CACHE >> 10,
    ))]
    cache_bytes: Option<usize>,
    #[arg(long, value_name = "SECONDS", value_parser = seconds_ahead, allow_negative_numbers = true, help = format!(
        "Prefetch factor k: prefetch the cell of the frustum k seconds of motion ahead, at most 60 (negative: no prefetching) [default: {} for --mode review, --config optimal and nc; none for np and box]",
        settings::DEFAULT_K,
    ))]
    k: Option<f32>,
    #[arg(long, value_parser = finite_f32, allow_negative_numbers = true, help = format!(
        "Scale factor SF of the disk cell over the frustum cell, at least 1 [default: {}]",
        settings::DEFAULT_SF,
    ))]
    sf: Option<f32>,
    #[arg(long, value_name = "METRES", value_parser = finite_f32, allow_negative_numbers = true, help = format!(
        "Frustum depth, metres: how far ahead the walk sees [default: {}]",
        settings::DEFAULT_FAR,
    ))]
    far: Option<f32>,
    #[arg(long, value_name = "MIB", help = format!(
        "Object buffer budget, MiB (--mode review and box) [default: {}]",
        settings::DEFAULT_MEMORY_BUDGET >> 20,
    ))]
    budget_mb: Option<usize>,
    /// Playback speed of walks that prefetch, times real time, within [0.01, 1000] (0:
    /// unpaced, frames back to back; the prefetch thread then rarely finishes in time).
    #[arg(long, default_value_t = settings::DEFAULT_PACE, value_parser = pace_factor, allow_negative_numbers = true)]
    speed: f32,
    /// REVIEW, BOX, PVS and VISUAL: the viewer's thread never waits on a read (ours): a
    /// search the viewer needs (PVS: the client and its rows; VISUAL: the HDoV-tree's)
    /// is queued on a loader thread of its own and the frame draws what is loaded,
    /// coarse levels first, its misses counted; a load that fails on the network is
    /// asked for again and the walk goes on.
    #[arg(long)]
    never_wait: bool,
    /// Write one row per frame to this CSV file (default: none).
    #[arg(long, value_name = "FILE")]
    csv: Option<PathBuf>,
    /// Save the camera path to this CSV file, time, x, y, z, yaw, pitch (default:
    /// none).
    #[arg(long, value_name = "FILE")]
    save_path: Option<PathBuf>,
    #[command(flatten)]
    source: SourceArgs,
    /// Print the summary only, not the progress.
    #[arg(long, short)]
    quiet: bool,
    /// Draw every frame headless (no window) as the walk selects it, and write them
    /// as PNGs to --frames-dir.
    #[arg(long)]
    render: bool,
    /// The folder --render writes its PNGs into (made if missing).
    #[arg(long, value_name = "DIR", default_value = "frames")]
    frames_dir: PathBuf,
    /// Rendered image size, WIDTHxHEIGHT; square fits the walk's 45° × 45° view.
    #[arg(long, value_parser = parse_size, default_value = "512x512")]
    size: (u32, u32),
    /// Write every N-th rendered frame (all are drawn and timed).
    #[arg(long, default_value_t = 1)]
    every: usize,
    /// With --mode pb: the polygon budget, triangles a frame.
    #[arg(long, default_value_t = 20_000)]
    budget: u64,
    /// With --mode visual or vsc: the DoV threshold η of the search, within [0, 1].
    #[arg(long, default_value_t = flaneur::walk::visual::DEFAULT_ETA, value_parser = eta, allow_negative_numbers = true)]
    eta: f32,
    #[command(flatten)]
    visual: VisualArgs,
    /// With --mode visual, vsc or pb: the rule that picks internal LODs and levels.
    /// `screen` (ours, the default): a node's internal LOD only where its DoV ≤ η and
    /// eq. 5.4 allow it and its stored error projects under --lod-tau (from the viewcell
    /// for visual, from the eye for vsc and pb), each object at the finer of eq. 5.6's
    /// level and --lod-tau's. `thesis`: Shou 2002's rules, whatever the screen says (the
    /// Table 5.3 and 6.1 reproductions).
    #[arg(long, default_value = "screen", value_parser = selection)]
    selection: flaneur::hdov::Selection,
    /// LOD selection's screen-space error, a fraction of the viewport: each object
    /// drawn at the coarsest stored level under it, within [0, 1) (0: full detail).
    #[arg(long, default_value_t = flaneur::walk::lod_select::DEFAULT_TAU, value_parser = lod_tau, allow_negative_numbers = true)]
    lod_tau: f32,
    /// With --render: objects refined view by view are refined on the thread pool once
    /// a frame is drawn, for the view predicted for the next (El-Sana–Varshney's Adapt
    /// and Display), not on the frame's thread.
    #[arg(long)]
    adapt_ahead: bool,
    /// With --render: draw the city's landmarks from a stream server (`flaneur
    /// serve-stream` of the same database) at this address (host:port), the rest as
    /// ever; the predictive client hides the round trip (Zheng ch. 5-6). Default: none,
    /// every object read from the database.
    #[arg(long, value_name = "HOST:PORT")]
    stream: Option<String>,
}

impl WalkArgs {
    /// Walks the path in the mode asked and prints the walk's figures.
    pub fn run(self) -> Result<()> {
        let render = self.render_opts()?;
        let cfg = self.walk_config()?;
        let db = self.source.open(&self.db)?;
        if let WalkConfig::Review(ReviewConfig {
            never_wait: true, ..
        }) = cfg
        {
            // A packed file (format version 2) puts neighbours' small extents on one
            // page, and a never-wait walk loads neighbours a batch apart: the last 1 MiB
            // of pages read is kept rather than read again for each of them.
            db.store()
                .keep_recent_pages((1 << 20) / db.store().page_size());
        }
        let (poses, count) = self.poses(&db, cfg.mode())?;
        let mut state = WalkState::new(&db);
        if let WalkConfig::Scene(_) = cfg {
            state = state.with_scene_tree(self.scene_tree(&db)?);
        }
        let mut rows = (self.csv.as_deref())
            .map(|p| CsvRows::create(p, Frame::csv_header(cfg.mode())))
            .transpose()?;
        let (report, drawn) = rendered(
            &db,
            (count, self.quiet),
            render.as_ref(),
            cfg.far(),
            |sink, tick| {
                let mut viewer = Playback::poses(poses).drawn_by(sink).with_progress(tick);
                // Each frame's figures go to the CSV as the frame ends: a walk of any
                // length in constant memory.
                let mut each = |f: &Frame| write_row(&mut rows, || f.csv_row());
                state.run(&cfg, &mut viewer, Frames::Each(&mut each))
            },
        )?;
        if let Some(rows) = rows {
            rows.finish()?;
        }
        print_report(&report, db.store().page_size());
        print_remote(&db);
        print_render(drawn, render.as_ref())?;
        let (failed, last) = report.failed_loads();
        gaps::went_without(report.damaged(), failed, last)
    }

    /// What `--render` asks of the walk's frames, checked against the flags that need it.
    fn render_opts(&self) -> Result<Option<RenderOpts>> {
        if self.adapt_ahead && !self.render {
            bail!("--adapt-ahead is for a walk drawn with --render: only it refines objects");
        }
        if self.stream.is_some() && (!self.render || self.lod_tau == 0.0) {
            bail!(
                "--stream is for a walk drawn with --render under a --lod-tau above 0: only \
                 it draws landmarks refined view by view"
            );
        }
        Ok(self.render.then(|| RenderOpts {
            dir: self.frames_dir.clone(),
            size: self.size,
            every: self.every,
            lod_tau: (self.lod_tau != 0.0).then_some(self.lod_tau),
            adapt_ahead: self.adapt_ahead,
            stream: self.stream.clone(),
        }))
    }

    /// The walk's poses, made as the walk asks for them where they are generated, and
    /// how many: over disk cells (REVIEW and BOX) a motion pattern by default, saved
    /// with `--save-path` if asked; over viewcells `cells` by default.
    fn poses<'db>(
        &self,
        db: &'db Database,
        mode: WalkMode,
    ) -> Result<(Box<dyn Iterator<Item = Pose> + 'db>, usize)> {
        let (frames, fps, seed) = (self.frames, self.fps, self.seed);
        if !matches!(mode, WalkMode::Review | WalkMode::Box) {
            let camera = self.path.as_deref().unwrap_or("cells");
            return viewcell_poses(db, camera, frames, fps, seed);
        }
        let camera = self.path.as_deref().unwrap_or("normal");
        match camera.parse::<Motion>() {
            Ok(m) if self.save_path.is_none() => {
                let poses =
                    motion::poses(&db.bounds(), m, frames.unwrap_or(DEFAULT_FRAMES), fps, seed)?;
                let count = poses.len();
                Ok((Box::new(poses), count))
            }
            _ => {
                let path = camera_path(db, camera, (frames, DEFAULT_FRAMES), fps, seed)?;
                if let Some(p) = &self.save_path {
                    path.save_csv(p)?;
                }
                let count = path.len();
                Ok((Box::new(path.poses.into_iter()), count))
            }
        }
    }

    /// `db`'s memory scene tree for a VSC, PB or CONV walk, loaded under a bar.
    fn scene_tree(&self, db: &Database) -> Result<SceneTree> {
        let started = std::time::Instant::now();
        let bars = super::bars::Bars::default();
        let tree = SceneTree::load(
            db,
            if self.quiet {
                &flaneur::progress::Silent
            } else {
                &bars
            },
        )?;
        if !self.quiet {
            eprintln!(
                "scene tree: {} nodes, loaded in {:.1} s",
                tree.nodes.len(),
                started.elapsed().as_secs_f64()
            );
        }
        Ok(tree)
    }
}

/// The poses of `camera` for a walk over viewcells, made as the walk asks for them where
/// they are generated, and how many: `cells` (a walk through the walkable ones at a
/// walker's pace, 1.4 m/s), a motion pattern, or a path file.
fn viewcell_poses<'db>(
    db: &'db Database,
    camera: &str,
    frames: Option<usize>,
    fps: f32,
    seed: u64,
) -> Result<(Box<dyn Iterator<Item = Pose> + 'db>, usize)> {
    let n = frames.unwrap_or(DEFAULT_FRAMES);
    if camera == "cells" {
        return Ok((Box::new(cell_poses(db, n, 1.4 / fps, fps, seed)?), n));
    }
    if let Ok(m) = camera.parse::<Motion>() {
        return Ok((Box::new(motion::poses(&db.bounds(), m, n, fps, seed)?), n));
    }
    let path = camera_path(db, camera, (frames, DEFAULT_FRAMES), fps, seed)?;
    let count = path.len();
    Ok((Box::new(path.poses.into_iter()), count))
}

/// Frames a walk makes of a motion pattern when `--frames` is not given.
pub const DEFAULT_FRAMES: usize = 600;

/// The poses of `camera`: `frames` of a motion pattern over `db`'s bounds (`default`
/// when not given), or a path CSV file, all of it or its first `frames` poses (a file
/// shorter than that is an error, not a shorter walk).
pub fn camera_path(
    db: &Database,
    camera: &str,
    (frames, default): (Option<usize>, usize),
    fps: f32,
    seed: u64,
) -> Result<CameraPath> {
    if let Ok(m) = camera.parse::<Motion>() {
        let n = frames.unwrap_or(default);
        return Ok(motion::generate(&db.bounds(), m, n, fps, seed)?);
    }
    let mut path = CameraPath::load_csv(Path::new(camera)).with_context(|| {
        format!("'{camera}' is neither a motion pattern nor a readable path file")
    })?;
    if let Some(n) = frames {
        if n > path.len() {
            bail!(
                "--frames {n}: the path file {camera} holds {} poses",
                path.len()
            );
        }
        path.poses.truncate(n);
        path.validate()?;
    }
    Ok(path)
}
