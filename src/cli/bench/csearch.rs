//! `flaneur bench csearch` (Shou 2002 §4.4): BOX against CSearch query by query, then
//! the REVIEW walks of Figs. 4.19–4.22, all into one summary.

use crate::cli::args::finite_f32;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use super::report::{report_file, write_report_files};
use super::walk_setup::WalkSetupArgs;
use crate::cli::bars::with_bar;
use crate::cli::write_file;
use flaneur::{Backend, Database};
use flaneur_bench::cell_size::{self, CellSizeConfig};
use flaneur_bench::csearch::{self, CsearchConfig, CsearchReport, CsearchReports};
use flaneur_bench::db_size::{self, DbSizeConfig};
use flaneur_bench::frame_time::{self, FrameTimeConfig};
use flaneur_bench::report::Report;
use flaneur_bench::walk_setup::WalkSetup;

/// `flaneur bench csearch`'s arguments.
#[derive(clap::Args)]
pub struct CsearchArgs {
    /// The database file (the insertion-built copy is made beside it in --out).
    db: PathBuf,
    /// Side of the query-by-query run's disk cells on the ground, metres.
    #[arg(long, value_name = "METRES", default_value_t = CsearchConfig::default().cell, value_parser = finite_f32, allow_negative_numbers = true)]
    cell: f32,
    /// Metres walked between two queries of that run.
    #[arg(long, value_name = "METRES", default_value_t = CsearchConfig::default().step, value_parser = finite_f32, allow_negative_numbers = true)]
    step: f32,
    /// Queries of that run.
    #[arg(long, default_value_t = CsearchConfig::default().steps)]
    steps: usize,
    /// Earlier disk cells CSearch keeps as its history.
    #[arg(long, default_value_t = CsearchConfig::default().history_len)]
    history_len: usize,
    /// The REVIEW walks; --seed also seeds the street walk of the query-by-query run.
    #[command(flatten)]
    walk: WalkSetupArgs,
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
    /// How the database file is read: mmap, pread, or direct (O_DIRECT, past the page
    /// cache).
    #[arg(long, default_value = "mmap")]
    backend: Backend,
    /// Folder for the CSVs, plots and summary.
    #[arg(long, default_value = "bench-out")]
    out: PathBuf,
    /// Print every query, not just the summary.
    #[arg(long)]
    verbose: bool,
}

impl CsearchArgs {
    /// Runs the query-by-query walk and, unless `--no-walks`, the REVIEW figures.
    pub fn run(self) -> Result<()> {
        let CsearchArgs {
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
        } = self;
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
    let mut runs = CsearchReports {
        config: cfg.clone(),
        reports: vec![csearch::run(&db, cfg)?],
    };
    if insertion {
        runs.reports.push(csearch::run_insertion_tree(
            &db,
            cfg,
            &out.join("insertion-tree.flaneur"),
        )?);
    }
    let mut md = runs.markdown();
    write_report_files(out, &runs, Some(&md))?;
    let (csv_path, md_path) = (
        report_file(out, &runs, "csv"),
        report_file(out, &runs, "md"),
    );
    println!(
        "csearch: {} queries, cell {} m, step {} m, history ≤ {}",
        cfg.steps, cfg.cell, cfg.step, cfg.history_len
    );
    for r in &runs.reports {
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
    write_report_files(out, &r, None)?;
    section(r.markdown())?;

    let r = with_bar("time per frame (Fig. 4.21)", |p| {
        frame_time::run_with_progress(db, &f.frames, p)
    })?;
    write_report_files(out, &r, None)?;
    section(r.markdown())?;

    let r = with_bar("database size (Fig. 4.22)", |p| {
        db_size::run_with_progress(&out.join("cities"), &f.sizes, p)
    })?;
    write_report_files(out, &r, None)?;
    section(r.markdown())
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
