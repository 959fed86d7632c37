//! `flaneur view`: a walk through the city in a window, restarted from where the viewer
//! stands whenever a key changes its mode or budget.

use crate::cli::args::{eta, finite_f32, finite_f64, lod_tau, selection};
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use super::args::{parse_look, parse_size, parse_vec3};
use super::source::SourceArgs;
use flaneur::path::CameraPath;
use flaneur::Database;
use flaneur_render::{WalkMode, WalkWindow};

/// `flaneur view`'s arguments.
#[derive(clap::Args)]
pub struct ViewArgs {
    /// The database: a file, or a URL (http://… or https://…) on any HTTP server.
    db: PathBuf,
    /// review (CSearch, index cache, prefetching), box (plain range queries), pvs
    /// (the current viewcell's PVS, PBNP prefetching; a database built with
    /// --visibility), visual (the HDoV-tree under --eta; one built with --visibility
    /// --hdov), or the memory scene tree by vsc (under --eta), pb (under --budget) or
    /// conv (frustum culling only); 1 to 7 switch while walking.
    #[arg(long, default_value = "review")]
    mode: String,
    /// Window size, WIDTHxHEIGHT pixels. The walk's view fills it: 45° high, and as
    /// wide as the window's shape makes it, the walk selecting and culling for that
    /// view; the view from above (T) is the window's largest centred square.
    /// Default: 1024x768, shrunk (its shape kept) to fit a smaller screen.
    #[arg(long, value_parser = parse_size)]
    size: Option<(u32, u32)>,
    /// LOD selection's screen-space error, a fraction of the viewport (0: full
    /// detail), within [0, 1); [ and ] halve and double it while walking.
    #[arg(long, default_value_t = flaneur::walk::lod_select::DEFAULT_TAU, value_parser = lod_tau, allow_negative_numbers = true)]
    lod_tau: f32,
    /// Start here (x,y,z metres); by default on the busiest street.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    at: Option<glam::Vec3>,
    /// Heading and elevation at the start, degrees (with --at).
    #[arg(long, value_parser = parse_look, default_value = "0,0", allow_hyphen_values = true)]
    look: (f32, f32),
    /// Save the poses walked to this path CSV file when the window closes (default:
    /// none).
    #[arg(long, value_name = "FILE")]
    record: Option<PathBuf>,
    /// Play a path CSV file (from --record, --save-path or by hand) instead of
    /// steering (default: none, steered).
    #[arg(long, value_name = "FILE")]
    play: Option<PathBuf>,
    /// GPU memory the meshes may take, MiB (0: as much as the walk's buffer holds);
    /// meshes not drawn are freed to make room, largest first.
    #[arg(long, default_value_t = 256.0, value_parser = finite_f64, allow_negative_numbers = true)]
    gpu_budget_mb: f64,
    /// Walking speed, m/s (Shift runs at four times it).
    #[arg(long, default_value_t = flaneur::walk::WALK_SPEED, value_parser = finite_f32, allow_negative_numbers = true)]
    speed: f32,
    /// Start with the bounding boxes drawn (B toggles them while walking).
    #[arg(long)]
    boxes: bool,
    /// Start with the city seen from above (T toggles it while walking).
    #[arg(long)]
    top_view: bool,
    /// The VISUAL and VSC modes' DoV threshold η, within [0, 1].
    #[arg(long, default_value_t = flaneur::walk::visual::DEFAULT_ETA, value_parser = eta, allow_negative_numbers = true)]
    eta: f32,
    /// The PB mode's polygon budget, triangles a frame.
    #[arg(long, default_value_t = flaneur::walk::DEFAULT_BUDGET)]
    budget: u64,
    /// The rule that picks the VISUAL, VSC and PB modes' internal LODs and levels.
    /// `screen` (ours, the default): a node's internal LOD only where its DoV ≤ η and
    /// eq. 5.4 allow it and its stored error projects under --lod-tau, each object at the
    /// finer of eq. 5.6's level and --lod-tau's. `thesis`: Shou 2002's rules.
    #[arg(long, default_value = "screen", value_parser = selection)]
    selection: flaneur::hdov::Selection,
    /// Draw the city's landmarks from a stream server (`flaneur serve-stream` of the same
    /// database) at this address (host:port), its round trip, prediction span and
    /// bytes/s on the HUD; the rest as ever. Default: none, every object read from
    /// the database.
    #[arg(long, value_name = "HOST:PORT")]
    stream: Option<String>,
    /// Refine the landmarks for the next frame on the thread pool while a frame draws
    /// (El-Sana–Varshney's Adapt and Display), not on the frame's thread.
    #[arg(long)]
    adapt_ahead: bool,
    #[command(flatten)]
    source: SourceArgs,
}

