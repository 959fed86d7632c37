//! Frame time against cell size (Shou 2002 §4.4.2, Fig. 4.19 and 4.20): the mean frame
//! time and its variance against the scale factor SF (the thesis's "cell size": the
//! disk cell is SF times the frustum cell), for the four configurations of §4.4 —
//! Optimal (CSearch + index cache + prefetching), NC (no index cache), NP (no
//! prefetching) and BOX (plain range queries) — all walking the same generated path.
//!
//! Each configuration is `walk::review`'s preset with this experiment's frustum and
//! budget and the swept SF; the frame-time figures are the walk's own summary (count
//! once, report everywhere). Times are wall-clock and noisy, so the report also gives
//! what does not depend on this machine's mood: index pages and disk I/Os (index + mesh
//! pages) per query, and the longest frame, the "pause" the thesis says a BOX query
//! causes.

use std::path::Path;

use crate::report::Report;
use crate::view_culling::THESIS_SFS;
use crate::walk_setup::{
    check_sf, check_sweep, describe_review, label, mean_query_ms, num, per_query, walk_path,
    WalkSetup,
};
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::path::motion::Motion;
use flaneur::walk::review::{Preset, ReviewConfig, WalkReport};
use flaneur::walk::NoSink;

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CellSizeConfig {
    /// The walk: one path, of the one pattern in `walk.patterns` (normal by default);
    /// `walk.sf` is not used, `sfs` replaces it.
    pub walk: WalkSetup,
    /// The scale factors tried, in order (default: the cell sizes of the thesis's Table 4.2).
    pub sfs: Vec<f32>,
}

impl Default for CellSizeConfig {
    fn default() -> CellSizeConfig {
        CellSizeConfig {
            walk: WalkSetup::short(Motion::Normal),
            sfs: THESIS_SFS.to_vec(),
        }
    }
}

impl CellSizeConfig {
    /// Checks the walk (one pattern) and the sweep (not empty, every SF ≥ 1, none twice).
    pub fn validate(&self) -> Result<()> {
        self.walk.validate()?;
        self.walk.single_pattern("the cell-size sweep")?;
        check_sweep("scale factor SF", &self.sfs, check_sf)
    }

    /// The walk settings of configuration `preset` at scale factor `sf`.
    pub fn review(&self, preset: Preset, sf: f32) -> ReviewConfig {
        ReviewConfig {
            sf,
            ..self.walk.review(preset)
        }
    }
}

/// One configuration at one scale factor.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CellSizeRow {
    pub sf: f32,
    pub preset: Preset,
    /// Mean, variance (ms²) and maximum of the frame time, as the walk's summary has them.
    pub mean_frame_ms: f64,
    pub frame_ms_variance: f64,
    pub max_frame_ms: f64,
    /// Frames over 50 ms, the thesis's real-time limit.
    pub frames_over_50ms: usize,
    pub queries: usize,
    /// The viewer's mean wait per query, ms.
    pub mean_query_ms: f64,
    pub index_pages: u64,
    pub mesh_pages: u64,
    pub index_per_query: f64,
    /// Index and mesh pages per query: the thesis's "disk I/Os per query".
    pub io_per_query: f64,
}

impl CellSizeRow {
    fn from_walk(sf: f32, preset: Preset, w: &WalkReport) -> CellSizeRow {
        let s = &w.summary;
        CellSizeRow {
            sf,
            preset,
            mean_frame_ms: s.mean_frame_ms,
            frame_ms_variance: s.frame_ms_variance,
            max_frame_ms: s.max_frame_ms,
            frames_over_50ms: s.frames_over_50ms,
            queries: s.queries,
            mean_query_ms: mean_query_ms(w),
            index_pages: s.index_pages,
            mesh_pages: s.mesh_pages,
            index_per_query: per_query(s.index_pages, s.queries),
            io_per_query: per_query(s.index_pages + s.mesh_pages, s.queries),
        }
    }
}

/// The whole sweep.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CellSizeReport {
    pub config: CellSizeConfig,
    /// SF by SF in the order of the sweep, each in the order of `Preset::ALL`.
    pub rows: Vec<CellSizeRow>,
}

/// The files [`CellSizeReport::plot`] writes: Fig. 4.19, Fig. 4.20, and index pages per
/// query against SF.
pub const FRAME_PLOT_FILE: &str = "csearch-cell-size-frame-time.png";
pub const VARIANCE_PLOT_FILE: &str = "csearch-cell-size-variance.png";
pub const PAGES_PLOT_FILE: &str = "csearch-cell-size-pages.png";

