//! The `flaneur` command line. Parses arguments, calls the library, prints; nothing
//! else lives here.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};

mod cli;
use cli::bars::Bars;
use flaneur::progress::{Progress, Silent};

use flaneur_bench::cell_size::{self, CellSizeConfig};
use flaneur_bench::csearch::{self, CsearchConfig, CsearchReport};
use flaneur_bench::db_size::{self, DbSizeConfig};
use flaneur_bench::frame_time::{self, FrameTimeConfig};
use flaneur_bench::index_cache::{self, IndexCacheConfig};
use flaneur_bench::lod_dag::{self, LodDagConfig};
use flaneur_bench::lod_parallel::{self, LodParallelConfig};
use flaneur_bench::lod_refine::{self, LodRefineConfig};
use flaneur_bench::patterns::{self, PatternsConfig};
use flaneur_bench::prefetch_k::{self, PrefetchKConfig};
use flaneur_bench::pvs_prefetch::{self, PvsPrefetchConfig};
use flaneur_bench::view_culling::{self, ViewCullingConfig};
use flaneur_bench::walk_setup::{self, WalkSetup};
use flaneur::geom::Aabb;
use flaneur::lod::{LodOptions, LodReport};
use flaneur::prefetch::pvs::{RouteConfig, SyntheticConfig};
use flaneur_render::{Change, ViewMode};
use flaneur::visibility::{SampleOptions, VisibilityOptions};
use flaneur::walk::motion::{self, CameraPath, Motion};
use flaneur::walk::pvs_walk::{self, PvsPrefetch};
use flaneur::walk::review::{self, Preset, ReviewConfig, WalkReport};
use flaneur::{Backend, BuildOptions, Database};

#[derive(Parser)]
#[command(
    name = "flaneur",
    version,
    about = "An urban walkthrough engine built around disk-resident spatial indexes"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Generate a default city (once, into a cache folder), build it, and walk it headless
    /// in REVIEW mode, then with plain BOX queries.
    Demo {
        /// Objects in the generated city.
        #[arg(long, default_value_t = 20_000)]
        objects: u64,
        /// Where the city and its database are kept between runs.
        #[arg(long, env = "FLANEUR_CACHE", default_value = "cache")]
        cache: PathBuf,
        /// Frames of the walk (30 per second).
        #[arg(long, default_value_t = 1800)]
        frames: usize,
    },
    /// Build a database from a citygen scene file or OBJ files.
    Build {
        /// A `.scene` file from citygen, or one or more `.obj` files.
        #[arg(required = true)]
        inputs: Vec<PathBuf>,
        /// The database file to write.
        #[arg(long, short)]
        out: PathBuf,
        #[arg(long, default_value_t = 4096)]
        page_size: usize,
        /// Share of each R-tree node that bulk loading fills.
        #[arg(long, default_value_t = flaneur::rtree::DEFAULT_FILL)]
        fill: f32,
        /// Build the index by one-by-one insertion (linear split), as the thesis did.
        #[arg(long)]
        insertion: bool,
        /// Store no LODs: only each object's full mesh (faster, smaller).
        #[arg(long)]
        no_lod: bool,
        /// Objects with more triangles than this also store their progressive mesh and
        /// DAG, for view-dependent refinement.
        #[arg(long, value_name = "N", default_value_t = flaneur::lod::DEFAULT_PM_THRESHOLD)]
        pm_threshold: usize,
        /// Precompute each viewcell's potentially visible set and its objects' degrees
        /// of visibility (the long step of a build; see --cell-size).
        #[arg(long)]
        visibility: bool,
        /// Side of a viewcell in metres (with --visibility).
        #[arg(long, value_name = "METRES", default_value_t = VisibilityOptions::default().cell_size)]
        cell_size: f32,
        /// Pixels per side of each cube face the DoV is measured on (with --visibility).
        #[arg(long, value_name = "N", default_value_t = VisibilityOptions::default().resolution)]
        dov_resolution: u32,
        /// Widest patch of a viewcell the conservative test samples, in metres (with
        /// --visibility): smaller is a tighter PVS and a slower build.
        #[arg(long, value_name = "METRES", default_value_t = SampleOptions::default().spacing)]
        sample_spacing: f32,
        /// Occluders further than this from a sample point are not used, in metres
        /// (with --visibility).
        #[arg(long, value_name = "METRES", default_value_t = SampleOptions::default().radius)]
        occluder_radius: f32,
        #[arg(long, short)]
        quiet: bool,
    },
    /// The LOD core on a mesh file: its levels written as OBJ (--out), or one view's
    /// selective mesh measured (--refine --eye --look --tau).
    Lod {
        /// An OBJ file; its objects are simplified together as disjoint pieces.
        mesh: PathBuf,
        /// Write level-0.obj (the original), level-1.obj, … here.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Triangles of each level over the one before (as `build` stores them).
        #[arg(long, default_value_t = flaneur::lod::LodOptions::default().ratio)]
        ratio: f32,
        /// Stop the chain of levels at this many triangles.
        #[arg(long, default_value_t = flaneur::lod::LodOptions::default().min_triangles)]
        min_triangles: usize,
        /// Refine view-dependently for one view instead.
        #[arg(long)]
        refine: bool,
        /// The eye, x,y,z.
        #[arg(long, value_parser = parse_vec3)]
        eye: Option<glam::Vec3>,
        /// The point looked at, x,y,z.
        #[arg(long, value_parser = parse_vec3)]
        look: Option<glam::Vec3>,
        /// Screen-space error, a fraction of the viewport (the thesis: 0.001).
        #[arg(long, default_value_t = 0.001)]
        tau: f32,
        /// Full apex angle of the view cone, degrees.
        #[arg(long, default_value_t = 60.0)]
        fov: f32,
    },
    /// Render one picture of the city headless (no window): the objects in view at full
    /// detail, on the GPU or a software adapter.
    Shot {
        db: PathBuf,
        /// The eye: x,y,z in metres.
        #[arg(long, value_parser = parse_vec3)]
        at: glam::Vec3,
        /// Heading and elevation in degrees: yaw,pitch (yaw 0 looks along +x, 90 along
        /// +z; pitch positive looks up).
        #[arg(long, value_parser = parse_look, default_value = "0,0")]
        look: (f32, f32),
        /// Image size, WIDTHxHEIGHT pixels.
        #[arg(long, value_parser = parse_size, default_value = "960x540")]
        size: (u32, u32),
        /// Vertical field of view, degrees.
        #[arg(long, default_value_t = 60.0)]
        fov: f32,
        #[arg(short, long, default_value = "shot.png")]
        out: PathBuf,
    },
    /// Walk a city in a window: W A S D and the mouse (click to capture it), Shift to
    /// run, F to fly; the walk engine selects, the window draws its selection at the
    /// chosen LODs, with a heads-up display. Opens on the city's busiest street.
    View {
        db: PathBuf,
        /// review (CSearch, index cache, prefetching), box (plain range queries) or pvs
        /// (the current viewcell's PVS, PBNP prefetching; a database built with
        /// --visibility); 1, 2 and 3 switch while walking.
        #[arg(long, default_value = "review")]
        mode: String,
        /// Window size, WIDTHxHEIGHT pixels (the walk's 45° view is its centred square).
        #[arg(long, value_parser = parse_size, default_value = "1024x768")]
        size: (u32, u32),
        /// LOD selection's screen-space error, a fraction of the viewport (0: full
        /// detail); [ and ] halve and double it while walking.
        #[arg(long, default_value_t = flaneur::walk::lod_select::DEFAULT_TAU)]
        lod_tau: f32,
        /// Start here (x,y,z metres) instead of the busiest street.
        #[arg(long, value_parser = parse_vec3)]
        at: Option<glam::Vec3>,
        /// Heading and elevation at the start, degrees (with --at).
        #[arg(long, value_parser = parse_look, default_value = "0,0")]
        look: (f32, f32),
        /// Save the poses walked as a path CSV when the window closes.
        #[arg(long)]
        record: Option<PathBuf>,
        /// Play a path CSV (from --record, --save-path or by hand) instead of steering.
        #[arg(long)]
        play: Option<PathBuf>,
        /// GPU memory the meshes may take, MiB (0: as much as the walk's buffer holds);
        /// meshes not drawn are freed to make room, largest first.
        #[arg(long, default_value_t = 256.0)]
        gpu_budget_mb: f64,
        /// Walking speed, m/s (Shift runs at four times it).
        #[arg(long, default_value_t = flaneur::walk::steer::WALK_SPEED)]
        speed: f32,
        /// Start with the bounding boxes on (B), and seen from above (T).
        #[arg(long)]
        boxes: bool,
        #[arg(long)]
        top_view: bool,
    },
    /// Objects, triangles, pages by kind, tree height and fill.
    Info {
        db: PathBuf,
        #[arg(long)]
        json: bool,
    },
    /// Range query (BOX), or CSearch when history cells are given.
    Query {
        db: PathBuf,
        /// The query box: x0,y0,z0,x1,y1,z1.
        #[arg(long = "box", value_name = "BOX")]
        query: Aabb,
        /// History cells for CSearch (repeatable).
        #[arg(long, value_name = "BOX")]
        history: Vec<Aabb>,
        #[arg(long, default_value = "mmap")]
        backend: Backend,
        #[arg(long)]
        json: bool,
    },
    /// Walk a database headless along a camera path (REVIEW, Shou 2002 ch. 4) and
    /// report per-frame figures.
    Walk {
        db: PathBuf,
        /// `review` (CSearch with index cache and prefetching), `box` (plain range
        /// queries) or `pvs` (the current viewcell's PVS, neighbours prefetched; needs a
        /// database built with --visibility).
        #[arg(long, default_value = "review")]
        mode: String,
        /// One of the thesis's configurations instead of --mode: optimal, nc, np, box.
        #[arg(long)]
        config: Option<Preset>,
        /// A motion pattern (normal, fast, slow, turning, backward, random), `cells` (a
        /// walk through the walkable viewcells; the default of --mode pvs) or a path CSV
        /// file. Default: normal.
        #[arg(long)]
        path: Option<String>,
        /// With --mode pvs: which neighbours' PVS the client prefetches, snp or pbnp.
        #[arg(long, default_value = "pbnp")]
        prefetch: String,
        /// With --mode pvs and pbnp: the border regions' width, a share of the cell's side.
        #[arg(long, default_value_t = flaneur::prefetch::pvs::DEFAULT_BORDER)]
        border: f64,
        #[arg(long, default_value_t = 600)]
        frames: usize,
        #[arg(long, default_value_t = 30.0)]
        fps: f32,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Index cache policy: lru, dplru, dov, dovtime.
        #[arg(long)]
        policy: Option<String>,
        /// Index cache size in bytes (0: no index cache).
        #[arg(long)]
        cache_bytes: Option<usize>,
        /// Prefetch factor k in seconds: prefetch the cell of the frustum k seconds of
        /// motion ahead (negative: no prefetching).
        #[arg(long)]
        k: Option<f32>,
        /// Scale factor SF of the disk cell over the frustum cell.
        #[arg(long)]
        sf: Option<f32>,
        /// Frustum depth, metres.
        #[arg(long)]
        far: Option<f32>,
        /// Object buffer budget, MiB.
        #[arg(long)]
        budget_mb: Option<usize>,
        /// Playback speed of walks that prefetch, times real time (0: unpaced, frames back
        /// to back; the prefetch thread then rarely finishes in time).
        #[arg(long, default_value_t = review::DEFAULT_PACE)]
        speed: f32,
        /// Write one row per frame here.
        #[arg(long)]
        csv: Option<PathBuf>,
        /// Save the camera path as CSV (time, x, y, z, yaw, pitch).
        #[arg(long)]
        save_path: Option<PathBuf>,
        #[arg(long, default_value = "mmap")]
        backend: Backend,
        #[arg(long, short)]
        quiet: bool,
        /// Draw every frame headless (no window) as the walk selects it, and write them
        /// as PNGs to --frames-dir.
        #[arg(long)]
        render: bool,
        #[arg(long, default_value = "frames")]
        frames_dir: PathBuf,
        /// Rendered image size, WIDTHxHEIGHT; square fits the walk's 45° × 45° view.
        #[arg(long, value_parser = parse_size, default_value = "512x512")]
        size: (u32, u32),
        /// Write every N-th rendered frame (all are drawn and timed).
        #[arg(long, default_value_t = 1)]
        every: usize,
        /// LOD selection's screen-space error, a fraction of the viewport: each object
        /// drawn at the coarsest stored level under it (0: full detail).
        #[arg(long, default_value_t = flaneur::walk::lod_select::DEFAULT_TAU)]
        lod_tau: f32,
    },
    /// Rerun an experiment of the papers on a database.
    Bench {
        #[command(subcommand)]
        experiment: Experiment,
    },
}

