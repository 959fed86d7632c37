//! The `csearch` experiment (Shou 2002 §4.4, Table 4.1): along a walk of consecutive,
//! overlapping disk cells, the pages BOX reads against the pages CSearch reads for
//! the same cells, query by query.
//!
//! Page counts are exact and deterministic; times are wall-clock and noisy. The thesis
//! built its trees by insertion with the linear split, ours are packed by default, so
//! the experiment can also run on an insertion-built copy of the index (same objects,
//! a temporary file) to reproduce the thesis's setting.

use std::path::Path;
use std::time::Instant;

use crate::report::Report;
use flaneur::database::Database;
use flaneur::error::Error;
use flaneur::error::Result;
use flaneur::geom::Aabb;
use flaneur::rtree::{Coverlap, History, RTree, DEFAULT_HISTORY_LEN};
use flaneur::store::Store;
use flaneur::{path::street_walk, walk::disk_cell};

/// The walk and the cells of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CsearchConfig {
    /// Side of a disk cell on the ground, metres (the thesis's frustum is 1 km deep).
    pub cell: f32,
    /// Metres walked between two queries.
    pub step: f32,
    pub steps: usize,
    /// Mean steps between turns.
    pub segment: usize,
    pub seed: u64,
    pub history_len: usize,
}

impl Default for CsearchConfig {
    fn default() -> CsearchConfig {
        CsearchConfig {
            cell: 1000.0,
            step: 25.0,
            steps: 200,
            segment: 24,
            seed: 1,
            history_len: DEFAULT_HISTORY_LEN,
        }
    }
}

/// One query of the walk.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CsearchRow {
    pub step: usize,
    pub x: f32,
    pub z: f32,
    pub box_objects: usize,
    pub box_pages: usize,
    pub box_us: f64,
    pub csearch_objects: usize,
    /// Pages read by CSearch with the default (clipped) COverlap.
    pub csearch_pages: usize,
    pub csearch_us: f64,
    /// Pages read by CSearch with the thesis's COverlap (Fig. 4.5 as written).
    pub thesis_pages: usize,
    pub thesis_us: f64,
    pub history: usize,
}

/// A whole walk on one tree.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CsearchReport {
    pub tree: String,
    pub rows: Vec<CsearchRow>,
    pub box_pages: u64,
    pub csearch_pages: u64,
    pub thesis_pages: u64,
    /// CSearch (clipped) pages over BOX pages, over the whole walk.
    pub ratio: f64,
    /// CSearch (thesis COverlap) pages over BOX pages.
    pub thesis_ratio: f64,
    pub box_ms: f64,
    pub csearch_ms: f64,
    pub thesis_ms: f64,
}

/// Runs the walk on the database's own index.
pub fn run(db: &Database, cfg: &CsearchConfig) -> Result<CsearchReport> {
    walk(
        db.store(),
        db.tree(),
        &db.bounds(),
        cfg,
        "packed (as built)",
    )
}

/// Runs the walk on a copy of the index built by one-by-one insertion with the linear
/// split, in a temporary file next to `scratch`.
pub fn run_insertion_tree(
    db: &Database,
    cfg: &CsearchConfig,
    scratch: &Path,
) -> Result<CsearchReport> {
    let all = db.range(&db.bounds())?.objects;
    let mut store = Store::create(scratch, db.store().page_size())?;
    let mut tree = RTree::bulk_load(&mut store, Vec::new(), 1.0)?;
    let mut ordered = all;
    ordered.sort_by_key(|o| o.id);
    for o in ordered {
        tree.insert(&mut store, o)?;
    }
    store.reset_stats();
    walk(&store, &tree, &db.bounds(), cfg, "insertion, linear split")
}

fn walk(
    store: &Store,
    tree: &RTree,
    bounds: &Aabb,
    cfg: &CsearchConfig,
    name: &str,
) -> Result<CsearchReport> {
    let path = street_walk(bounds, cfg.steps, cfg.step, cfg.segment, cfg.seed)?;
    let mut history = History::new(cfg.history_len);
    let mut rows = Vec::with_capacity(path.len());
    for (step, eye) in path.positions().enumerate() {
        let cell = disk_cell(eye, cfg.cell, bounds)?;
        let t = Instant::now();
        let plain = tree.range(store, &cell)?;
        let box_us = t.elapsed().as_secs_f64() * 1e6;
        // Both rules give the same result, so one history serves both.
        history.filter(&cell);
        let cells = history.cells();
        let t = Instant::now();
        let thesis = tree.csearch_with(store, &cell, &cells, Coverlap::Thesis)?;
        let thesis_us = t.elapsed().as_secs_f64() * 1e6;
        let t = Instant::now();
        let complement = tree.csearch_with(store, &cell, &cells, Coverlap::Clipped)?;
        let csearch_us = t.elapsed().as_secs_f64() * 1e6;
        if thesis.objects.len() != complement.objects.len() {
            return Err(Error::Invalid(format!(
                "step {step}: the two COverlap rules disagree"
            )));
        }
        history.record(cell, &complement.objects);
        rows.push(CsearchRow {
            step,
            x: eye.x,
            z: eye.z,
            box_objects: plain.objects.len(),
            box_pages: plain.pages.len(),
            box_us,
            csearch_objects: complement.objects.len(),
            csearch_pages: complement.pages.len(),
            csearch_us,
            thesis_pages: thesis.pages.len(),
            thesis_us,
            history: history.len(),
        });
    }
    let box_pages: u64 = rows.iter().map(|r| r.box_pages as u64).sum();
    let csearch_pages: u64 = rows.iter().map(|r| r.csearch_pages as u64).sum();
    let thesis_pages: u64 = rows.iter().map(|r| r.thesis_pages as u64).sum();
    let share = |pages: u64| {
        if box_pages == 0 {
            0.0
        } else {
            pages as f64 / box_pages as f64
        }
    };
    let ms = |f: fn(&CsearchRow) -> f64| rows.iter().map(f).sum::<f64>() / 1e3;
    Ok(CsearchReport {
        tree: name.into(),
        ratio: share(csearch_pages),
        thesis_ratio: share(thesis_pages),
        box_ms: ms(|r| r.box_us),
        csearch_ms: ms(|r| r.csearch_us),
        thesis_ms: ms(|r| r.thesis_us),
        box_pages,
        csearch_pages,
        thesis_pages,
        rows,
    })
}