impl ViewArgs {
    /// Opens the window on the start and walks until it closes.
    pub fn run(self) -> Result<()> {
        let ViewArgs {
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
            eta,
            budget,
            selection,
            stream,
            adapt_ahead,
            source,
        } = self;
        let mode = match mode.as_str() {
            "review" => WalkMode::Review,
            "box" => WalkMode::Box,
            "pvs" => WalkMode::Pvs,
            "visual" => WalkMode::Visual,
            "vsc" => WalkMode::Vsc,
            "pb" => WalkMode::Pb,
            "conv" => WalkMode::Conv,
            other => {
                bail!("the window shows the review, box, pvs, visual, vsc, pb and conv modes, not '{other}'")
            }
        };
        let db = source.open(&db)?;
        let start = match at {
            Some(p) => flaneur::path::Pose {
                time: 0.0,
                position: p,
                yaw: look.0.to_radians(),
                pitch: look.1.to_radians(),
            },
            None => flaneur::walk::busiest_street(&db)?,
        };
        let play = play
            .map(|p| CameraPath::load_csv(&p).with_context(|| format!("reading {}", p.display())))
            .transpose()?;
        let defaults = window_options(&db, start);
        let opts = flaneur_render::ViewOptions {
            // A size asked for is kept whatever the screen; the default one fits it.
            size: size.unwrap_or(defaults.size),
            fit_screen: size.is_none(),
            lod_tau: (lod_tau != 0.0).then_some(lod_tau),
            play,
            gpu_budget: (gpu_budget_mb > 0.0).then_some((gpu_budget_mb * 1048576.0) as u64),
            speed,
            eta,
            polygon_budget: budget,
            selection,
            adapt_ahead,
            ..defaults
        };
        let remote = match &stream {
            Some(_) if lod_tau == 0.0 => {
                bail!("--stream draws landmarks refined view by view: give a --lod-tau above 0")
            }
            Some(addr) => {
                let (landmarks, _) = super::stream_client::stream_landmarks(addr, lod_tau)?;
                println!("drawing the landmarks streamed from {addr}");
                Some(Box::new(landmarks) as Box<dyn flaneur::walk::RemoteRefinements>)
            }
            None => None,
        };
        view(
            &db,
            opts,
            mode,
            (boxes, top_view),
            record.as_deref(),
            remote,
        )
    }
}

/// How the window opens on `db` from `start` by default: titled with the database's
/// path.
pub fn window_options(db: &Database, start: flaneur::path::Pose) -> flaneur_render::ViewOptions {
    flaneur_render::ViewOptions {
        title: format!("flaneur — {}", db.store().path().display()),
        ..flaneur_render::ViewOptions::new(db.bounds(), start)
    }
}

/// A session at the window (the walk engine's `walk::live` session): walks run one
/// after another from where the viewer stands, until the window closes; what it drew
/// said after, and the poses walked saved to `record`. Objects `remote` refines are
/// drawn from there.
pub fn view(
    db: &Database,
    opts: flaneur_render::ViewOptions,
    mode: WalkMode,
    (boxes, top_view): (bool, bool),
    record: Option<&Path>,
    remote: Option<Box<dyn flaneur::walk::RemoteRefinements>>,
) -> Result<()> {
    let start = opts.start;
    let mut window = WalkWindow::open(opts, mode)?.telling(|m| eprintln!("{m}"));
    if let Some(r) = remote {
        window = window.with_remote(r);
    }
    window.boxes = boxes;
    window.top_view = top_view;
    if let Some(a) = window.adapter() {
        println!("drawing on {} ({:?})", a.name, a.backend);
    }
    let p = start.position;
    println!(
        "starting at {:.0}, {:.1}, {:.0} in {} mode; W A S D and the mouse (click to capture it), \
         Shift runs, F flies, 1-7 review/box/pvs/visual/vsc/pb/conv, [ ] LOD τ, - = budget, H HUD, Q quits",
        p.x,
        p.y,
        p.z,
        mode.name()
    );
    flaneur::walk::live::run(db, mode, &mut window)?;
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
