//! `flaneur demo`: a default city generated, built with its visibility and HDoV-tree,
//! walked by REVIEW and BOX and then by the four modes side by side (`demo_modes`), and
//! shown in a window or, with no display, flown over headless.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use super::bars::Bars;
use super::build::print_lod_report;
use super::view::{view, window_options};
use super::walk::print_walk;
use flaneur::path::motion::{self, Motion};
use flaneur::path::CameraPath;
use flaneur::walk::review::{self, Preset, ReviewConfig};
use flaneur::walk::{self, settings, Frames, Playback, WalkConfig};
use flaneur::{BuildOptions, Database};
use flaneur_render::WalkMode;

/// `flaneur demo`'s arguments.
#[derive(clap::Args)]
pub struct DemoArgs {
    /// Objects in the generated city.
    #[arg(long, default_value_t = DEMO_OBJECTS)]
    objects: u64,
    /// Where the city and its database are kept between runs.
    #[arg(long, env = "FLANEUR_CACHE", default_value = "cache")]
    cache: PathBuf,
    /// Frames of each walk (30 per second); the headless flight, where there is no display,
    /// draws as many, at most 120.
    #[arg(long, default_value_t = 1800)]
    frames: usize,
}

impl DemoArgs {
    /// Runs the demo in the cache folder.
    pub fn run(self) -> Result<()> {
        demo(self.objects, &self.cache, self.frames)
    }
}

/// The demo city's objects: a city whose visibility and HDoV-tree build in a minute or
/// two on two cores.
const DEMO_OBJECTS: u64 = 3_000;

/// The demo's build: LODs, the visibility at its defaults, and the HDoV-tree under the
/// indexed-vertical scheme (the smallest; VISUAL reads it).
fn demo_build_options() -> BuildOptions {
    BuildOptions {
        visibility: Some(flaneur::visibility::VisibilityOptions::default()),
        hdov: Some(flaneur::hdov::HdovOptions {
            schemes: vec![flaneur::hdov::Scheme::Indexed],
            ..Default::default()
        }),
        ..BuildOptions::default()
    }
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
    let db = match cached_demo(&db_path) {
        Some(db) => {
            println!("using {} (delete it to rebuild)", db_path.display());
            db
        }
        None => build_demo(&city, &scene, &db_path)?,
    };
    review_and_box(&db, frames)?;
    let gpu = flaneur_render::Gpu::headless();
    super::demo_modes::walk_modes(&db, frames, gpu.as_ref().ok())?;
    let display = ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()));
    if display {
        println!(
            "opening a window on the city's busiest street (close it or press Q to end the demo)"
        );
        let start = flaneur::walk::busiest_street(&db)?;
        let opts = window_options(&db, start);
        match view(&db, opts, WalkMode::Review, (false, false), None, None) {
            Ok(()) => {
                print_next_steps(&db_path);
                return Ok(());
            }
            Err(e) => println!("no window ({e:#}); drawing a flight headless instead"),
        }
    }
    demo_flight(
        gpu,
        &db,
        &cache.join("demo-frames"),
        frames.min(FLIGHT_FRAMES),
    )?;
    print_next_steps(&db_path);
    Ok(())
}

/// The demo's database cached by an earlier run, when this version of flaneur reads it
/// whole (its LOD table, its HDoV-tree): else it is built again rather than failing
/// halfway through the demo.
fn cached_demo(db_path: &Path) -> Option<Database> {
    if !db_path.exists() {
        return None;
    }
    match Database::open(db_path).and_then(|db| db.lod_stats().map(|_| db)) {
        Ok(db) if db.hdov().is_ok_and(|h| h.is_some()) => Some(db),
        Ok(_) => {
            println!(
                "{} has no HDoV-tree (an older demo's): building it again",
                db_path.display()
            );
            None
        }
        Err(e) => {
            println!(
                "{} cannot be read by this version of flaneur ({e}): building it again",
                db_path.display()
            );
            None
        }
    }
}

/// Generates the demo's city into `scene` (unless there) and builds `db_path` from it.
fn build_demo(city: &citygen::CityConfig, scene: &Path, db_path: &Path) -> Result<Database> {
    if !scene.exists() {
        println!(
            "generating a city of {} objects into {}",
            city.objects,
            scene.display()
        );
        let bar = super::bars::city_bar(city.objects);
        let s = citygen::write_city_with_progress(city, scene, |n| bar.set_position(n))?;
        bar.finish_and_clear();
        println!(
            "  {} objects, {} triangles, {:.1} MiB",
            s.objects,
            s.triangles,
            s.bytes as f64 / (1 << 20) as f64
        );
    }
    println!("building {}", db_path.display());
    let b = flaneur::build_from_scene_with_progress(
        scene,
        db_path,
        &demo_build_options(),
        &Bars::default(),
    )?;
    println!(
        "  {} pages, tree height {}, {:.1} s",
        b.pages, b.height, b.seconds
    );
    print_lod_report(b.lod.as_ref(), b.bytes);
    if let Some(v) = &b.visibility {
        println!(
            "  visibility: {} walkable viewcells of {} m, {:.0} objects in a cell's PVS on \
             average, {:.1} s ({:.1} ms a cell)",
            v.cells,
            flaneur::visibility::VisibilityOptions::default().cell_size,
            v.entries as f64 / v.cells.max(1) as f64,
            v.seconds,
            1000.0 * v.seconds / v.cells.max(1) as f64
        );
    }
    println!(
        "  (LODs: each object's coarser levels of detail, read instead of its full mesh when it is far; \
         PM + DAG: the largest objects' progressive meshes and their dependency graphs, \
         refined view by view as the viewer comes near: Zheng 2007)"
    );
    Ok(Database::open(db_path)?)
}

