//! The `prefetch-k` experiment (Shou 2002 §4.4.1, Fig. 4.17): mean frame time, mean
//! query time and disk pages read against the prefetch factor k (F' = F + k·velocity, §4.2.5),
//! one curve per motion pattern.
//!
//! Each pattern is one generated camera path (`path::motion`, the same seed for every
//! pattern and every k); the Optimal configuration (CSearch + distance-priority index
//! cache + prefetching) walks it once per k with the REVIEW frame loop (`walk::review`).
//! k is in seconds: the predicted cell is the disk cell of the frusta the viewer will
//! have over the next k seconds of its current motion (`walk::review`). The query time of a frame is what the
//! viewer waited for its query: the whole query when it ran on the frame's thread, the
//! rest of a prefetch otherwise; it is averaged over the frames that queried.
//!
//! The best k is named by counts, not by the times: first the searches the viewer's
//! thread ran itself (what a prediction is for: too small a k and the viewer leaves each
//! predicted cell before the next one is ready), then the disk pages the walk read (too
//! large a k and the predicted cell overlaps the viewer's less: bigger loads, objects
//! fetched that the viewer never reaches, evictions under the budget that force
//! reloads). Counts are exact for a given run of the walk; the frame times beside them
//! are wall-clock and noisy.

use std::path::Path;

use crate::report::Report;
use crate::walk_setup::{check_k, check_sweep, mean_query_ms, num, walk_path, WalkSetup};
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::path::motion::Motion;
use flaneur::walk::review::{Preset, ReviewConfig, WalkReport};
use flaneur::walk::NoSink;

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PrefetchKConfig {
    /// The walks: every pattern of `walk.patterns`, once per k.
    pub walk: WalkSetup,
    /// The prefetch factors tried, in order.
    pub ks: Vec<f32>,
    /// Walks per pattern and k; the row kept is the median walk by the ranking's
    /// order, with the spread of the counts over all of them.
    pub repeats: usize,
}

/// The thesis's range of Fig. 4.17 (0 to 2) in steps of 0.4, then on to 8 s: on the demo
/// city's 1.2 km disk cells the predictions start to miss only past 2 s of motion.
pub fn default_ks() -> Vec<f32> {
    vec![0.0, 0.4, 0.8, 1.2, 1.6, 2.0, 3.0, 4.0, 6.0, 8.0]
}

impl Default for PrefetchKConfig {
    fn default() -> PrefetchKConfig {
        PrefetchKConfig {
            walk: WalkSetup::default(),
            ks: default_ks(),
            repeats: 1,
        }
    }
}

impl PrefetchKConfig {
    /// Checks the walk and the sweep.
    pub fn validate(&self) -> Result<()> {
        self.walk.validate()?;
        if self.repeats == 0 {
            return Err(Error::Invalid(
                "prefetch-k: repeats must be at least 1".into(),
            ));
        }
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
    pub frames_over_50ms: usize,
    pub index_pages: u64,
    pub mesh_pages: u64,
    /// Smallest and largest viewer's own searches over the repeated walks.
    pub sync_queries_spread: (usize, usize),
    /// Smallest and largest pages read over the repeated walks.
    pub pages_spread: (u64, u64),
}

impl PrefetchKRow {
    /// Disk pages read by the walk, index and meshes.
    pub fn pages(&self) -> u64 {
        self.index_pages + self.mesh_pages
    }

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
            frames_over_50ms: s.frames_over_50ms,
            index_pages: s.index_pages,
            mesh_pages: s.mesh_pages,
            sync_queries_spread: (s.sync_queries, s.sync_queries),
            pages_spread: (s.index_pages + s.mesh_pages, s.index_pages + s.mesh_pages),
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
/// Disk pages read per walk against k (not in the thesis; the count [`PrefetchKReport::best_k`] ranks by).
pub const PAGES_PLOT_FILE: &str = "prefetch-k-pages.png";

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
    let total = cfg.walk.patterns.len() * cfg.ks.len() * cfg.repeats;
    let mut rows = Vec::with_capacity(total / cfg.repeats);
    let mut done = 0;
    for &pattern in &cfg.walk.patterns {
        let path = cfg.walk.path(db, pattern)?;
        for &k in &cfg.ks {
            let mut runs = Vec::with_capacity(cfg.repeats);
            for _ in 0..cfg.repeats {
                let walk = walk_path(db, &path, cfg.review(k), &mut NoSink)?;
                runs.push(PrefetchKRow::from_walk(pattern, k, &walk));
                done += 1;
                progress(done, total);
            }
            rows.push(median_run(runs));
        }
    }
    Ok(PrefetchKReport {
        config: cfg.clone(),
        rows,
    })
}

impl PrefetchKReport {
    /// The rows of `pattern`, in the order of the sweep.
    pub fn rows_of(&self, pattern: Motion) -> impl Iterator<Item = &PrefetchKRow> {
        self.rows.iter().filter(move |r| r.pattern == pattern)
    }