#[derive(Subcommand)]
enum Experiment {
    /// Each frame of a walk drawn twice, with the mode's selection and at full detail,
    /// and compared: PSNR and the share of differing pixels beside triangles drawn
    /// (the thesis's Figs. 5.26 and 6.6 as numbers). Renders headless.
    Fidelity {
        db: PathBuf,
        /// A motion pattern (normal, fast, slow, turning, backward, random), a path
        /// CSV file, or (pvs mode) cells: a walk along the walkable viewcells [default:
        /// normal; cells in pvs mode].
        #[arg(long)]
        path: Option<String>,
        /// review, box, or pvs (the viewcell's PVS with PBNP prefetching; the database
        /// must have been built with --visibility).
        #[arg(long, default_value = "review")]
        mode: String,
        #[arg(long, default_value_t = 300)]
        frames: usize,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Image size, WIDTHxHEIGHT.
        #[arg(long, value_parser = parse_size, default_value = "256x256")]
        size: (u32, u32),
        /// LOD selection's screen-space error for the mode's pictures, a fraction of the
        /// viewport (0: the mode's objects at full detail).
        #[arg(long, default_value_t = flaneur::walk::lod_select::DEFAULT_TAU)]
        lod_tau: f32,
        #[arg(long, default_value = "bench-out")]
        out: PathBuf,
    },
    /// Frame and query time against the prefetch factor k, per motion pattern (Fig. 4.17).
    PrefetchK {
        db: PathBuf,
        #[command(flatten)]
        walk: WalkArgs,
        /// The k values in seconds, comma-separated (default 0, 0.4, 0.8, 1.2, 1.6, 2, 3, 4, 6, 8).
        #[arg(long, value_delimiter = ',')]
        ks: Vec<f32>,
        /// Walks per pattern and k (the median is reported, with the spread).
        #[arg(long, default_value_t = 1)]
        repeats: usize,
        #[arg(long, default_value = "bench-out")]
        out: PathBuf,
    },
    /// Objects and time removed by frustum culling against the disk cell's scale factor (Table 4.2).
    ViewCulling {
        db: PathBuf,
        #[command(flatten)]
        walk: WalkArgs,
        /// The scale factors, comma-separated (default the thesis's 1.0 ... 3.1).
        #[arg(long, value_delimiter = ',')]
        sfs: Vec<f32>,
        #[arg(long, default_value = "bench-out")]
        out: PathBuf,
    },
    /// Disk I/Os per query, Optimal against BOX, on the five motion patterns (Table 4.1).
    Patterns {
        db: PathBuf,
        #[command(flatten)]
        walk: WalkArgs,
        #[arg(long, default_value = "bench-out")]
        out: PathBuf,
    },
    /// Index cache hit rate against cache size: LRU, DPLRU and Belady (Fig. 4.18).
    IndexCache {
        db: PathBuf,
        #[command(flatten)]
        walk: WalkArgs,
        /// Cache sizes in pages, comma-separated.
        #[arg(long, value_delimiter = ',', default_values_t = IndexCacheConfig::default().sizes)]
        sizes: Vec<usize>,
        #[arg(long, default_value = "bench-out")]
        out: PathBuf,
    },
    /// Pages read by BOX against CSearch along a walk of overlapping disk cells; then
    /// REVIEW walks: frame time and variance against cell size, Optimal / NC / NP / BOX
    /// (Fig. 4.19, 4.20), time per frame, Optimal against BOX (Fig. 4.21), and search
    /// time against database size on generated cities (Fig. 4.22).
    Csearch {
        db: PathBuf,
        #[arg(long, default_value_t = CsearchConfig::default().cell)]
        cell: f32,
        #[arg(long, default_value_t = CsearchConfig::default().step)]
        step: f32,
        #[arg(long, default_value_t = CsearchConfig::default().steps)]
        steps: usize,
        #[arg(long, default_value_t = CsearchConfig::default().history_len)]
        history_len: usize,
        /// The REVIEW walks; --seed also seeds the street walk of the query-by-query run.
        #[command(flatten)]
        walk: WalkArgs,
        /// Scale factors of the cell-size sweep, comma-separated (the thesis's cell sizes by default).
        #[arg(long, value_delimiter = ',', default_values_t = CellSizeConfig::default().sfs)]
        sfs: Vec<f32>,
        /// Objects in each city of the database-size series, comma-separated; the cities
        /// are generated and built once into `--out`/cities and reused.
        #[arg(long, value_delimiter = ',', default_values_t = DbSizeConfig::default().sizes)]
        sizes: Vec<u64>,
        /// Only the query-by-query run: skip the REVIEW walks (long on a large city).
        #[arg(long)]
        no_walks: bool,
        /// Skip the second run on a copy of the index built by insertion with the
        /// linear split (the thesis's setting), which is built in `--out`.
        #[arg(long)]
        packed_only: bool,
        #[arg(long, default_value = "mmap")]
        backend: Backend,
        /// Folder for the CSVs, plots and summary.
        #[arg(long, default_value = "bench-out")]
        out: PathBuf,
        /// Print every query, not just the summary.
        #[arg(long)]
        verbose: bool,
    },
    /// DAG edges, build time and bytes per vertex: full-, non- and mini-redundant, on the
    /// bunny and bumpy tori of the thesis's sizes (Zheng Tables 3.1–3.3). No database.
    LodDag {
        /// Triangles of each bumpy torus, comma-separated [default: 69451,1087474].
        #[arg(long, value_delimiter = ',')]
        sizes: Vec<usize>,
        /// The bunny and the 69,451-triangle torus only (under a second).
        #[arg(long, conflicts_with = "sizes")]
        quick: bool,
        /// Build the non-redundant DAG (worst case quadratic) only up to this many
        /// triangles [default: always].
        #[arg(long)]
        non_redundant_max: Option<usize>,
        #[arg(long, default_value = "bench-out")]
        out: PathBuf,
    },
    /// One large mesh's progressive mesh built on 1 and on all threads: time, speed-up and
    /// load balance (El-Sana & Varshney Tables 1–2), beside the serial build; and the
    /// throughput of building many city objects' progressive meshes. No database.
    LodParallel {
        /// Triangles of each bumpy torus, comma-separated [default: 250000,1000000].
        #[arg(long, value_delimiter = ',')]
        triangles: Vec<usize>,
        /// Thread counts, comma-separated; the first is the speed-ups' base
        /// [default: 1 and every core].
        #[arg(long, value_delimiter = ',')]
        threads: Vec<usize>,
        /// Builds per measurement; the median counts.
        #[arg(long, default_value_t = LodParallelConfig::default().repeats)]
        repeats: usize,
        /// City objects for the throughput rows (0: none).
        #[arg(long, default_value_t = LodParallelConfig::default().objects)]
        objects: u64,
        /// Octree leaves hold at most this many triangles on average.
        #[arg(long, default_value_t = LodParallelConfig::default().options.leaf_triangles)]
        leaf_triangles: usize,
        #[arg(long, default_value = "bench-out")]
        out: PathBuf,
    },
    /// Traversal and update time, accuracy and fronts per frame along a scripted orbit:
    /// priority, linear and constant-time traversals (Zheng Tables 4.1, 4.3, Fig. 4.11,
    /// 4.12). No database.
    LodRefine {
        /// Triangles of the bumpy-torus landmark.
        #[arg(long, default_value_t = lod_refine::DEFAULT_TRIANGLES)]
        triangles: usize,
        #[arg(long, default_value_t = lod_refine::DEFAULT_FRAMES)]
        frames: usize,
        /// Screen-space errors τ, fractions of the viewport, comma-separated; one run each
        /// [default: 0.001 (the thesis's), 0.0003, 0.0001].
        #[arg(long, value_delimiter = ',')]
        taus: Vec<f32>,
        /// Triangle budget (0: none, fidelity alone).
        #[arg(long, default_value_t = flaneur::lod::THESIS_BUDGET)]
        budget: usize,
        /// N: operators per pass (priority, linear) or nodes evaluated (constant-time).
        #[arg(long, default_value_t = flaneur::lod::THESIS_MAX_WORK)]
        max_work: usize,
        /// Runs of each orbit; a frame's times are the shortest over them.
        #[arg(long, default_value_t = LodRefineConfig::default().repeats)]
        repeats: usize,
        #[arg(long, default_value = "bench-out")]
        out: PathBuf,
    },
    /// SNP against PBNP neighbour PVS prefetching on the thesis's synthetic city and its
    /// two routes: transactions, cache swaps, objects sent, visual misses (Zheng Table
    /// 7.2, Figs. 7.6–7.8), and PBNP against its region size. No database.
    PvsPrefetch {
        /// Buildings along each side of the synthetic city.
        #[arg(long, default_value_t = SyntheticConfig::default().blocks)]
        blocks: u32,
        /// Mean PVS size, a share of the buildings.
        #[arg(long, default_value_t = SyntheticConfig::default().pvs_share)]
        share: f64,
        /// Share of a viewcell's PVS that a side neighbour also sees.
        #[arg(long, default_value_t = SyntheticConfig::default().overlap)]
        overlap: f64,
        /// Steps of each route.
        #[arg(long, default_value_t = RouteConfig::default().steps)]
        steps: usize,
        /// Metres per step.
        #[arg(long, default_value_t = RouteConfig::default().step)]
        step: f64,
        /// PBNP's side and corner regions, a fraction of a cell's side, in (0, 0.5].
        #[arg(long, default_value_t = PvsPrefetchConfig::default().border)]
        border: f64,
        /// Region sizes of PBNP's sweep, comma-separated [default: 0.1, 0.15, … 0.5].
        #[arg(long, value_delimiter = ',')]
        borders: Vec<f64>,
        /// Client cache entries (viewcells); at least 9.
        #[arg(long, default_value_t = PvsPrefetchConfig::default().capacity)]
        cache: usize,
        /// Draws the PVS table and both routes.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Also run the experiment, both routes and the region sweep, over this
        /// database's precomputed visibility (built with --visibility); its files go to
        /// OUT/pvs-prefetch-db.
        #[arg(long)]
        db: Option<PathBuf>,
        #[arg(long, default_value = "bench-out")]
        out: PathBuf,
    },
}

