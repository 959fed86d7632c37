//! The `patterns` experiment (Shou 2002 §4.4.2, Table 4.1): disk I/Os per query of the
//! Optimal configuration (CSearch + 1 MB distance-priority index cache + prefetching)
//! against plain BOX, on one walk per motion pattern.
//!
//! Each of the five patterns of the thesis (normal, fast, slow, turning, backward) is a
//! generated camera path (`path::motion`, the same seed for every pattern); both
//! configurations walk the same path with the REVIEW frame loop (`walk::review`). A disk
//! I/O is a physical page read counted by the store, on either thread of the walk: index
//! (R-tree node) pages and mesh pages, reported apart and summed. Page counts are exact
//! and deterministic for BOX; with prefetching they depend a little on thread timing
//! (which prefetches finish in time).
//!
//! The per-query figures leave out the cold load of the first cell: it is the same full
//! cell for both configurations (there is no history yet), and on a walk of a handful of
//! queries (a slow walker leaves its cell a few times a minute) it would decide the
//! mean. The shares with it are reported beside.

use std::path::Path;

use crate::report::Report;
use crate::walk_setup::{check_k, num, per_query, walk_path, WalkSetup, PATTERN_FRAMES};
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::path::motion::Motion;
use flaneur::walk::review::{Preset, ReviewConfig, WalkReport};
use flaneur::walk::settings;
use flaneur::walk::NoSink;

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PatternsConfig {
    /// The walks: every pattern of `walk.patterns`, walked by both configurations.
    pub walk: WalkSetup,
    /// Prefetch factor k of the Optimal configuration.
    pub prefetch_k: f32,
}

impl Default for PatternsConfig {
    fn default() -> PatternsConfig {
        PatternsConfig {
            walk: WalkSetup {
                frames: PATTERN_FRAMES,
                ..WalkSetup::default()
            },
            prefetch_k: settings::DEFAULT_K,
        }
    }
}

impl PatternsConfig {
    /// Checks the walk and k.
    pub fn validate(&self) -> Result<()> {
        self.walk.validate()?;
        check_k(self.prefetch_k)
    }

    /// The walk settings of one configuration: the preset with this experiment's walk,
    /// and its k where the preset prefetches.
    pub fn review(&self, preset: Preset) -> ReviewConfig {
        let base = self.walk.review(preset);
        ReviewConfig {
            prefetch_k: base.prefetch_k.map(|_| self.prefetch_k),
            ..base
        }
    }
}

/// Pages read by one configuration on one walk.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PresetIo {
    /// Index searches, the first cell's included.
    pub queries: usize,
    pub index_pages: u64,
    pub mesh_pages: u64,
    /// Pages read by the cold load of the first cell.
    pub first_load_pages: u64,
    /// Per query after the first cell (see the module's note).
    pub index_per_query: f64,
    pub mesh_per_query: f64,
    /// Index and mesh pages per query after the first cell: the thesis's "disk I/Os per
    /// query".
    pub io_per_query: f64,
    /// The same over every query, the first cell's included.
    pub io_per_query_with_first: f64,
    pub mean_frame_ms: f64,
}

impl PresetIo {
    fn from_walk(w: &WalkReport) -> PresetIo {
        let s = &w.summary;
        let (first_index, first_mesh) = s.initial_load_pages;
        let later = s.queries.saturating_sub(1);
        PresetIo {
            queries: s.queries,
            index_pages: s.index_pages,
            mesh_pages: s.mesh_pages,
            first_load_pages: first_index + first_mesh,
            index_per_query: per_query(s.index_pages.saturating_sub(first_index), later),
            mesh_per_query: per_query(s.mesh_pages.saturating_sub(first_mesh), later),
            io_per_query: per_query(
                (s.index_pages + s.mesh_pages).saturating_sub(first_index + first_mesh),
                later,
            ),
            io_per_query_with_first: per_query(s.index_pages + s.mesh_pages, s.queries),
            mean_frame_ms: s.mean_frame_ms,
        }
    }
}