    /// The k whose walk of `pattern` ran the fewest searches on the viewer's thread, ties
    /// going to fewer disk pages read (index and meshes, on either thread), then to the
    /// smaller mean frame time; `None` if the pattern was not walked.
    pub fn best_k(&self, pattern: Motion) -> Option<f32> {
        self.best(pattern).map(|r| r.k)
    }

    /// Whether `pattern`'s best k lies inside the sweep, with a worse k (by the same
    /// order) on both sides: an optimum rather than the end of a slope (or a flat line).
    pub fn has_interior_optimum(&self, pattern: Motion) -> bool {
        let rows: Vec<&PrefetchKRow> = self.rows_of(pattern).collect();
        let Some(best) = self.best(pattern) else {
            return false;
        };
        let Some(i) = rows.iter().position(|r| std::ptr::eq(*r, best)) else {
            return false;
        };
        let more = |r: &&PrefetchKRow| rank(r) > rank(best);
        rows[..i].iter().any(more) && rows[i + 1..].iter().any(more)
    }

    /// The k with the smallest mean frame time on `pattern` (ties to the smaller k).
    pub fn best_frame_k(&self, pattern: Motion) -> Option<f32> {
        self.best_by(pattern, |r| r.mean_frame_ms).map(|r| r.k)
    }

    /// The k with the smallest mean query time on `pattern` (ties to the smaller k).
    pub fn best_query_k(&self, pattern: Motion) -> Option<f32> {
        self.best_by(pattern, |r| r.mean_query_ms).map(|r| r.k)
    }

    fn best(&self, pattern: Motion) -> Option<&PrefetchKRow> {
        self.rows_of(pattern).min_by(|a, b| {
            rank(a)
                .cmp(&rank(b))
                .then(a.mean_frame_ms.total_cmp(&b.mean_frame_ms))
                .then(a.k.total_cmp(&b.k))
        })
    }

    fn best_by(&self, pattern: Motion, by: fn(&PrefetchKRow) -> f64) -> Option<&PrefetchKRow> {
        self.rows_of(pattern)
            .min_by(|a, b| by(a).total_cmp(&by(b)).then(a.k.total_cmp(&b.k)))
    }
}

impl Report for PrefetchKReport {
    fn name(&self) -> &'static str {
        "prefetch-k"
    }