/// The walk every walking experiment takes (`bench::walk_setup::WalkSetup`).
#[derive(clap::Args)]
struct WalkArgs {
    #[arg(long, help = frames_help())]
    frames: Option<usize>,
    #[arg(long, default_value_t = walk_setup::DEFAULT_FPS)]
    fps: f32,
    #[arg(long, default_value_t = walk_setup::DEFAULT_SEED)]
    seed: u64,
    /// Frustum depth, metres.
    #[arg(long, default_value_t = review::DEFAULT_FAR)]
    far: f32,
    /// Scale factor SF of the disk cell (not used where SF is swept).
    #[arg(long, default_value_t = review::DEFAULT_SF)]
    sf: f32,
    /// Object buffer budget, MiB.
    #[arg(long, default_value_t = review::DEFAULT_MEMORY_BUDGET >> 20)]
    budget_mb: usize,
    /// Motion patterns, comma-separated (default: the thesis's five; normal where one
    /// path is walked).
    #[arg(long, value_delimiter = ',')]
    patterns: Vec<Motion>,
    /// Playback speed of walks that prefetch, times real time (0: unpaced, frames back
    /// to back; the prefetch thread then rarely finishes in time).
    #[arg(long, default_value_t = review::DEFAULT_PACE)]
    speed: f32,
}

/// `--speed` as the walk takes it: 0 for unpaced.
fn pace(speed: f32) -> Option<f32> {
    (speed != 0.0).then_some(speed)
}

/// `--frames`'s help, with the defaults as the library has them.
fn frames_help() -> String {
    format!(
        "Frames of each walk [default: {}; {} for bench patterns; {} for bench csearch's figures, which walk once per configuration and cell size or city]",
        walk_setup::DEFAULT_FRAMES,
        walk_setup::PATTERN_FRAMES,
        walk_setup::SHORT_FRAMES
    )
}

impl WalkArgs {
    /// The experiment's walk: these settings over `base`, the experiment's default,
    /// which gives the frames and the patterns when they are not given.
    fn setup(self, base: WalkSetup) -> WalkSetup {
        WalkSetup {
            frames: self.frames.unwrap_or(base.frames),
            fps: self.fps,
            seed: self.seed,
            far: self.far,
            sf: self.sf,
            memory_budget: self.budget_mb.saturating_mul(1 << 20),
            patterns: if self.patterns.is_empty() {
                base.patterns
            } else {
                self.patterns
            },
            pace: pace(self.speed),
        }
    }
}