/// One pattern: both configurations on the same path.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PatternRow {
    pub pattern: Motion,
    pub optimal: PresetIo,
    pub box_io: PresetIo,
    /// Optimal's disk I/Os per query over BOX's, after the first cell (1 when BOX read
    /// nothing).
    pub ratio: f64,
    /// The same ratio for index pages alone.
    pub index_ratio: f64,
    /// The ratio over every query, the first cell's included.
    pub ratio_with_first: f64,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct PatternsReport {
    pub config: PatternsConfig,
    /// Page size of the database, bytes (what one disk I/O reads).
    pub page_size: usize,
    pub rows: Vec<PatternRow>,
}

/// The file [`PatternsReport::plot`] writes.
pub const PLOT_FILE: &str = "patterns-io-per-query.png";

/// The thesis's Table 4.1: (session, BOX, Optimal) disk I/Os per query.
pub const THESIS_TABLE_4_1: [(usize, f64, f64); 5] = [
    (1, 1877.75, 410.95),
    (2, 1900.94, 169.96),
    (3, 1963.73, 265.88),
    (4, 2018.24, 201.89),
    (5, 1934.57, 212.48),
];

/// Runs the experiment.
pub fn run(db: &Database, cfg: &PatternsConfig) -> Result<PatternsReport> {
    run_with_progress(db, cfg, |_, _| {})
}

/// Runs the experiment; `progress(done, total)` is told after each walk.
pub fn run_with_progress(
    db: &Database,
    cfg: &PatternsConfig,
    mut progress: impl FnMut(usize, usize),
) -> Result<PatternsReport> {
    cfg.validate()?;
    let patterns = &cfg.walk.patterns;
    let total = patterns.len() * 2;
    let mut rows = Vec::with_capacity(patterns.len());
    for (i, &pattern) in patterns.iter().enumerate() {
        let path = cfg.walk.path(db, pattern)?;
        let optimal = PresetIo::from_walk(&walk_path(
            db,
            &path,
            cfg.review(Preset::Optimal),
            &mut NoSink,
        )?);
        progress(2 * i + 1, total);
        let box_io =
            PresetIo::from_walk(&walk_path(db, &path, cfg.review(Preset::Box), &mut NoSink)?);
        progress(2 * i + 2, total);
        let share = |a: f64, b: f64| if b > 0.0 { a / b } else { 1.0 };
        rows.push(PatternRow {
            pattern,
            ratio: share(optimal.io_per_query, box_io.io_per_query),
            index_ratio: share(optimal.index_per_query, box_io.index_per_query),
            ratio_with_first: share(
                optimal.io_per_query_with_first,
                box_io.io_per_query_with_first,
            ),
            optimal,
            box_io,
        });
    }
    Ok(PatternsReport {
        config: cfg.clone(),
        page_size: db.store().page_size(),
        rows,
    })
}

impl PatternsReport {
    /// The row of `pattern`, if it was walked.
    pub fn row(&self, pattern: Motion) -> Option<&PatternRow> {
        self.rows.iter().find(|r| r.pattern == pattern)
    }
}