/// Runs the sweep.
pub fn run(db: &Database, cfg: &CellSizeConfig) -> Result<CellSizeReport> {
    run_with_progress(db, cfg, |_, _| {})
}

/// Runs the sweep; `progress(done, total)` is told after each walk.
pub fn run_with_progress(
    db: &Database,
    cfg: &CellSizeConfig,
    mut progress: impl FnMut(usize, usize),
) -> Result<CellSizeReport> {
    cfg.validate()?;
    let path = cfg
        .walk
        .path(db, cfg.walk.single_pattern("the cell-size sweep")?)?;
    let total = cfg.sfs.len() * Preset::ALL.len();
    let mut rows = Vec::with_capacity(total);
    for &sf in &cfg.sfs {
        for preset in Preset::ALL {
            let walk = walk_path(db, &path, cfg.review(preset, sf), &mut NoSink)?;
            rows.push(CellSizeRow::from_walk(sf, preset, &walk));
            progress(rows.len(), total);
        }
    }
    Ok(CellSizeReport {
        config: cfg.clone(),
        rows,
    })
}

/// A column of the tables and a line of the plots: a figure of a row.
type Figure = fn(&CellSizeRow) -> f64;

impl CellSizeReport {
    /// The row of `preset` at `sf`, if it was walked.
    pub fn row(&self, sf: f32, preset: Preset) -> Option<&CellSizeRow> {
        self.rows.iter().find(|r| r.sf == sf && r.preset == preset)
    }

    /// The rows of `preset`, in the order of the sweep.
    pub fn rows_of(&self, preset: Preset) -> impl Iterator<Item = &CellSizeRow> {
        self.rows.iter().filter(move |r| r.preset == preset)
    }

    /// How the measured figures compare, counted over the sweep, and the cell sizes at
    /// which the first disk cell held the whole walk.
    fn comparison(&self) -> String {
        let n = self.config.sfs.len();
        let one_cell: Vec<String> = self
            .config
            .sfs
            .iter()
            .filter(|&&sf| {
                self.rows
                    .iter()
                    .filter(|r| r.sf == sf)
                    .all(|r| r.queries <= 1)
            })
            .map(|&sf| num(sf))
            .collect();
        let count = |by: Figure| {
            self.config
                .sfs
                .iter()
                .filter(
                    |&&sf| match (self.row(sf, Preset::Box), self.row(sf, Preset::Optimal)) {
                        (Some(b), Some(o)) => by(b) > by(o),
                        _ => false,
                    },
                )
                .count()
        };
        let mut s = format!(
            "Here BOX's mean frame time is above Optimal's at {} of {n} cell sizes, its variance at {}, its longest \
             frame at {}, and its index pages per query at {}.",
            count(|r| r.mean_frame_ms),
            count(|r| r.frame_ms_variance),
            count(|r| r.max_frame_ms),
            count(|r| r.index_per_query)
        );
        if !one_cell.is_empty() {
            s.push_str(&format!(
                " At SF {} the first disk cell held the whole walk: no configuration queried again, so the figures \
                 there say nothing about retrieval.",
                one_cell.join(", ")
            ));
        }
        s.push('\n');
        s
    }
}