fn main() {
    if let Err(e) = run(Cli::parse()) {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Demo {
            objects,
            cache,
            frames,
        } => demo(objects, &cache, frames),
        Command::Build {
            inputs,
            out,
            page_size,
            fill,
            insertion,
            no_lod,
            pm_threshold,
            visibility,
            cell_size,
            dov_resolution,
            sample_spacing,
            occluder_radius,
            quiet,
        } => {
            let opts = BuildOptions {
                visibility: visibility.then(|| VisibilityOptions {
                    cell_size,
                    resolution: dov_resolution,
                    samples: SampleOptions {
                        spacing: sample_spacing,
                        radius: occluder_radius,
                    },
                    ..VisibilityOptions::default()
                }),
                page_size,
                fill,
                insertion,
                lod: (!no_lod).then(|| LodOptions {
                    pm_threshold,
                    ..LodOptions::default()
                }),
            };
            let summary = build(&inputs, &out, &opts, !quiet)?;
            println!(
                "built {}: {} objects, {} triangles, {} pages ({:.1} MiB), tree height {}, {:.1} s",
                out.display(),
                summary.objects,
                summary.triangles,
                summary.pages,
                summary.bytes as f64 / (1 << 20) as f64,
                summary.height,
                summary.seconds
            );
            print_lod_report(summary.lod.as_ref(), summary.bytes);
            if let Some(v) = &summary.visibility {
                println!(
                    "  visibility: {} walkable cells of {} × {}, {:.1} objects per PVS, {} occluders; \
                     {:.1} s ({:.3} s per cell, of which DoV {:.3} s at {:.2} M rays/s)",
                    v.cells,
                    v.rows,
                    v.columns,
                    v.entries as f64 / v.cells.max(1) as f64,
                    v.occluders,
                    v.seconds,
                    v.seconds / v.cells.max(1) as f64,
                    v.dov_seconds / v.cells.max(1) as f64,
                    v.rays as f64 / v.dov_seconds.max(1e-9) / 1e6
                );
            }
            Ok(())
        }
        Command::Info { db, json } => info(&db, json),
        Command::View {
            db,
            mode,
            size,
            lod_tau,
            at,
            look,
            record,
            play,
            gpu_budget_mb,
            speed,
            boxes,
            top_view,
        } => {
            let mode = match mode.as_str() {
                "review" => ViewMode::Review,
                "box" => ViewMode::Box,
                "pvs" => ViewMode::Pvs,
                other => {
                    bail!("the window shows the review, box and pvs modes so far, not '{other}'")
                }
            };
            let db = Database::open(&db)?;
            let start = match at {
                Some(p) => flaneur::walk::Pose {
                    time: 0.0,
                    position: p,
                    yaw: look.0.to_radians(),
                    pitch: look.1.to_radians(),
                },
                None => flaneur::walk::start::busiest_street(&db)?,
            };
            let play = play
                .map(|p| {
                    CameraPath::load_csv(&p).with_context(|| format!("reading {}", p.display()))
                })
                .transpose()?;
            let opts = flaneur_render::ViewOptions {
                size,
                lod_tau: (lod_tau != 0.0).then_some(lod_tau),
                play,
                gpu_budget: (gpu_budget_mb > 0.0).then_some((gpu_budget_mb * 1048576.0) as u64),
                speed,
                ..flaneur_render::ViewOptions::new(&db, start)
            };
            view(&db, opts, mode, (boxes, top_view), record.as_deref())
        }
        Command::Shot {
            db,
            at,
            look,
            size,
            fov,
            out,
        } => {
            let db = Database::open(&db)?;
            let camera = flaneur::geom::Camera::new(at, look.0.to_radians(), look.1.to_radians())?
                .with_fov(fov.to_radians(), fov.to_radians())?;
            let gpu = flaneur_render::Gpu::headless()?;
            let s = flaneur_render::shot(&db, &gpu, &camera, size.0, size.1)?;
            s.frame.save_png(&out)?;
            println!(
                "{}: {} × {} on {} ({:?}); {} objects, {} triangles, {:.1} MiB on the GPU; \
                 select {:.1} ms, upload {:.1} ms, draw and read back {:.1} ms",
                out.display(),
                size.0,
                size.1,
                gpu.adapter.name,
                gpu.adapter.backend,
                s.objects,
                s.triangles,
                s.gpu_bytes as f64 / 1048576.0,
                s.select.as_secs_f64() * 1e3,
                s.upload.as_secs_f64() * 1e3,
                s.draw.as_secs_f64() * 1e3
            );
            Ok(())
        }
        Command::Lod {
            mesh,
            out,
            ratio,
            min_triangles,
            refine,
            eye,
            look,
            tau,
            fov,
        } => lod(
            &mesh,
            out.as_deref(),
            ratio,
            min_triangles,
            refine.then_some((eye, look, tau, fov)),
        ),
        Command::Walk {
            db,
            mode,
            config,
            path,
            frames,
            fps,
            seed,
            policy,
            cache_bytes,
            k,
            sf,
            far,
            budget_mb,
            speed,
            csv,
            save_path,
            backend,
            quiet,
            prefetch,
            border,
            render,
            frames_dir,
            size,
            every,
            lod_tau,
        } => {
            let render = render.then_some(RenderOpts {
                dir: frames_dir,
                size,
                every,
                lod_tau: (lod_tau != 0.0).then_some(lod_tau),
            });
            if mode == "pvs" && config.is_none() {
                let rule = match prefetch.as_str() {
                    "snp" => PvsPrefetch::Snp,
                    "pbnp" => PvsPrefetch::Pbnp { border },
                    other => bail!("unknown prefetch '{other}' (snp, pbnp)"),
                };
                return pvs_walk_cmd(
                    &db,
                    path.as_deref().unwrap_or("cells"),
                    frames,
                    fps,
                    seed,
                    rule,
                    csv.as_deref(),
                    backend,
                    quiet,
                    render.as_ref(),
                );
            }
            let path = path.unwrap_or_else(|| "normal".into());
            let preset = match config {
                Some(p) => p,
                None => match mode.as_str() {
                    "review" => Preset::Optimal,
                    "box" => Preset::Box,
                    other => bail!("unknown mode '{other}' (review, box, pvs)"),
                },
            };
            let mut cfg = ReviewConfig::preset(preset);
            if let Some(bytes) = cache_bytes {
                cfg.index_cache =
                    (bytes > 0).then(|| (policy.clone().unwrap_or_else(|| "dplru".into()), bytes));
            } else if let (Some(p), Some(c)) = (&policy, &mut cfg.index_cache) {
                c.0 = p.clone();
            }
            if let Some(k) = k {
                cfg.prefetch_k = (k >= 0.0).then_some(k);
            }
            cfg.sf = sf.unwrap_or(cfg.sf);
            cfg.far = far.unwrap_or(cfg.far);
            cfg.memory_budget = budget_mb.map_or(cfg.memory_budget, |m| m << 20);
            cfg.pace = pace(speed);
            walk_cmd(
                &db,
                &cfg,
                &path,
                frames,
                fps,
                seed,
                csv.as_deref(),
                save_path.as_deref(),
                backend,
                quiet,
                render.as_ref(),
            )
        }
        Command::Query {
            db,
            query,
            history,
            backend,
            json,
        } => run_query(&db, &query, &history, backend, json),
        Command::Bench { experiment } => match experiment {
            Experiment::PrefetchK {
                db,
                walk,
                ks,
                repeats,
                out,
            } => {
                let d = PrefetchKConfig::default();
                let cfg = PrefetchKConfig {
                    walk: walk.setup(d.walk),
                    ks: if ks.is_empty() { d.ks } else { ks },
                    repeats,
                };
                let db = Database::open(&db)?;
                let r = prefetch_k::run(&db, &cfg)?;
                write_experiment(&out, "prefetch-k", &r.to_csv(), &r.markdown(), |dir| {
                    Ok(r.plot(dir)?)
                })
            }
            Experiment::ViewCulling { db, walk, sfs, out } => {
                let d = ViewCullingConfig::default();
                let cfg = ViewCullingConfig {
                    walk: walk.setup(d.walk),
                    sfs: if sfs.is_empty() { d.sfs } else { sfs },
                    ..d
                };
                let db = Database::open(&db)?;
                let r = view_culling::run(&db, &cfg)?;
                write_experiment(&out, "view-culling", &r.to_csv(), &r.markdown(), |dir| {
                    Ok(r.plot(dir)?)
                })
            }
            Experiment::Patterns { db, walk, out } => {
                let d = PatternsConfig::default();
                let cfg = PatternsConfig {
                    walk: walk.setup(d.walk),
                    ..d
                };
                let db = Database::open(&db)?;
                let r = patterns::run(&db, &cfg)?;
                write_experiment(&out, "patterns", &r.to_csv(), &r.markdown(), |dir| {
                    Ok(r.plot(dir)?)
                })
            }
            Experiment::IndexCache {
                db,
                walk,
                sizes,
                out,
            } => {
                let cfg = IndexCacheConfig {
                    walk: walk.setup(IndexCacheConfig::default().walk),
                    sizes,
                };
                bench_index_cache(&db, &cfg, &out)
            }
            Experiment::Csearch {
                db,
                cell,
                step,
                steps,
                history_len,
                walk,
                sfs,
                sizes,
                no_walks,
                packed_only,
                backend,
                out,
                verbose,
            } => {
                let cfg = CsearchConfig {
                    cell,
                    step,
                    steps,
                    seed: walk.seed,
                    history_len,
                    ..CsearchConfig::default()
                };
                let walks = (!no_walks).then(|| CsearchWalks {
                    walk: walk.setup(CellSizeConfig::default().walk),
                    sfs,
                    sizes,
                });
                bench_csearch(&db, &cfg, !packed_only, backend, &out, verbose, walks)
            }
            Experiment::LodDag {
                sizes,
                quick,
                non_redundant_max,
                out,
            } => {
                let d = if quick {
                    LodDagConfig::quick()
                } else {
                    LodDagConfig::default()
                };
                let cfg = LodDagConfig {
                    sizes: if sizes.is_empty() { d.sizes } else { sizes },
                    non_redundant_max,
                    ..d
                };
                let r = with_bar("lod-dag models", |p| lod_dag::run_with_progress(&cfg, p))?;
                write_experiment(&out, "lod-dag", &r.to_csv(), &r.markdown(), |dir| {
                    Ok(r.plot(dir)?)
                })
            }
            Experiment::LodParallel {
                triangles,
                threads,
                repeats,
                objects,
                leaf_triangles,
                out,
            } => {
                let d = LodParallelConfig::default();
                let cfg = LodParallelConfig {
                    triangles: if triangles.is_empty() {
                        d.triangles
                    } else {
                        triangles
                    },
                    threads: if threads.is_empty() {
                        d.threads
                    } else {
                        threads
                    },
                    repeats,
                    objects,
                    options: flaneur::lod::ParallelOptions {
                        leaf_triangles,
                        ..d.options
                    },
                };
                let r = with_bar("lod-parallel builds", |p| lod_parallel::run(&cfg, p))?;
                write_experiment(&out, "lod-parallel", &r.to_csv(), &r.markdown(), |dir| {
                    Ok(r.plot(dir)?)
                })
            }
            Experiment::Fidelity {
                db,
                path,
                mode,
                frames,
                seed,
                size,
                lod_tau,
                out,
            } => {
                let preset = match mode.as_str() {
                    "review" => Some(Preset::Optimal),
                    "box" => Some(Preset::Box),
                    "pvs" => None,
                    other => bail!("fidelity draws the review, box and pvs modes, not '{other}'"),
                };
                let db = Database::open(&db)?;
                if preset.is_none() && !db.has_visibility() {
                    bail!(
                        "{} has no precomputed visibility for the pvs mode (build it with --visibility)",
                        db.store().path().display()
                    );
                }
                let fps = 30.0;
                let path = path.unwrap_or_else(|| {
                    if preset.is_some() { "normal" } else { "cells" }.to_string()
                });
                let poses = match path.as_str() {
                    "cells" if preset.is_none() => {
                        pvs_walk::cell_walk(&db, frames, 1.4 / fps, fps, seed)?
                    }
                    other => camera_path(&db, other, frames, fps, seed)?,
                };
                let cfg = ReviewConfig {
                    pace: None,
                    ..ReviewConfig::preset(preset.unwrap_or(Preset::Optimal))
                };
                let walk = match preset {
                    Some(_) => flaneur_bench::fidelity::ModeWalk::Review(&cfg),
                    None => flaneur_bench::fidelity::ModeWalk::Pvs(PvsPrefetch::Pbnp {
                        border: PvsPrefetchConfig::default().border,
                    }),
                };
                let gpu = flaneur_render::Gpu::headless()?;
                println!(
                    "fidelity: {} frames of {} in {mode} mode, {} × {}, each drawn twice",
                    poses.poses.len(),
                    path,
                    size.0,
                    size.1
                );
                let bar = indicatif::ProgressBar::new(poses.poses.len() as u64);
                let drawing = flaneur_bench::fidelity::Drawing {
                    width: size.0,
                    height: size.1,
                    lod_tau: (lod_tau != 0.0).then_some(lod_tau),
                };
                let r = flaneur_bench::fidelity::run(
                    &db,
                    &gpu,
                    &poses,
                    walk,
                    &mode,
                    &drawing,
                    |_| bar.inc(1),
                )?;
                bar.finish_and_clear();
                write_experiment(&out, "fidelity", &r.to_csv(), &r.markdown(), |dir| {
                    Ok(r.plot(dir)?)
                })
            }
            Experiment::LodRefine {
                triangles,
                frames,
                taus,
                budget,
                max_work,
                repeats,
                out,
            } => {
                let d = LodRefineConfig::default();
                let cfg = LodRefineConfig {
                    triangles,
                    frames,
                    taus: if taus.is_empty() {
                        d.taus.clone()
                    } else {
                        taus
                    },
                    orbit: flaneur_bench::lod_orbit::OrbitConfig {
                        budget: (budget > 0).then_some(budget),
                        max_work,
                        ..d.orbit
                    },
                    repeats,
                    ..d
                };
                println!(
                    "lod-refine: a bumpy torus of about {triangles} triangles, {frames} frames"
                );
                let r = lod_refine::run(&cfg)?;
                write_experiment(&out, "lod-refine", &r.to_csv(), &r.markdown(), |dir| {
                    Ok(r.plot(dir)?)
                })
            }
            Experiment::PvsPrefetch {
                blocks,
                share,
                overlap,
                steps,
                step,
                border,
                borders,
                cache,
                seed,
                db,
                out,
            } => {
                let d = PvsPrefetchConfig::default();
                let cfg = PvsPrefetchConfig {
                    city: SyntheticConfig {
                        blocks,
                        pvs_share: share,
                        overlap,
                        seed,
                        ..d.city
                    },
                    route: RouteConfig { steps, step, seed },
                    border,
                    capacity: cache,
                    borders: if borders.is_empty() {
                        d.borders
                    } else {
                        borders
                    },
                };
                let r = pvs_prefetch::run(&cfg)?;
                write_experiment(&out, "pvs-prefetch", &r.to_csv(), &r.markdown(), |dir| {
                    for (name, text) in r.extra_csvs() {
                        write_file(&dir.join(name), &text)?;
                    }
                    Ok(r.plot(dir)?)
                })?;
                if let Some(path) = db {
                    let db = Database::open(&path)?;
                    let name = path.display().to_string();
                    let r = pvs_prefetch::run_on_database(&db, &name, &cfg)?;
                    println!();
                    write_experiment(
                        &out.join("pvs-prefetch-db"),
                        "pvs-prefetch",
                        &r.to_csv(),
                        &r.markdown(),
                        |dir| {
                            for (name, text) in r.extra_csvs() {
                                write_file(&dir.join(name), &text)?;
                            }
                            Ok(r.plot(dir)?)
                        },
                    )?;
                }
                Ok(())
            }
        },
    }
}

