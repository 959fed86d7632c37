//! The `flaneur` command line: parses the arguments and hands each command to its file
//! under `cli/`, which calls the library and prints; nothing else lives here.

use clap::{Parser, Subcommand};

mod cli;
use cli::{
    bench, build, check, demo, info, insert, lod, merge, query, serve, serve_stream, shot, view,
    walk,
};

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
    Demo(demo::DemoArgs),
    /// Build a database from a citygen scene file, or OBJ, glTF and OpenStreetMap files
    /// (with --shard K/N, only one shard of its visibility, for merge).
    Build(build::BuildArgs),
    /// Build a database as build does, its visibility joined from shard files that
    /// build --visibility --shard K/N computed, each on any machine.
    Merge(merge::MergeArgs),
    /// The LOD core on a mesh file: its levels written as OBJ (--out), or one view's
    /// selective mesh measured (--refine --eye --look --tau).
    Lod(lod::LodArgs),
    /// Render one picture of the city headless (no window): the objects in view at full
    /// detail, on the GPU or a software adapter.
    Shot(shot::ShotArgs),
    /// Walk a city in a window: W A S D and the mouse (click to capture it), Shift to
    /// run, F to fly; the walk engine selects, the window draws its selection at the
    /// chosen LODs, with a heads-up display. Opens on the city's busiest street.
    View(view::ViewArgs),
    /// Verify every page's checksum and every structure of a database (the R-tree, the
    /// meshes, the LODs, the visibility, the HDoV-tree); each problem named with its
    /// page. Exit status 1 when one is found.
    Check(check::CheckArgs),
    /// Objects, triangles, pages by kind, tree height and fill.
    Info(info::InfoArgs),
    /// Add the objects of OBJ files to a built database, each insert crash-atomic.
    Insert(insert::InsertArgs),
    /// Range query (BOX), or CSearch when history cells are given.
    Query(query::QueryArgs),
    /// Walk a database headless along a camera path (REVIEW, Shou 2002 ch. 4) and
    /// report per-frame figures.
    Walk(walk::WalkArgs),
    /// Rerun an experiment of the papers, or one of ours. Most run on a database given
    /// to them (each says how it must be built); nine make their own data and need none:
    /// hdov-scaling, lod-dag, lod-parallel, lod-refine, pvs-prefetch, stream,
    /// stream-crowd, stream-bytes and stream-blocks.
    Bench(bench::BenchArgs),
    /// Serve database files over HTTP with byte ranges, ETag and If-Match, for every
    /// command to open by URL (any static server that honours Range does as well).
    Serve(serve::ServeArgs),
    /// Stream a database's landmarks (its objects with progressive meshes) to clients
    /// over TCP: each client sends its views and gets batches of edge collapses and
    /// vertex splits for them (Zheng 2007 ch. 5-6, §8.2).
    ServeStream(serve_stream::ServeStreamArgs),
}

fn main() {
    quiet_wayland_probe();
    let cli = Cli::parse();
    // A closed pipe (`flaneur query … | head -1`) ends the program quietly, as it ends
    // coreutils: Rust's runtime ignores SIGPIPE, which turns the next write into a
    // panic; its default action is to end the process. The servers keep it ignored: a
    // client that goes away must not end them.
    #[cfg(unix)]
    if !matches!(cli.command, Command::Serve(_) | Command::ServeStream(_)) {
        // SAFETY: restoring a signal's default action, before any thread starts.
        unsafe {
            libc::signal(libc::SIGPIPE, libc::SIG_DFL);
        }
    }
    if let Err(e) = run(cli) {
        eprintln!("error: {}", message(&e));
        std::process::exit(1);
    }
}

/// Mesa's device-select Vulkan layer asks Wayland for the default GPU whenever the
/// Vulkan instance offers Wayland surfaces, and libwayland prints "error:
/// XDG_RUNTIME_DIR is invalid or not set in the environment" when there is no session
/// to ask: on every plain X display and headless machine, where it reads as our
/// failure. Where no Wayland session can exist the layer is turned off
/// (`NODEVICE_SELECT`); wgpu chooses the adapter by its power preference either way.
fn quiet_wayland_probe() {
    let runtime_dir =
        std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_dir());
    let wayland = std::env::var_os("WAYLAND_DISPLAY").is_some();
    if !runtime_dir && !wayland && std::env::var_os("NODEVICE_SELECT").is_none() {
        // Before any thread starts.
        std::env::set_var("NODEVICE_SELECT", "1");
    }
}

/// The error and its causes, joined by ": " as anyhow's `{:#}` joins them, less each
/// cause the message already ends with: the engine's errors name their file and say
/// what the system said, which is also their source.
fn message(e: &anyhow::Error) -> String {
    let mut out = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !out.ends_with(&cause) {
            out.push_str(": ");
            out.push_str(&cause);
        }
    }
    out
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Demo(a) => a.run(),
        Command::Build(a) => a.run(),
        Command::Merge(a) => a.run(),
        Command::Lod(a) => a.run(),
        Command::Shot(a) => a.run(),
        Command::View(a) => a.run(),
        Command::Check(a) => a.run(),
        Command::Info(a) => a.run(),
        Command::Insert(a) => a.run(),
        Command::Query(a) => a.run(),
        Command::Walk(a) => a.run(),
        Command::Bench(a) => a.run(),
        Command::Serve(a) => a.run(),
        Command::ServeStream(a) => a.run(),
    }
}