impl Report for CellSizeReport {
    fn name(&self) -> &'static str {
        "csearch-cell-size"
    }

    /// One line per configuration and scale factor.
    fn to_csv(&self) -> String {
        let mut s = String::from(
            "sf,configuration,mean_frame_ms,frame_ms_variance,max_frame_ms,frames_over_50ms,queries,mean_query_ms,index_pages,mesh_pages,index_per_query,io_per_query\n",
        );
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{:.4},{:.4},{:.3},{},{},{:.4},{},{},{:.2},{:.2}\n",
                r.sf,
                r.preset.name(),
                r.mean_frame_ms,
                r.frame_ms_variance,
                r.max_frame_ms,
                r.frames_over_50ms,
                r.queries,
                r.mean_query_ms,
                r.index_pages,
                r.mesh_pages,
                r.index_per_query,
                r.io_per_query
            ));
        }
        s
    }

    /// Fig. 4.19 (mean frame time), Fig. 4.20 (its variance) and index pages per query,
    /// each against SF with a line per configuration; written to [`FRAME_PLOT_FILE`],
    /// [`VARIANCE_PLOT_FILE`] and [`PAGES_PLOT_FILE`] in `dir` (created if missing).
    fn plot(&self, dir: &Path) -> Result<()> {
        use super::plot::{line_plot, LinePlot, Series};
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let series = |by: Figure| -> Vec<Series> {
            Preset::ALL
                .iter()
                .map(|&p| {
                    let mut points: Vec<(f64, f64)> =
                        self.rows_of(p).map(|r| (r.sf as f64, by(r))).collect();
                    points.sort_by(|a, b| a.0.total_cmp(&b.0));
                    Series {
                        name: label(p).into(),
                        points,
                    }
                })
                .collect()
        };
        let x_label = "cell size: scale factor SF (disk cell / frustum cell)".to_string();
        for (file, title, y_label, by) in [
            (
                FRAME_PLOT_FILE,
                "Mean frame time against cell size (Fig. 4.19)",
                "mean frame time (ms)",
                (|r: &CellSizeRow| r.mean_frame_ms) as Figure,
            ),
            (
                VARIANCE_PLOT_FILE,
                "Variance of the frame time against cell size (Fig. 4.20)",
                "frame time variance (ms²)",
                |r: &CellSizeRow| r.frame_ms_variance,
            ),
            (
                PAGES_PLOT_FILE,
                "Index pages read per query against cell size",
                "index pages per query",
                |r: &CellSizeRow| r.index_per_query,
            ),
        ] {
            line_plot(
                &dir.join(file),
                &LinePlot {
                    title: title.into(),
                    x_label: x_label.clone(),
                    y_label: y_label.into(),
                    series: series(by),
                },
            )?;
        }
        Ok(())
    }

    /// The tables beside the thesis's Fig. 4.19 and 4.20, described in words (the thesis
    /// gives them as plots only).
    fn markdown(&self) -> String {
        let c = &self.config;
        let mut s = String::from("## Frame time against cell size, four configurations (Shou 2002, Fig. 4.19 and 4.20)\n\n");
        s.push_str(&format!(
            "One {} walk: {}; SF = {}. Optimal: {}; NC: no index cache; NP: no prefetching; BOX: plain range \
             queries, each reloading its whole cell.\n\n",
            c.walk.patterns.iter().map(|p| p.name()).collect::<Vec<_>>().join(", "),
            c.walk.describe(),
            c.sfs.iter().map(|&v| num(v)).collect::<Vec<_>>().join(", "),
            describe_review(&c.walk.review(Preset::Optimal))
        ));
        let head = format!(
            "| SF | {} |\n|---|{}\n",
            Preset::ALL
                .iter()
                .map(|&p| label(p))
                .collect::<Vec<_>>()
                .join(" | "),
            "---|".repeat(Preset::ALL.len())
        );
        for (title, by) in [
            (
                "Mean frame time, ms (Fig. 4.19)",
                (|r: &CellSizeRow| format!("{:.3}", r.mean_frame_ms)) as fn(&CellSizeRow) -> String,
            ),
            (
                "Frame time variance, ms² (Fig. 4.20)",
                |r: &CellSizeRow| format!("{:.3}", r.frame_ms_variance),
            ),
            (
                "Longest frame, ms (frames over 50 ms)",
                |r: &CellSizeRow| format!("{:.1} ({})", r.max_frame_ms, r.frames_over_50ms),
            ),
            (
                "Queries (viewer's mean wait per query, ms)",
                |r: &CellSizeRow| format!("{} ({:.2})", r.queries, r.mean_query_ms),
            ),
            ("Index pages per query", |r: &CellSizeRow| {
                format!("{:.1}", r.index_per_query)
            }),
            (
                "Disk I/Os (index + mesh pages) per query",
                |r: &CellSizeRow| format!("{:.0}", r.io_per_query),
            ),
        ] {
            s.push_str(&format!("{title}:\n\n{head}"));
            for &sf in &c.sfs {
                let cells: Vec<String> = Preset::ALL
                    .iter()
                    .map(|&p| self.row(sf, p).map(by).unwrap_or_default())
                    .collect();
                s.push_str(&format!("| {} | {} |\n", num(sf), cells.join(" | ")));
            }
            s.push('\n');
        }
        s.push_str(&self.comparison());
        s.push_str(
            "\nThe thesis (Fig. 4.19): BOX's mean frame time is much longer than that of the three configurations \
             with complement search at every cell size, and grows as the cells shrink (more queries, and their \
             overlaps re-read); Optimal, NC and NP stay about flat, since a query returns only what the new cell \
             adds. BOX's mean falls as the cells grow only because it queries less often, each query a longer \
             pause. Fig. 4.20: BOX's frame time varies more than Optimal's (a choppy walk), and caching and \
             prefetching matter less to the frame time than complement search. It gives no numbers for either \
             figure; compare the shapes. Our frame is headless (query, load, cull and draw preparation, no \
             rendering), so our times are smaller than the thesis's and BOX's pauses are mostly mesh loading.\n",
        );
        s
    }
}