fn build(
    inputs: &[PathBuf],
    out: &Path,
    opts: &BuildOptions,
    bars: bool,
) -> Result<flaneur::BuildSummary> {
    let is_obj = |p: &PathBuf| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    let progress: &dyn Progress = if bars { &Bars::default() } else { &Silent };
    if inputs.iter().all(is_obj) {
        Ok(flaneur::build_from_obj_with_progress(inputs, out, opts, progress)?)
    } else if inputs.len() == 1 {
        Ok(flaneur::build_from_scene_with_progress(&inputs[0], out, opts, progress)?)
    } else {
        bail!("give one scene file, or OBJ files only")
    }
}

fn info(path: &Path, json: bool) -> Result<()> {
    let db = Database::open(path)?;
    let info = db.info()?;
    if json {
        println!("{}", serde_json::to_string_pretty(&info)?);
        return Ok(());
    }
    let k = &info.pages_by_kind;
    println!("database    {}", path.display());
    println!("objects     {}", info.objects);
    println!("triangles   {}", info.triangles);
    println!(
        "pages       {} of {} bytes ({:.1} MiB)",
        info.pages,
        info.page_size,
        info.file_bytes as f64 / (1 << 20) as f64
    );
    println!(
        "  by kind   header 1, r-tree {}, mesh {}, meta {}, lod {}, visibility {}",
        k.rtree, k.mesh, k.meta, k.lod, k.visibility
    );
    match &info.lod {
        None => println!("lods        none (built with --no-lod, or before LODs were stored)"),
        Some(l) => {
            let bytes = l.pages * info.page_size as u64;
            println!(
                "lods        {} of {} objects, {} levels coarser than the full meshes, {} pages ({:.1} MiB, {:.1}% of the file)",
                l.with_levels,
                info.objects,
                l.levels,
                l.pages,
                bytes as f64 / (1 << 20) as f64,
                100.0 * bytes as f64 / info.file_bytes.max(1) as f64
            );
            println!(
                "  settings  ratio {}, down to {} triangles; PM + DAG above {} triangles: {} objects",
                l.ratio, l.min_triangles, l.pm_threshold, l.with_pm
            );
            if l.refused > 0 {
                println!(
                    "  refused   {} objects the simplifier refused have no LODs",
                    l.refused
                );
            }
        }
    }
    match &info.visibility {
        None => println!("visibility  none (built without --visibility)"),
        Some(v) => {
            println!(
                "visibility  {} walkable cells of {} × {} ({} m, eyes {}–{} m), {} pages",
                v.cells, v.rows, v.columns, v.cell_size, v.eye[0], v.eye[1], k.visibility
            );
            println!(
                "  PVS       {:.1} objects on average, {:.2}% of the scene (patches of {} m, occluders within {} m)",
                v.mean_pvs,
                100.0 * v.mean_share,
                v.sample_spacing,
                v.occluder_radius
            );
            println!(
                "  computed  in {:.1} s, {:.3} s per cell; DoV at N = {}: {:.3} s per cell, {} rays, {:.2} M rays/s",
                v.seconds,
                v.seconds_per_cell,
                v.resolution,
                v.dov_seconds_per_cell,
                v.rays,
                v.rays_per_second / 1e6
            );
        }
    }
    let b = info.bounds;
    println!(
        "bounds      x {:.1}..{:.1}  y {:.1}..{:.1}  z {:.1}..{:.1}",
        b[0], b[3], b[1], b[4], b[2], b[5]
    );
    println!(
        "r-tree      height {}, fan-out {} (leaf) / {} (internal), fill {:.1}%",
        info.tree.height,
        info.fanout_leaf,
        info.fanout_internal,
        info.tree.fill * 100.0
    );
    for (level, (n, e)) in info.tree.nodes.iter().zip(&info.tree.entries).enumerate() {
        println!("  level {level}   {n} nodes, {e} entries");
    }
    Ok(())
}

/// The LOD lines of a build's summary.
fn print_lod_report(lod: Option<&LodReport>, file_bytes: u64) {
    let Some(r) = lod else {
        println!("  LODs: none (--no-lod)");
        return;
    };
    let s = &r.stats;
    println!(
        "  LODs: {} objects simplified, {} with coarse levels ({} levels), {} with PM + DAG (over {} triangles); \
         {} pages ({:.1} MiB, {:.1}% of the file); {:.1} s of the build ({:.1} s of simplifying tasks on {} threads)",
        s.objects,
        s.with_levels,
        s.levels,
        s.with_pm,
        s.pm_threshold,
        s.pages,
        r.bytes as f64 / (1 << 20) as f64,
        100.0 * r.bytes as f64 / file_bytes.max(1) as f64,
        r.seconds,
        r.task_seconds,
        r.threads
    );
    if s.refused > 0 {
        println!(
            "  LODs: {} objects refused by the simplifier have none (first: {})",
            s.refused,
            r.first_refusal.as_deref().unwrap_or("?")
        );
    }
}