impl Report for PatternsReport {
    fn name(&self) -> &'static str {
        "patterns"
    }

    /// One line per pattern and configuration.
    fn to_csv(&self) -> String {
        let mut s = String::from(
            "pattern,configuration,queries,index_pages,mesh_pages,first_load_pages,index_per_query,mesh_per_query,io_per_query,io_per_query_with_first,mean_frame_ms,ratio_to_box\n",
        );
        for r in &self.rows {
            for (name, io, ratio) in [("optimal", &r.optimal, r.ratio), ("box", &r.box_io, 1.0)] {
                s.push_str(&format!(
                    "{},{},{},{},{},{},{:.2},{:.2},{:.2},{:.2},{:.3},{:.4}\n",
                    r.pattern.name(),
                    name,
                    io.queries,
                    io.index_pages,
                    io.mesh_pages,
                    io.first_load_pages,
                    io.index_per_query,
                    io.mesh_per_query,
                    io.io_per_query,
                    io.io_per_query_with_first,
                    io.mean_frame_ms,
                    ratio
                ));
            }
        }
        s
    }

    /// Disk I/Os per query against the pattern (x = its position in the report, from 1),
    /// a line per configuration, index pages alone and index + mesh pages; written to
    /// [`PLOT_FILE`] in `dir` (created if missing).
    fn plot(&self, dir: &Path) -> Result<()> {
        use super::plot::{line_plot, LinePlot, Series};
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let series = |name: &str, f: fn(&PatternRow) -> f64| Series {
            name: name.into(),
            points: self
                .rows
                .iter()
                .enumerate()
                .map(|(i, r)| ((i + 1) as f64, f(r)))
                .collect(),
        };
        let names: Vec<String> = self
            .rows
            .iter()
            .enumerate()
            .map(|(i, r)| format!("{} {}", i + 1, r.pattern.name()))
            .collect();
        line_plot(
            &dir.join(PLOT_FILE),
            &LinePlot {
                title: format!("Disk I/Os per query ({})", names.join(", ")),
                x_label: "motion pattern".into(),
                y_label: format!("pages read per query ({} B pages)", self.page_size),
                series: vec![
                    series("BOX, index + mesh", |r| r.box_io.io_per_query),
                    series("Optimal, index + mesh", |r| r.optimal.io_per_query),
                    series("BOX, index", |r| r.box_io.index_per_query),
                    series("Optimal, index", |r| r.optimal.index_per_query),
                ],
            },
        )
    }

    /// The figures beside the thesis's Table 4.1.
    fn markdown(&self) -> String {
        let c = &self.config;
        let mut s = String::from(
            "# patterns — disk I/Os per query, Optimal against BOX (Shou 2002, Table 4.1)\n\n",
        );
        s.push_str(&format!(
            "Each pattern: {}, SF {}, Optimal with k = {}. A disk I/O is one {}-byte page read (index or mesh).\n\n",
            c.walk.describe(),
            num(c.walk.sf),
            num(c.prefetch_k),
            self.page_size
        ));
        s.push_str(
            "Per query after the first cell (the cold load of the first cell, the same for both, is left out; \
             the last column keeps it in):\n\n\
             | pattern | BOX queries | BOX index / q | BOX mesh / q | BOX I/Os / q | Optimal queries | Optimal index / q | Optimal mesh / q | Optimal I/Os / q | Optimal / BOX | index only | with the first cell |\n\
             |---|---|---|---|---|---|---|---|---|---|---|---|\n",
        );
        for r in &self.rows {
            let (b, o) = (&r.box_io, &r.optimal);
            s.push_str(&format!(
                "| {} | {} | {:.1} | {:.1} | {:.1} | {} | {:.1} | {:.1} | {:.1} | {:.1} % | {:.1} % | {:.1} % |\n",
                r.pattern.name(),
                b.queries,
                b.index_per_query,
                b.mesh_per_query,
                b.io_per_query,
                o.queries,
                o.index_per_query,
                o.mesh_per_query,
                o.io_per_query,
                r.ratio * 100.0,
                r.index_ratio * 100.0,
                r.ratio_with_first * 100.0
            ));
        }
        if let (Some(lo), Some(hi)) = (
            self.rows.iter().map(|r| r.ratio).min_by(f64::total_cmp),
            self.rows.iter().map(|r| r.ratio).max_by(f64::total_cmp),
        ) {
            s.push_str(&format!(
                "\nHere Optimal needs {:.1}–{:.1} % of BOX's disk I/Os per query.\n",
                lo * 100.0,
                hi * 100.0
            ));
        }
        s.push_str("\nThe thesis's Table 4.1 (900,000 objects, 1 km frustum, 20 MB memory):\n\n");
        s.push_str(
            "| session | BOX I/Os / q | Optimal I/Os / q | Optimal / BOX |\n|---|---|---|---|\n",
        );
        for (session, b, o) in THESIS_TABLE_4_1 {
            s.push_str(&format!(
                "| {session} | {b:.2} | {o:.2} | {:.1} % |\n",
                o / b * 100.0
            ));
        }
        s.push_str(
            "\nThe thesis: Optimal does 9–21 % of BOX's disk I/Os per query; BOX 1,878–2,018 I/Os per query, \
             Optimal 170–411. It does not say which session had which pattern in Table 4.1 (its Fig. 4.17 \
             lists fast, slow, turning, backward and normal for its five sessions), nor its page size, so \
             compare the shares, not the counts: ours depend on the city, the page size and the frustum.\n",
        );
        s
    }
}
