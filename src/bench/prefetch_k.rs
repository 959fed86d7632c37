//! The `prefetch-k` experiment (Shou 2002 §4.4.1, Fig. 4.17): mean frame time and mean
//! query time against the prefetch factor k (F' = F + k·velocity, §4.2.5), one curve per
//! motion pattern.
//!
//! Each pattern is one generated camera path (`walk::motion`, the same seed for every
//! pattern and every k); the Optimal configuration (CSearch + distance-priority index
//! cache + prefetching) walks it once per k with the REVIEW frame loop (`walk::review`).
//! The query time of a frame is what the viewer waited for its query: the whole query
//! when it ran on the frame's thread, the rest of a prefetch otherwise; it is averaged
//! over the frames that queried. Times are wall-clock and noisy: on a small city the
//! curves are flat within the noise, and the best k should be read with that in mind.

use std::path::Path;

use super::walk_setup::{check_k, check_sweep, mean_query_ms, num, WalkSetup};
use crate::database::Database;
use crate::error::{Error, Result};
use crate::walk::motion::Motion;
use crate::walk::review::{self, Preset, ReviewConfig, WalkReport};

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PrefetchKConfig {
    /// The walks: every pattern of `walk.patterns`, once per k.
    pub walk: WalkSetup,
    /// The prefetch factors tried, in order.
    pub ks: Vec<f32>,
}

/// The thesis's sweep of Fig. 4.17: 0.0, 0.2, …, 2.0.
pub fn default_ks() -> Vec<f32> {
    (0..=10).map(|i| i as f32 / 5.0).collect()
}

impl Default for PrefetchKConfig {
    fn default() -> PrefetchKConfig {
        PrefetchKConfig {
            walk: WalkSetup::default(),
            ks: default_ks(),
        }
    }
}

impl PrefetchKConfig {
    /// Checks the walk and the sweep.
    pub fn validate(&self) -> Result<()> {
        self.walk.validate()?;
        check_sweep("prefetch factor k", &self.ks, check_k)
    }

    /// The walk settings for factor `k`: Optimal with this experiment's walk.
    pub fn review(&self, k: f32) -> ReviewConfig {
        ReviewConfig {
            prefetch_k: Some(k),
            ..self.walk.review(Preset::Optimal)
        }
    }
}

/// One walk: one pattern, one k.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PrefetchKRow {
    pub pattern: Motion,
    pub k: f32,
    pub mean_frame_ms: f64,
    pub frame_ms_variance: f64,
    /// Mean query time over the frames that queried, ms.
    pub mean_query_ms: f64,
    pub queries: usize,
    /// Queries answered by a prefetch.
    pub prefetches_used: usize,
    /// Queries the viewer's thread ran itself (it waited for their I/O): what a good
    /// prediction avoids. A count, less noisy than the times.
    pub sync_queries: usize,
    pub index_pages: u64,
    pub mesh_pages: u64,
}