fn run_query(path: &Path, q: &Aabb, history: &[Aabb], backend: Backend, json: bool) -> Result<()> {
    let db = Database::open_with(path, backend)?;
    let t = Instant::now();
    let result = if history.is_empty() {
        db.range(q)?
    } else {
        db.csearch(q, history)?
    };
    let us = t.elapsed().as_secs_f64() * 1e6;
    let io = db.io();
    if json {
        let v = serde_json::json!({
            "query": if history.is_empty() { "box" } else { "csearch" },
            "ids": result.ids(),
            "pages": result.pages,
            "page_reads": io.page_reads,
            "micros": us,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    let ids: Vec<String> = result.ids().iter().map(u64::to_string).collect();
    println!("{} objects: {}", ids.len(), ids.join(" "));
    let pages: Vec<String> = result.pages.iter().map(u64::to_string).collect();
    println!("{} pages read: {}", pages.len(), pages.join(" "));
    println!("{:.0} µs", us);
    Ok(())
}

/// The REVIEW walks of `bench csearch` as the command line gives them (Fig. 4.19–4.22).
struct CsearchWalks {
    walk: WalkSetup,
    sfs: Vec<f32>,
    sizes: Vec<u64>,
}

/// The settings of each figure of [`CsearchWalks`], checked.
struct WalkFigures {
    cell: CellSizeConfig,
    frames: FrameTimeConfig,
    sizes: DbSizeConfig,
}

impl CsearchWalks {
    /// Each figure's settings, checked before anything runs; the cities of the size
    /// series get the page size of the database benched.
    fn figures(self, page_size: usize) -> Result<WalkFigures> {
        let f = WalkFigures {
            cell: CellSizeConfig {
                walk: self.walk.clone(),
                sfs: self.sfs,
            },
            frames: FrameTimeConfig {
                walk: self.walk.clone(),
            },
            sizes: DbSizeConfig {
                walk: self.walk,
                sizes: self.sizes,
                page_size,
                ..DbSizeConfig::default()
            },
        };
        f.cell.validate()?;
        f.frames.validate()?;
        f.sizes.validate()?;
        Ok(f)
    }
}

fn bench_csearch(
    path: &Path,
    cfg: &CsearchConfig,
    insertion: bool,
    backend: Backend,
    out: &Path,
    verbose: bool,
    walks: Option<CsearchWalks>,
) -> Result<()> {
    let db = Database::open_with(path, backend)?;
    let walks = walks
        .map(|w| w.figures(db.store().page_size()))
        .transpose()?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let mut reports = vec![csearch::run(&db, cfg)?];
    if insertion {
        reports.push(csearch::run_insertion_tree(
            &db,
            cfg,
            &out.join("insertion-tree.flaneur"),
        )?);
    }
    let csv: String = reports
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let s = r.to_csv();
            if i == 0 {
                s
            } else {
                s.lines().skip(1).map(|l| format!("{l}\n")).collect()
            }
        })
        .collect();
    let csv_path = out.join("csearch.csv");
    write_file(&csv_path, &csv)?;
    for (r, name) in reports
        .iter()
        .zip(["csearch-pages.png", "csearch-pages-insertion.png"])
    {
        csearch::plot(r, &out.join(name))?;
    }
    let md_path = out.join("csearch.md");
    let mut md = csearch::markdown(&reports, cfg);
    write_file(&md_path, &md)?;
    println!(
        "csearch: {} queries, cell {} m, step {} m, history ≤ {}",
        cfg.steps, cfg.cell, cfg.step, cfg.history_len
    );
    for r in &reports {
        print_report(r, verbose);
    }
    println!(
        "per-query rows in {}, plots and a summary beside it",
        csv_path.display()
    );
    if let Some(walks) = walks {
        // The summary is written again after each figure, so that a long run that stops
        // keeps what it measured.
        csearch_walks(&db, &walks, out, |section| {
            println!("\n{section}");
            md.push('\n');
            md.push_str(&section);
            write_file(&md_path, &md)
        })?;
        println!(
            "CSVs, plots and the summary ({}) in {}",
            md_path.display(),
            out.display()
        );
    }
    Ok(())
}

/// Runs the figures of `bench csearch` one after the other, each writing its CSV and
/// plots into `out` and handing its markdown section to `section`; the cities of the
/// size series go into `out`/cities.
fn csearch_walks(
    db: &Database,
    f: &WalkFigures,
    out: &Path,
    mut section: impl FnMut(String) -> Result<()>,
) -> Result<()> {
    let r = with_bar("cell size (Fig. 4.19, 4.20)", |p| {
        cell_size::run_with_progress(db, &f.cell, p)
    })?;
    write_figure(
        out,
        "csearch-cell-size",
        &r.to_csv(),
        |dir| Ok(r.plot(dir)?),
    )?;
    section(r.markdown())?;

    let r = with_bar("time per frame (Fig. 4.21)", |p| {
        frame_time::run_with_progress(db, &f.frames, p)
    })?;
    write_figure(out, "csearch-frame-time", &r.to_csv(), |dir| {
        Ok(r.plot(dir)?)
    })?;
    section(r.markdown())?;

    let r = with_bar("database size (Fig. 4.22)", |p| {
        db_size::run_with_progress(&out.join("cities"), &f.sizes, p)
    })?;
    write_figure(out, "csearch-db-size", &r.to_csv(), |dir| Ok(r.plot(dir)?))?;
    section(r.markdown())
}

/// Runs `f` under a progress bar that its `progress(done, total)` moves.
fn with_bar<T>(
    what: &str,
    f: impl FnOnce(&mut dyn FnMut(usize, usize)) -> flaneur::Result<T>,
) -> Result<T> {
    let bar = indicatif::ProgressBar::new(1);
    bar.set_message(what.to_string());
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg}: [{bar:30}] {pos}/{len} ({elapsed})")
            .expect("a valid template")
            .progress_chars("=> "),
    );
    let result = f(&mut |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    });
    bar.finish_and_clear();
    Ok(result?)
}

/// Writes a figure's CSV (`name`.csv) and plots into `out`.
fn write_figure(
    out: &Path,
    name: &str,
    csv: &str,
    plot: impl FnOnce(&Path) -> Result<()>,
) -> Result<()> {
    write_file(&out.join(format!("{name}.csv")), csv)?;
    plot(out)
}

fn write_file(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))
}

fn print_report(r: &CsearchReport, verbose: bool) {
    println!("tree: {}", r.tree);
    if verbose {
        println!(
            "{:>5} {:>8} {:>8} {:>8} {:>7} {:>8} {:>8} {:>8}",
            "step", "box pg", "cs pg", "thesis", "ratio", "box µs", "cs µs", "new"
        );
        for row in &r.rows {
            let ratio = if row.box_pages == 0 {
                0.0
            } else {
                row.csearch_pages as f64 / row.box_pages as f64
            };
            println!(
                "{:>5} {:>8} {:>8} {:>8} {:>6.1}% {:>8.0} {:>8.0} {:>8}",
                row.step,
                row.box_pages,
                row.csearch_pages,
                row.thesis_pages,
                ratio * 100.0,
                row.box_us,
                row.csearch_us,
                row.csearch_objects
            );
        }
    }
    println!(
        "  pages  BOX {}  CSearch {} ({:.1}%)  CSearch with the thesis's COverlap {} ({:.1}%)",
        r.box_pages,
        r.csearch_pages,
        r.ratio * 100.0,
        r.thesis_pages,
        r.thesis_ratio * 100.0
    );
    println!(
        "  time   BOX {:.1} ms  CSearch {:.1} ms  thesis COverlap {:.1} ms",
        r.box_ms, r.csearch_ms, r.thesis_ms
    );
}

fn demo(objects: u64, cache: &Path, frames: usize) -> Result<()> {
    std::fs::create_dir_all(cache)
        .with_context(|| format!("creating cache folder {}", cache.display()))?;
    let scene = cache.join(format!("demo-{objects}.scene"));
    let db_path = cache.join(format!("demo-{objects}.flaneur"));
    let city = citygen::CityConfig {
        objects,
        ..Default::default()
    };
    if !db_path.exists() {
        if !scene.exists() {
            println!(
                "generating a city of {objects} objects into {}",
                scene.display()
            );
            let s = citygen::write_city(&city, &scene, true)?;
            println!(
                "  {} objects, {} triangles, {:.1} MiB",
                s.objects,
                s.triangles,
                s.bytes as f64 / (1 << 20) as f64
            );
        }
        println!("building {}", db_path.display());
        let b = flaneur::build_from_scene_with_progress(
            &scene,
            &db_path,
            &BuildOptions::default(),
            &Bars::default(),
        )?;
        println!(
            "  {} pages, tree height {}, {:.1} s",
            b.pages, b.height, b.seconds
        );
        print_lod_report(b.lod.as_ref(), b.bytes);
    } else {
        println!("using {} (delete it to rebuild)", db_path.display());
    }
    let db = Database::open(&db_path)?;
    let path = motion::generate(&db.bounds(), Motion::Normal, frames, 30.0, 1)?;
    println!(
        "walking {frames} frames ({:.0} s of path, played {}x faster) of the 'normal' pattern in REVIEW mode, then with plain BOX queries",
        frames as f64 / 30.0,
        review::DEFAULT_PACE
    );
    for preset in [Preset::Optimal, Preset::Box] {
        let bar = indicatif::ProgressBar::new(frames as u64);
        let report = review::walk(&db, &path, &ReviewConfig::preset(preset), |_| bar.inc(1))?;
        bar.finish_and_clear();
        println!("{}:", preset.name());
        for f in report
            .frames
            .iter()
            .filter(|f| f.queried || f.prefetch_adopted)
        {
            let what = match (f.sync_query, f.prefetch_used, f.prefetch_adopted) {
                (true, ..) => "queried",
                (false, true, _) => "entered a prefetched cell",
                (false, false, true) => "prefetch arrived",
                _ => "waited for a prefetch",
            };
            println!(
                "  frame {:>4}: {what}, {} objects loaded, {} index + {} mesh pages read, {:.1} ms",
                f.frame, f.objects_loaded, f.index_pages, f.mesh_pages, f.frame_ms
            );
        }
        print_walk(&report);
    }
    let display = ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()));
    if display {
        println!(
            "opening a window on the city's busiest street (close it or press Q to end the demo)"
        );
        let start = flaneur::walk::start::busiest_street(&db)?;
        let opts = flaneur_render::ViewOptions::new(&db, start);
        match view(&db, opts, ViewMode::Review, (false, false), None) {
            Ok(()) => return Ok(()),
            Err(e) => println!("no window ({e:#}); drawing a flight headless instead"),
        }
    }
    demo_flight(&db, &cache.join("demo-frames"))
}