    /// One line per walk.
    fn to_csv(&self) -> String {
        let mut s = String::from(
            "pattern,k,mean_frame_ms,frame_ms_variance,mean_query_ms,queries,prefetches_used,sync_queries,frames_over_50ms,index_pages,mesh_pages\n",
        );
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{:.4},{:.4},{:.4},{},{},{},{},{},{}\n",
                r.pattern.name(),
                r.k,
                r.mean_frame_ms,
                r.frame_ms_variance,
                r.mean_query_ms,
                r.queries,
                r.prefetches_used,
                r.sync_queries,
                r.frames_over_50ms,
                r.index_pages,
                r.mesh_pages
            ));
        }
        s
    }

    /// Fig. 4.17: (a) mean frame time and (b) mean query time against k, one line per
    /// pattern, and (c) disk pages read per walk; written to [`FRAME_PLOT_FILE`],
    /// [`QUERY_PLOT_FILE`] and [`PAGES_PLOT_FILE`] in `dir` (created if missing).
    fn plot(&self, dir: &Path) -> Result<()> {
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
                x_label: "prefetch factor k (s)".into(),
                y_label: "mean frame time (ms)".into(),
                series: series(|r| r.mean_frame_ms),
            },
        )?;
        line_plot(
            &dir.join(QUERY_PLOT_FILE),
            &LinePlot {
                title: "(b) Mean query time against the prefetch factor k".into(),
                x_label: "prefetch factor k (s)".into(),
                y_label: "mean query time (ms)".into(),
                series: series(|r| r.mean_query_ms),
            },
        )?;
        line_plot(
            &dir.join(PAGES_PLOT_FILE),
            &LinePlot {
                title: "(c) Disk pages read per walk against the prefetch factor k".into(),
                x_label: "prefetch factor k (s)".into(),
                y_label: "pages read (index and meshes)".into(),
                series: series(|r| r.pages() as f64),
            },
        )
    }

    /// The best k per pattern beside the thesis's.
    fn markdown(&self) -> String {
        let c = &self.config;
        let mut s = String::from("# prefetch-k — frame and query time against the prefetch factor k (Shou 2002, Fig. 4.17)\n\n");
        s.push_str(&format!(
            "Optimal configuration (CSearch, 1 MB distance-priority index cache, prefetching); each pattern: \
             {}, SF {}; k = {}; {} per k (the median walk by the ranking below is shown).\n\n",
            c.walk.describe(),
            num(c.walk.sf),
            c.ks.iter().map(|&k| num(k)).collect::<Vec<_>>().join(", "),
            if c.repeats == 1 { "one walk".to_string() } else { format!("{} walks", c.repeats) }
        ));
        let head = format!(
            "| pattern | {} |\n|---|{}\n",
            c.ks.iter()
                .map(|&k| format!("k = {}", num(k)))
                .collect::<Vec<_>>()
                .join(" | "),
            "---|".repeat(c.ks.len())
        );
        type Cell = fn(&PrefetchKRow) -> String;
        let mut tables: Vec<(String, Cell)> = vec![
            ("Mean frame time, ms".into(), |r| {
                format!("{:.3}", r.mean_frame_ms)
            }),
            ("Mean query time (frames that queried), ms".into(), |r| {
                format!("{:.3}", r.mean_query_ms)
            }),
            (
                "Index searches per walk (prefetched, dropped or the viewer's own)".into(),
                |r| r.queries.to_string(),
            ),
            (
                "Of those, the viewer's own (a prediction that held spares one)".into(),
                |r| r.sync_queries.to_string(),
            ),
            ("Disk pages read (index and meshes)".into(), |r| {
                r.pages().to_string()
            }),
            ("Frames over 50 ms".into(), |r| {
                r.frames_over_50ms.to_string()
            }),
        ];
        if c.repeats > 1 {
            let over = format!(", over {} walks per k", c.repeats);
            tables.push((
                format!("The viewer's own searches, smallest–largest{over}"),
                |r| format!("{}–{}", r.sync_queries_spread.0, r.sync_queries_spread.1),
            ));
            tables.push((format!("Pages read, smallest–largest{over}"), |r| {
                format!("{}–{}", r.pages_spread.0, r.pages_spread.1)
            }));
        }
        for (title, cell) in tables {
            s.push_str(&format!("{title}:\n\n{head}"));
            for &p in &c.walk.patterns {
                let cells: Vec<String> = self.rows_of(p).map(cell).collect();
                s.push_str(&format!("| {} | {} |\n", p.name(), cells.join(" | ")));
            }
            s.push('\n');
        }
        s.push_str(
            "| pattern | best k (fewest own searches, then pages) | pages there | searches | viewer's own | an optimum inside the sweep? | \
             best k (frame time) | best k (query time) |\n|---|---|---|---|---|---|---|---|\n",
        );
        for &p in &c.walk.patterns {
            let Some(best) = self.best(p) else { continue };
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} | {} | {} |\n",
                p.name(),
                num(best.k),
                best.pages(),
                best.queries,
                best.sync_queries,
                if self.has_interior_optimum(p) {
                    "yes"
                } else {
                    "no: flat or at an end"
                },
                self.best_frame_k(p).map(num).unwrap_or_default(),
                self.best_query_k(p).map(num).unwrap_or_default(),
            ));
        }
        s.push_str(
            "\nA walk's loads depend on when its prefetches land and on what the budget evicts, so pages read \
             differ by tens of percent between neighbouring k's even where nothing changes systematically: read \
             the best k as the region where both the viewer's own searches and the pages are low.\n",
        );
        s.push_str(&format!(
            "\nThe thesis (Fig. 4.17) finds the smallest mean frame time, and the smallest mean query time, around \
             k = {} for all five sessions (fast, slow, turning, backward, normal), and uses it as its default; it gives no unit \
             for the velocity. Ours is metres per second, so k is in seconds. The best k here is named by the \
             viewer's own searches, then the disk pages read, which are exact; the times are wall-clock on this machine, and differences \
             smaller than the run-to-run noise do not rank the k's.\n",
            num(THESIS_BEST_K)
        ));
        s
    }
}