impl PrefetchKRow {
    fn from_walk(pattern: Motion, k: f32, w: &WalkReport) -> PrefetchKRow {
        let s = &w.summary;
        PrefetchKRow {
            pattern,
            k,
            mean_frame_ms: s.mean_frame_ms,
            frame_ms_variance: s.frame_ms_variance,
            mean_query_ms: mean_query_ms(w),
            queries: s.queries,
            prefetches_used: s.prefetches_used,
            sync_queries: s.sync_queries,
            index_pages: s.index_pages,
            mesh_pages: s.mesh_pages,
        }
    }
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct PrefetchKReport {
    pub config: PrefetchKConfig,
    /// Pattern by pattern, k by k, in the orders of the config.
    pub rows: Vec<PrefetchKRow>,
}

/// The files [`PrefetchKReport::plot`] writes: Fig. 4.17(a) and (b).
pub const FRAME_PLOT_FILE: &str = "prefetch-k-frame-time.png";
pub const QUERY_PLOT_FILE: &str = "prefetch-k-query-time.png";

/// The thesis's optimum (Fig. 4.17): around k = 0.8 for every session.
pub const THESIS_BEST_K: f32 = 0.8;

/// Runs the experiment.
pub fn run(db: &Database, cfg: &PrefetchKConfig) -> Result<PrefetchKReport> {
    run_with_progress(db, cfg, |_, _| {})
}

/// Runs the experiment; `progress(done, total)` is told after each walk.
pub fn run_with_progress(
    db: &Database,
    cfg: &PrefetchKConfig,
    mut progress: impl FnMut(usize, usize),
) -> Result<PrefetchKReport> {
    cfg.validate()?;
    let total = cfg.walk.patterns.len() * cfg.ks.len();
    let mut rows = Vec::with_capacity(total);
    for &pattern in &cfg.walk.patterns {
        let path = cfg.walk.path(db, pattern)?;
        for &k in &cfg.ks {
            let walk = review::walk(db, &path, &cfg.review(k), |_| {})?;
            rows.push(PrefetchKRow::from_walk(pattern, k, &walk));
            progress(rows.len(), total);
        }
    }
    Ok(PrefetchKReport {
        config: cfg.clone(),
        rows,
    })
}

impl PrefetchKReport {
    /// One line per walk.
    pub fn to_csv(&self) -> String {
        let mut s = String::from(
            "pattern,k,mean_frame_ms,frame_ms_variance,mean_query_ms,queries,prefetches_used,sync_queries,index_pages,mesh_pages\n",
        );
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{:.4},{:.4},{:.4},{},{},{},{},{}\n",
                r.pattern.name(),
                r.k,
                r.mean_frame_ms,
                r.frame_ms_variance,
                r.mean_query_ms,
                r.queries,
                r.prefetches_used,
                r.sync_queries,
                r.index_pages,
                r.mesh_pages
            ));
        }
        s
    }

    /// The rows of `pattern`, in the order of the sweep.
    pub fn rows_of(&self, pattern: Motion) -> impl Iterator<Item = &PrefetchKRow> {
        self.rows.iter().filter(move |r| r.pattern == pattern)
    }

    /// The k with the smallest mean frame time on `pattern` (ties go to the smaller k);
    /// `None` if the pattern was not walked.
    pub fn best_k(&self, pattern: Motion) -> Option<f32> {
        self.best(pattern, |r| r.mean_frame_ms).map(|r| r.k)
    }

    /// The k with the smallest mean query time on `pattern` (ties to the smaller k).
    pub fn best_query_k(&self, pattern: Motion) -> Option<f32> {
        self.best(pattern, |r| r.mean_query_ms).map(|r| r.k)
    }

    fn best(&self, pattern: Motion, by: fn(&PrefetchKRow) -> f64) -> Option<&PrefetchKRow> {
        self.rows_of(pattern)
            .min_by(|a, b| by(a).total_cmp(&by(b)).then(a.k.total_cmp(&b.k)))
    }

    /// Fig. 4.17: (a) mean frame time and (b) mean query time against k, one line per
    /// pattern; written to [`FRAME_PLOT_FILE`] and [`QUERY_PLOT_FILE`] in `dir` (created
    /// if missing).
    pub fn plot(&self, dir: &Path) -> Result<()> {
        use super::plot::{line_plot, LinePlot, Series};
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let series = |by: fn(&PrefetchKRow) -> f64| -> Vec<Series> {
            self.config
                .walk
                .patterns
                .iter()
                .map(|&p| Series {
                    name: p.name().into(),
                    points: self.rows_of(p).map(|r| (r.k as f64, by(r))).collect(),
                })
                .collect()
        };
        line_plot(
            &dir.join(FRAME_PLOT_FILE),
            &LinePlot {
                title: "(a) Mean frame time against the prefetch factor k".into(),
                x_label: "prefetch factor k".into(),
                y_label: "mean frame time (ms)".into(),
                series: series(|r| r.mean_frame_ms),
            },
        )?;
        line_plot(
            &dir.join(QUERY_PLOT_FILE),
            &LinePlot {
                title: "(b) Mean query time against the prefetch factor k".into(),
                x_label: "prefetch factor k".into(),
                y_label: "mean query time (ms)".into(),
                series: series(|r| r.mean_query_ms),
            },
        )
    }

    /// The best k per pattern beside the thesis's.
    pub fn markdown(&self) -> String {
        let c = &self.config;
        let mut s = String::from("# prefetch-k — frame and query time against the prefetch factor k (Shou 2002, Fig. 4.17)\n\n");
        s.push_str(&format!(
            "Optimal configuration (CSearch, 1 MB distance-priority index cache, prefetching); each pattern: \
             {}, SF {}; k = {}.\n\n",
            c.walk.describe(),
            num(c.walk.sf),
            c.ks.iter().map(|&k| num(k)).collect::<Vec<_>>().join(", ")
        ));
        let head = format!(
            "| pattern | {} |\n|---|{}\n",
            c.ks.iter()
                .map(|&k| format!("k = {}", num(k)))
                .collect::<Vec<_>>()
                .join(" | "),
            "---|".repeat(c.ks.len())
        );
        for (title, by) in [
            (
                "Mean frame time, ms",
                (|r: &PrefetchKRow| r.mean_frame_ms) as fn(&PrefetchKRow) -> f64,
            ),
            (
                "Mean query time (frames that queried), ms",
                |r: &PrefetchKRow| r.mean_query_ms,
            ),
        ] {
            s.push_str(&format!("{title}:\n\n{head}"));
            for &p in &c.walk.patterns {
                let cells: Vec<String> = self.rows_of(p).map(|r| format!("{:.3}", by(r))).collect();
                s.push_str(&format!("| {} | {} |\n", p.name(), cells.join(" | ")));
            }
            s.push('\n');
        }
        s.push_str(&format!(
            "Queries the viewer's thread ran itself (a prediction that held spares one):\n\n{head}"
        ));
        for &p in &c.walk.patterns {
            let cells: Vec<String> = self
                .rows_of(p)
                .map(|r| r.sync_queries.to_string())
                .collect();
            s.push_str(&format!("| {} | {} |\n", p.name(), cells.join(" | ")));
        }
        s.push('\n');
        s.push_str("| pattern | best k (frame time) | mean frame ms there | best k (query time) | queries | prefetches used |\n|---|---|---|---|---|---|\n");
        for &p in &c.walk.patterns {
            let Some(best) = self.best(p, |r| r.mean_frame_ms) else {
                continue;
            };
            s.push_str(&format!(
                "| {} | {} | {:.3} | {} | {} | {} |\n",
                p.name(),
                num(best.k),
                best.mean_frame_ms,
                self.best_query_k(p).map(num).unwrap_or_default(),
                best.queries,
                best.prefetches_used
            ));
        }
        s.push_str(&format!(
            "\nThe thesis (Fig. 4.17) finds the smallest mean frame time, and the smallest mean query time, around \
             k = {} for all five sessions (fast, slow, turning, backward, normal), and uses it as its default. \
             Our times are wall-clock on this machine: differences smaller than the run-to-run noise do not \
             rank the k's.\n",
            num(THESIS_BEST_K)
        ));
        s
    }
}