/// A session at the window: walks run one after another from where the viewer stands
/// (a key changed the mode or the budget, or the walk failed), until the window closes.
fn view(
    db: &Database,
    opts: flaneur_render::ViewOptions,
    mode: ViewMode,
    (boxes, top_view): (bool, bool),
    record: Option<&Path>,
) -> Result<()> {
    let start = opts.start;
    let preset = |m: ViewMode| ReviewConfig {
        pace: None,
        ..ReviewConfig::preset(match m {
            ViewMode::Box => Preset::Box,
            _ => Preset::Optimal,
        })
    };
    let mut mode = mode;
    let mut cfg = preset(mode);
    let mut window = flaneur_render::WalkWindow::open(db, opts, mode)?;
    window.boxes = boxes;
    window.top_view = top_view;
    if let Some(a) = window.adapter() {
        println!("drawing on {} ({:?})", a.name, a.backend);
    }
    let p = start.position;
    println!(
        "starting at {:.0}, {:.1}, {:.0} in {} mode; W A S D and the mouse (click to capture it), \
         Shift runs, F flies, 1/2/3 review/box/pvs, [ ] LOD τ, - = budget, H HUD, Q quits",
        p.x,
        p.y,
        p.z,
        mode.name()
    );
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
                let rule = flaneur::walk::pvs_walk::PvsPrefetch::Pbnp {
                    border: PvsPrefetchConfig::default().border,
                };
                flaneur::walk::pvs_walk::walk_pvs_live(db, rule, |_| {}, &mut window).map(|_| ())
            }
            _ => review::walk_live(db, &cfg, |_| {}, &mut window).map(|_| ()),
        };
        match walked {
            Ok(()) => failures = 0,
            Err(e) => {
                failures += 1;
                window.report(format!(
                    "the walk stopped: {e}; going on from where you stand"
                ));
                if failures >= 5 {
                    bail!("the walk failed five times running; last: {e}");
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
    let s = &window.summary;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let worst = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    println!(
        "{} frames drawn: CPU (LOD selection, uploads) {:.1} ms a frame (worst {:.1}; {:.1} after the cold first frame), GPU {:.1} ms (worst {:.1}); at most {:.1} MiB of meshes on the GPU ({} frames over its budget); {} problems met",
        s.frames,
        mean(&s.cpu_ms),
        worst(&s.cpu_ms),
        worst(s.cpu_ms.get(1..).unwrap_or_default()),
        mean(&s.gpu_ms),
        worst(&s.gpu_ms),
        s.peak_gpu_bytes as f64 / 1048576.0,
        s.over_budget,
        s.problems.len()
    );
    if let Some(r) = record {
        flaneur_render::save_recording(&window.recorded, r)?;
        println!(
            "{} poses recorded to {}",
            window.recorded.len(),
            r.display()
        );
    }
    Ok(())
}

/// The demo's last part where there is no display: a short flight over the city drawn
/// headless to PNG frames. Without a GPU adapter, it says so and the demo ends well.
fn demo_flight(db: &Database, dir: &Path) -> Result<()> {
    let gpu = match flaneur_render::Gpu::headless() {
        Ok(gpu) => gpu,
        Err(e) => {
            println!("no flight drawn: {e}");
            return Ok(());
        }
    };
    // Four seconds across the city's middle, 120 m up, looking ahead and down.
    let b = db.bounds();
    let (c, e) = (b.center(), b.extent());
    let (from, to) = (
        glam::Vec3::new(c.x - 0.3 * e.x, b.min.y + 120.0, c.z - 0.3 * e.z),
        glam::Vec3::new(c.x + 0.1 * e.x, b.min.y + 120.0, c.z + 0.1 * e.z),
    );
    let yaw = (to.z - from.z).atan2(to.x - from.x);
    let frames = 120;
    let poses = (0..frames)
        .map(|i| {
            let t = i as f32 / (frames - 1) as f32;
            flaneur::walk::Pose {
                time: i as f64 / 30.0,
                position: from.lerp(to, t),
                yaw,
                pitch: -0.35,
            }
        })
        .collect();
    let path = CameraPath::new(poses)?;
    let cfg = ReviewConfig::preset(Preset::Optimal);
    println!(
        "drawing a {frames}-frame flight over the city on {} ({:?}), headless",
        gpu.adapter.name, gpu.adapter.backend
    );
    let mut writer = flaneur_render::FrameWriter::new(&gpu, (640, 640), (&b, cfg.far), dir, 10)?
        .with_lods(db, flaneur::walk::lod_select::DEFAULT_TAU)?;
    let bar = indicatif::ProgressBar::new(frames as u64);
    review::walk_into(db, &path, &cfg, |_| bar.inc(1), &mut writer)?;
    bar.finish_and_clear();
    let t = &writer.times;
    println!(
        "  {} frames drawn ({:.0} ms each on average, {:.0} triangles, {:.0} objects at a coarse level), every tenth written: {}",
        t.frames,
        t.draw_ms.iter().sum::<f64>() / t.frames.max(1) as f64,
        t.triangles.iter().sum::<u64>() as f64 / t.frames.max(1) as f64,
        t.coarse.iter().sum::<usize>() as f64 / t.frames.max(1) as f64,
        dir.join("frame-*.png").display()
    );
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn walk_cmd(
    path: &Path,
    cfg: &ReviewConfig,
    camera: &str,
    frames: usize,
    fps: f32,
    seed: u64,
    csv: Option<&Path>,
    save_path: Option<&Path>,
    backend: Backend,
    quiet: bool,
    render: Option<&RenderOpts>,
) -> Result<()> {
    let db = Database::open_with(path, backend)?;
    let poses = camera_path(&db, camera, frames, fps, seed)?;
    if let Some(p) = save_path {
        poses.save_csv(p)?;
    }
    let bar = if quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(poses.poses.len() as u64)
    };
    let (report, drawn) = rendered(&db, render, cfg.far, |sink| {
        review::walk_into(&db, &poses, cfg, |_| bar.inc(1), sink)
    })?;
    bar.finish_and_clear();
    if let Some(p) = csv {
        std::fs::write(p, report.to_csv()).with_context(|| format!("writing {}", p.display()))?;
    }
    print_walk(&report);
    if let (Some(drawn), Some(r)) = (drawn, render) {
        print_render(&drawn, r)?;
    }
    Ok(())
}

/// Runs `walk` with a frame writer when `render` asks for one (frames drawn with a
/// ground reaching `far` past the city), else with no sink; and what drawing cost.
fn rendered<R>(
    db: &Database,
    render: Option<&RenderOpts>,
    far: f32,
    walk: impl FnOnce(&mut dyn flaneur::walk::FrameSink) -> flaneur::Result<R>,
) -> Result<(R, Option<Drawn>)> {
    let Some(r) = render else {
        return Ok((walk(&mut flaneur::walk::NoSink)?, None));
    };
    let gpu = flaneur_render::Gpu::headless()?;
    let mut writer =
        flaneur_render::FrameWriter::new(&gpu, r.size, (&db.bounds(), far), &r.dir, r.every)?;
    if let Some(tau) = r.lod_tau {
        writer = writer.with_lods(db, tau)?;
    }
    let result = walk(&mut writer)?;
    Ok((
        result,
        Some(Drawn {
            adapter: gpu.adapter.clone(),
            times: writer.times,
        }),
    ))
}

/// What drew a walk, and what it cost.
struct Drawn {
    adapter: flaneur_render::AdapterInfo,
    times: flaneur_render::FrameTimes,
}

/// What drawing a walk's frames cost, printed and written to `render.csv` beside them.
fn print_render(drawn: &Drawn, r: &RenderOpts) -> Result<()> {
    let (adapter, t) = (&drawn.adapter, &drawn.times);
    let csv = r.dir.join("render.csv");
    std::fs::write(&csv, t.to_csv()).with_context(|| format!("writing {}", csv.display()))?;
    let stats = |v: &[f64]| {
        let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
        (mean, v.iter().copied().fold(0.0, f64::max))
    };
    let ((select, select_max), (up, up_max), (draw, draw_max)) =
        (stats(&t.select_ms), stats(&t.upload_ms), stats(&t.draw_ms));
    println!(
        "rendered {} frames of {} × {} on {} ({:?}), {} written to {}: LOD selection {:.1} ms a \
             frame (most {:.1}), uploads {:.1} ms (most {:.1}), drawing and reading back {:.1} ms \
             (most {:.1}); {} uploads, {} frees, at most {:.1} MiB of meshes on the GPU",
        t.frames,
        r.size.0,
        r.size.1,
        adapter.name,
        adapter.backend,
        t.written,
        r.dir.display(),
        select,
        select_max,
        up,
        up_max,
        draw,
        draw_max,
        t.uploads,
        t.evictions,
        t.peak_gpu_bytes as f64 / 1048576.0
    );
    if let Some(c) = t.lod {
        println!(
            "  LOD selection: {} draws coarser than full detail, {} levels read; {} draws refined view by view ({} vertex splits and edge collapses), {} progressive meshes decoded off the frame's thread ({} draws at discrete levels meanwhile); {} pages",
            c.coarse_draws, c.levels_read, c.refined_draws, c.refine_ops, c.decoded, c.drawn_while_decoding, c.pages
        );
    }
    println!("  per-frame times in {}", csv.display());
    Ok(())
}

/// Where and how `walk --render` draws its frames.
struct RenderOpts {
    dir: PathBuf,
    size: (u32, u32),
    every: usize,
    lod_tau: Option<f32>,
}

/// The poses of `camera`: a motion pattern over `db`'s bounds, or a path CSV file.
fn camera_path(
    db: &Database,
    camera: &str,
    frames: usize,
    fps: f32,
    seed: u64,
) -> Result<CameraPath> {
    Ok(match camera.parse::<Motion>() {
        Ok(m) => motion::generate(&db.bounds(), m, frames, fps, seed)?,
        Err(_) => CameraPath::load_csv(Path::new(camera)).with_context(|| {
            format!("'{camera}' is neither a motion pattern nor a readable path file")
        })?,
    })
}

#[allow(clippy::too_many_arguments)]
fn pvs_walk_cmd(
    path: &Path,
    camera: &str,
    frames: usize,
    fps: f32,
    seed: u64,
    rule: PvsPrefetch,
    csv: Option<&Path>,
    backend: Backend,
    quiet: bool,
    render: Option<&RenderOpts>,
) -> Result<()> {
    let db = Database::open_with(path, backend)?;
    let poses = match camera {
        // A walker's pace: 1.4 m/s.
        "cells" => pvs_walk::cell_walk(&db, frames, 1.4 / fps, fps, seed)?,
        other => camera_path(&db, other, frames, fps, seed)?,
    };
    let bar = if quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(poses.poses.len() as u64)
    };
    // The PVS walk's cameras have the default frustum (`Pose::camera`).
    let (r, drawn) = rendered(&db, render, flaneur::geom::DEFAULT_FAR, |sink| {
        pvs_walk::walk_pvs_into(&db, &poses, rule, |_| bar.inc(1), sink)
    })?;
    bar.finish_and_clear();
    if let Some(p) = csv {
        let mut out = String::from("frame,cell,drawn,transaction,sent,swaps,visual_misses,pages\n");
        for (i, f) in r.frames.iter().enumerate() {
            out.push_str(&format!(
                "{i},{},{},{},{},{},{},{}\n",
                f.cell.map_or(String::new(), |c| c.to_string()),
                f.drawn,
                f.transaction as u8,
                f.sent,
                f.swaps,
                f.visual_misses,
                f.pages
            ));
        }
        std::fs::write(p, out).with_context(|| format!("writing {}", p.display()))?;
    }
    println!(
        "pvs walk, {} prefetch: {} frames ({} outside any walkable cell), {} cells entered",
        r.prefetch.name(),
        r.frames.len(),
        r.frames_outside,
        r.cells_entered
    );
    println!(
        "  {} prefetch transactions, {} cache swaps, {:.1} objects per transaction, {} visual misses",
        r.transactions,
        r.swaps,
        r.objects_per_transaction(),
        r.visual_misses
    );
    println!(
        "  {:.1} objects drawn per frame (the current cell's PVS), {} pages read",
        r.mean_drawn, r.pages
    );
    if let (Some(drawn), Some(r)) = (drawn, render) {
        print_render(&drawn, r)?;
    }
    Ok(())
}

fn print_walk(r: &WalkReport) {
    let s = &r.summary;
    let c = &r.config;
    let cache = c
        .index_cache
        .as_ref()
        .map_or("none".to_string(), |(p, b)| format!("{p}, {} KiB", b >> 10));
    let k = c
        .prefetch_k
        .map_or("off".to_string(), |k| format!("k = {k}"));
    let pace = match (c.prefetch_k, c.pace) {
        (Some(_), Some(p)) => format!(", played {p}x real time"),
        (Some(_), None) => ", unpaced".to_string(),
        _ => String::new(),
    };
    println!("walk: {:?} retrieval, index cache {cache}, prefetch {k}{pace}, SF {}, frustum {} m, budget {} MiB", c.retrieval, c.sf, c.far, c.memory_budget >> 20);
    println!(
        "  frames {}   first (cold) load {:.1} ms   then mean {:.2} ms   max {:.2} ms   variance {:.3}   over 50 ms: {}",
        s.frames, s.initial_load_ms, s.mean_frame_ms, s.max_frame_ms, s.frame_ms_variance, s.frames_over_50ms
    );
    println!(
        "  queries {} ({} on the viewer's thread, {} prefetched, {} prefetches dropped)   cells entered {} ({} prefetched)",
        s.queries, s.sync_queries, s.prefetches_adopted, s.prefetches_stale, s.cell_changes, s.prefetches_used
    );
    println!(
        "  pages read: {} index + {} mesh, {:.1} per query ({:.1} index)",
        s.index_pages, s.mesh_pages, s.io_per_query, s.index_pages_per_query
    );
    println!(
        "  visual misses {}   peak buffer {:.1} MiB   frames over budget {}",
        s.visual_misses,
        s.peak_buffer_bytes as f64 / (1 << 20) as f64,
        s.overflow_frames
    );
    if let Some(cs) = &s.index_cache {
        println!(
            "  index cache: {} hits, {} misses, hit rate {:.1}%",
            cs.hits,
            cs.misses,
            cs.hit_rate() * 100.0
        );
    }
}

fn bench_index_cache(path: &Path, cfg: &IndexCacheConfig, out: &Path) -> Result<()> {
    let db = Database::open(path)?;
    let r = index_cache::run(&db, cfg)?;
    write_experiment(out, "index-cache", &r.to_csv(), &r.markdown(), |dir| {
        Ok(r.plot(dir)?)
    })
}

/// Writes an experiment's CSV, markdown summary and plots into `out`, and prints the summary.
fn write_experiment(
    out: &Path,
    name: &str,
    csv: &str,
    markdown: &str,
    plot: impl FnOnce(&Path) -> Result<()>,
) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    for (ext, text) in [("csv", csv), ("md", markdown)] {
        write_file(&out.join(format!("{name}.{ext}")), text)?;
    }
    plot(out)?;
    print!("{markdown}");
    println!("\nCSV, summary and plots in {}", out.display());
    Ok(())
}