/// REVIEW, then BOX, along `frames` of the normal motion pattern: each query or
/// prefetch they made, and their summaries.
fn review_and_box(db: &Database, frames: usize) -> Result<()> {
    let path = motion::generate(&db.bounds(), Motion::Normal, frames, 30.0, 1)?;
    println!(
        "walking {frames} frames ({:.0} s of path, played {}x faster) of the 'normal' pattern in REVIEW mode, then with plain BOX queries",
        frames as f64 / 30.0,
        settings::DEFAULT_PACE
    );
    print_legend();
    for preset in [Preset::Optimal, Preset::Box] {
        let bar = indicatif::ProgressBar::new(frames as u64);
        let cfg = WalkConfig::Review(ReviewConfig::preset(preset));
        let mut tick = |_| bar.inc(1);
        let mut viewer = Playback::path(&path).with_progress(&mut tick);
        let report: review::WalkReport =
            walk::run(db, &cfg, &mut viewer, Frames::Keep)?.try_into()?;
        bar.finish_and_clear();
        println!(
            "{}",
            match preset {
                Preset::Optimal =>
                    "REVIEW (the thesis's 'optimal' configuration, `--config optimal`):",
                _ => "BOX (`--config box`):",
            }
        );
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
        print_walk(&report, db.store().page_size());
    }
    Ok(())
}

/// The flight's frames where there is no display: four seconds at 30 a second, or the
/// walk's own length where that is shorter.
const FLIGHT_FRAMES: usize = 120;

/// The words the walks' lines use, said once before them.
fn print_legend() {
    for line in [
        "REVIEW (Shou 2002) asks the paged R-tree only for what each new disk cell adds to",
        "those it already holds (CSearch), keeps R-tree pages in a 1 MB index cache",
        "(distance-priority LRU) and prefetches the cell the viewer will reach k seconds",
        "ahead. BOX asks for the whole cell again at every change, with neither.",
        "SF: the scale factor, how many times larger than the view's own box (the frustum",
        "cell, as deep as the frustum's metres) the disk cell that is queried is.",
        "Pages read are counted exactly. Visual misses: objects in view whose mesh had not",
        "arrived when a frame was drawn, counted once a frame.",
    ] {
        println!("  {line}");
    }
}

/// Where the demo's database is, and what to do with it next.
fn print_next_steps(db_path: &Path) {
    let db = db_path.display();
    let name = db_path
        .file_name()
        .map_or_else(|| db.to_string(), |n| n.to_string_lossy().into_owned());
    println!("\nthe city's database is {db}; the next demo reuses it (delete it to build again).");
    println!("What to try next (`flaneur` is target/release/flaneur; `cargo run --release --` does the same):");
    let steps = [
        (
            format!("flaneur view {db}"),
            "walk it yourself: WASD and the mouse, 1-7 the modes, H the HUD",
        ),
        (
            format!("flaneur info {db}"),
            "what it holds: objects, pages by kind, levels of detail",
        ),
        (
            format!("flaneur walk {db} --config box"),
            "the walk again, headless, with other settings (--help)",
        ),
        (
            format!("flaneur serve {db} --port 8080"),
            "publish it over HTTP; then, from anywhere:",
        ),
        (
            format!("flaneur walk http://127.0.0.1:8080/{name} --never-wait"),
            "",
        ),
    ];
    let width = steps.iter().map(|(c, _)| c.len()).max().unwrap_or(0);
    for (command, what) in steps {
        println!("{}", format!("  {command:width$}   {what}").trim_end());
    }
    println!("The README's \"The commands\" lists the rest.");
}

/// The demo's last part where there is no display: a short flight over the city drawn
/// headless to PNG frames. Without a GPU adapter, it says so and the demo ends well.
fn demo_flight(
    gpu: flaneur::Result<flaneur_render::Gpu>,
    db: &Database,
    dir: &Path,
    frames: usize,
) -> Result<()> {
    let gpu = match gpu {
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
    let frames = frames.max(2);
    let poses = (0..frames)
        .map(|i| {
            let t = i as f32 / (frames - 1) as f32;
            flaneur::path::Pose {
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
        .with_lod_tau(flaneur::walk::lod_select::DEFAULT_TAU)?;
    let bar = indicatif::ProgressBar::new(frames as u64);
    let mut tick = |_| bar.inc(1);
    walk::run(
        db,
        &WalkConfig::Review(cfg),
        &mut Playback::path(&path)
            .drawn_by(&mut writer)
            .with_progress(&mut tick),
        Frames::Each(&mut |_| Ok(())),
    )?;
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