/// The median of repeated walks by [`rank`], carrying the spread of all of them.
fn median_run(mut runs: Vec<PrefetchKRow>) -> PrefetchKRow {
    let sync = runs.iter().map(|r| r.sync_queries);
    let sync_spread = (sync.clone().min().unwrap_or(0), sync.max().unwrap_or(0));
    let pages = runs.iter().map(|r| r.pages());
    let pages_spread = (pages.clone().min().unwrap_or(0), pages.max().unwrap_or(0));
    runs.sort_by_key(rank);
    let mut median = runs.swap_remove(runs.len() / 2);
    median.sync_queries_spread = sync_spread;
    median.pages_spread = pages_spread;
    median
}

/// The order [`PrefetchKReport::best_k`] ranks by.
fn rank(r: &PrefetchKRow) -> (usize, u64) {
    (r.sync_queries, r.pages())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(counts: &[(f32, usize, usize, f64)]) -> PrefetchKReport {
        let rows = counts
            .iter()
            .map(|&(k, pages, sync_queries, mean_frame_ms)| PrefetchKRow {
                pattern: Motion::Normal,
                k,
                mean_frame_ms,
                frame_ms_variance: 0.0,
                mean_query_ms: 0.0,
                queries: 1,
                prefetches_used: 0,
                sync_queries,
                frames_over_50ms: 0,
                index_pages: 1,
                mesh_pages: pages as u64 - 1,
                sync_queries_spread: (sync_queries, sync_queries),
                pages_spread: (pages as u64, pages as u64),
            })
            .collect();
        PrefetchKReport {
            config: PrefetchKConfig::default(),
            rows,
        }
    }

    #[test]
    fn best_k_runs_the_fewest_own_searches_then_reads_the_fewest_pages_then_is_fastest() {
        let r = report(&[
            (0.0, 30, 9, 0.1),
            (1.0, 26, 6, 0.9),
            (2.0, 27, 5, 0.8),
            (3.0, 26, 5, 0.7),
            (4.0, 33, 20, 0.2),
        ]);
        assert_eq!(r.best_k(Motion::Normal), Some(3.0));
        assert!(r.has_interior_optimum(Motion::Normal));
        assert_eq!(r.best_frame_k(Motion::Normal), Some(0.0));
        let tie = report(&[(0.0, 30, 5, 0.3), (1.0, 30, 5, 0.2)]);
        assert_eq!(tie.best_k(Motion::Normal), Some(1.0));
        assert_eq!(tie.best_k(Motion::Fast), None);
    }

    #[test]
    fn repeated_walks_keep_the_median_and_the_spread() {
        let rows = report(&[(1.0, 300, 5, 0.1), (1.0, 100, 1, 0.1), (1.0, 900, 9, 0.1)]).rows;
        let m = median_run(rows);
        assert_eq!((m.sync_queries, m.pages()), (5, 300));
        assert_eq!(
            (m.sync_queries_spread, m.pages_spread),
            ((1, 9), (100, 900))
        );
    }

    #[test]
    fn a_slope_or_a_flat_line_is_no_optimum() {
        assert!(
            !report(&[(0.0, 30, 5, 0.1), (1.0, 28, 5, 0.1), (2.0, 26, 5, 0.1)])
                .has_interior_optimum(Motion::Normal)
        );
        assert!(
            !report(&[(0.0, 3, 1, 0.1), (1.0, 3, 1, 0.1), (2.0, 3, 1, 0.1)])
                .has_interior_optimum(Motion::Normal)
        );
        assert!(!report(&[(0.0, 3, 1, 0.1)]).has_interior_optimum(Motion::Normal));
    }
}