impl CsearchReport {
    /// The rows as CSV, one query a line.
    pub fn to_csv(&self) -> String {
        let mut s = String::from(
            "tree,step,x,z,box_objects,box_pages,box_us,csearch_objects,csearch_pages,csearch_us,thesis_pages,thesis_us,history\n",
        );
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{:.1},{:.1},{},{},{:.1},{},{},{:.1},{},{:.1},{}\n",
                self.tree,
                r.step,
                r.x,
                r.z,
                r.box_objects,
                r.box_pages,
                r.box_us,
                r.csearch_objects,
                r.csearch_pages,
                r.csearch_us,
                r.thesis_pages,
                r.thesis_us,
                r.history
            ));
        }
        s
    }
}

/// Pages read per query along the walk, BOX against CSearch (both COverlap rules), one
/// plot per tree.
fn plot_pages(report: &CsearchReport, path: &Path) -> Result<()> {
    use super::plot::{line_plot, LinePlot, Series};
    let series = |name: &str, f: fn(&CsearchRow) -> usize| Series {
        name: name.into(),
        points: report
            .rows
            .iter()
            .map(|r| (r.step as f64, f(r) as f64))
            .collect(),
    };
    line_plot(
        path,
        &LinePlot {
            title: format!("Index pages per query, {} tree", report.tree),
            x_label: "query along the walk".into(),
            y_label: "pages read".into(),
            series: vec![
                series("BOX", |r| r.box_pages),
                series("CSearch, thesis COverlap", |r| r.thesis_pages),
                series("CSearch", |r| r.csearch_pages),
            ],
        },
    )
}

/// The walk on each tree benched, reported together: one CSV, one plot per tree, one
/// summary.
#[derive(Clone, Debug)]
pub struct CsearchReports {
    /// The walk and the cells every tree was walked with.
    pub config: CsearchConfig,
    /// The database's own tree first, then the insertion-built copy when it ran.
    pub reports: Vec<CsearchReport>,
}

/// The pages plot of each tree of [`CsearchReports`], in the order of its reports.
pub const PAGES_PLOT_FILES: [&str; 2] = ["csearch-pages.png", "csearch-pages-insertion.png"];

impl Report for CsearchReports {
    fn name(&self) -> &'static str {
        "csearch"
    }

    /// Every tree's rows under one header.
    fn to_csv(&self) -> String {
        self.reports
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
            .collect()
    }

    /// A short summary that sets the figures beside the thesis's.
    fn markdown(&self) -> String {
        let (reports, cfg) = (&self.reports, &self.config);
        let mut s = String::from("# csearch — pages read by BOX and CSearch along a walk\n\n");
        s.push_str(&format!(
            "{} queries, a disk cell of {} m every {} m along a generated street walk (seed {}), history of at most {} cells.\n\n",
            cfg.steps, cfg.cell, cfg.step, cfg.seed, cfg.history_len
        ));
        s.push_str("| tree | BOX pages | CSearch pages | share | CSearch (thesis COverlap) | share |\n|---|---|---|---|---|---|\n");
        for r in reports {
            s.push_str(&format!(
                "| {} | {} | {} | {:.1}% | {} | {:.1}% |\n",
                r.tree,
                r.box_pages,
                r.csearch_pages,
                r.ratio * 100.0,
                r.thesis_pages,
                r.thesis_ratio * 100.0
            ));
        }
        s.push_str(
            "\nThe thesis (Shou 2002, Table 4.1) reports 9–21 % of BOX's disk I/Os per query for its Optimal \
             configuration: CSearch with a 1 MB index cache and prefetching. The figures above are CSearch alone, \
             with no index cache: every query reads the root again.\n",
        );
        s
    }

    /// [`PAGES_PLOT_FILES`] in `dir`, one per tree.
    fn plot(&self, dir: &Path) -> Result<()> {
        for (r, name) in self.reports.iter().zip(PAGES_PLOT_FILES) {
            plot_pages(r, &dir.join(name))?;
        }
        Ok(())
    }
}