type RefineArgs = (Option<glam::Vec3>, Option<glam::Vec3>, f32, f32);

fn lod(
    mesh: &Path,
    out: Option<&Path>,
    ratio: f32,
    min_triangles: usize,
    refine: Option<RefineArgs>,
) -> Result<()> {
    let m = flaneur_bench::lod_inspect::load_merged(mesh)?;
    match (refine, out) {
        (Some((Some(eye), Some(look), tau, fov)), _) => {
            let t = Instant::now();
            let r = flaneur_bench::lod_inspect::refine_view(&m, eye, look, fov.to_radians(), tau)?;
            println!(
                "{}: {} of {} triangles ({} vertices) for the view from {eye} towards {look}, tau {tau}; \
                 Hausdorff distance to the original {:.4} m; settled in {} frames, {:.2} s with the build",
                mesh.display(),
                r.triangles,
                r.original_triangles,
                r.vertices,
                r.hausdorff,
                r.frames,
                t.elapsed().as_secs_f64()
            );
            Ok(())
        }
        (Some(_), _) => Err(flaneur::Error::Invalid(
            "--refine needs --eye x,y,z and --look x,y,z".into(),
        )
        .into()),
        (None, Some(out)) => {
            let t = Instant::now();
            let levels = flaneur_bench::lod_inspect::write_levels(&m, out, ratio, min_triangles)?;
            for l in &levels {
                println!(
                    "{}: {} triangles, error {:.5} m",
                    l.path.display(),
                    l.triangles,
                    l.error
                );
            }
            println!(
                "{} levels in {:.2} s",
                levels.len(),
                t.elapsed().as_secs_f64()
            );
            Ok(())
        }
        (None, None) => Err(flaneur::Error::Invalid(
            "give --out DIR for the levels, or --refine with --eye and --look".into(),
        )
        .into()),
    }
}

fn parse_look(s: &str) -> std::result::Result<(f32, f32), String> {
    match s
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Vec<_>>()[..]
    {
        [Ok(yaw), Ok(pitch)] if yaw.is_finite() && pitch.is_finite() => Ok((yaw, pitch)),
        _ => Err(format!(
            "{s:?} is not two finite numbers yaw,pitch (degrees)"
        )),
    }
}

fn parse_size(s: &str) -> std::result::Result<(u32, u32), String> {
    match s
        .split_once(['x', 'X'])
        .map(|(w, h)| (w.trim().parse(), h.trim().parse()))
    {
        Some((Ok(w), Ok(h))) if w > 0 && h > 0 => Ok((w, h)),
        _ => Err(format!(
            "{s:?} is not a size WIDTHxHEIGHT in pixels, like 960x540"
        )),
    }
}

fn parse_vec3(s: &str) -> std::result::Result<glam::Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|e| format!("{s:?}: {e}"))?;
    match v[..] {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(glam::Vec3::new(x, y, z)),
        _ => Err(format!("{s:?} is not three finite numbers x,y,z")),
    }
}
