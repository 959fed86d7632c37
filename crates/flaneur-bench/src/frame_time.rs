//! Time per frame along one path (Shou 2002 §4.4.2, Fig. 4.21): the Optimal
//! configuration against BOX, frame by frame, on the same generated path.
//!
//! Both walk with a 1 MB distance-priority index cache, as the thesis says of this
//! figure ("both of them use the same cache size of 1 MB"): BOX is `walk::review`'s BOX
//! preset plus that cache, so it differs from Optimal only in its queries (plain range
//! queries, each reloading its whole cell) and in having no prefetching. The per-frame
//! times are the walk's own; frame 0 loads the first disk cell from nothing and is left
//! out of the plot (not of the CSV), where it would dwarf the walk itself.

use std::path::Path;

use crate::report::Report;
use crate::walk_setup::{describe_review, label, num, walk_path, WalkSetup};
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::path::motion::Motion;
use flaneur::walk::review::{Preset, ReviewConfig, WalkReport, WalkSummary};
use flaneur::walk::NoSink;

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FrameTimeConfig {
    /// The walk: one path, of the one pattern in `walk.patterns` (normal by default), at
    /// `walk.sf`.
    pub walk: WalkSetup,
}

impl Default for FrameTimeConfig {
    fn default() -> FrameTimeConfig {
        FrameTimeConfig {
            walk: WalkSetup::short(Motion::Normal),
        }
    }
}

/// The two configurations of the figure, in the order of the report.
pub const PRESETS: [Preset; 2] = [Preset::Optimal, Preset::Box];

impl FrameTimeConfig {
    /// Checks the walk (one pattern).
    pub fn validate(&self) -> Result<()> {
        self.walk.validate()?;
        self.walk.single_pattern("the frame-time walk").map(|_| ())
    }

    /// The walk settings of `preset`, with Optimal's index cache (1 MB, distance-priority
    /// LRU) whatever the preset, as in the thesis's figure.
    pub fn review(&self, preset: Preset) -> ReviewConfig {
        ReviewConfig {
            index_cache: ReviewConfig::preset(Preset::Optimal).index_cache,
            ..self.walk.review(preset)
        }
    }
}

/// One frame of both walks.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FrameTimeRow {
    pub frame: usize,
    /// Time along the path, seconds.
    pub time: f64,
    pub optimal_ms: f64,
    pub box_ms: f64,
    /// The viewer entered a new disk cell on this frame.
    pub optimal_queried: bool,
    pub box_queried: bool,
}

/// Both walks, frame by frame.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FrameTimeReport {
    pub config: FrameTimeConfig,
    /// The walks' summaries, in the order of [`PRESETS`].
    pub summaries: [WalkSummary; 2],
    pub rows: Vec<FrameTimeRow>,
}

/// The file [`FrameTimeReport::plot`] writes.
pub const PLOT_FILE: &str = "csearch-frame-time.png";

/// Runs the experiment.
pub fn run(db: &Database, cfg: &FrameTimeConfig) -> Result<FrameTimeReport> {
    run_with_progress(db, cfg, |_, _| {})
}

/// Runs the experiment; `progress(done, total)` is told after each walk.
pub fn run_with_progress(
    db: &Database,
    cfg: &FrameTimeConfig,
    mut progress: impl FnMut(usize, usize),
) -> Result<FrameTimeReport> {
    cfg.validate()?;
    let path = cfg
        .walk
        .path(db, cfg.walk.single_pattern("the frame-time walk")?)?;
    let optimal: WalkReport = walk_path(db, &path, cfg.review(Preset::Optimal), &mut NoSink)?;
    progress(1, 2);
    let boxed: WalkReport = walk_path(db, &path, cfg.review(Preset::Box), &mut NoSink)?;
    progress(2, 2);
    Ok(FrameTimeReport {
        config: cfg.clone(),
        rows: rows(&optimal, &boxed)?,
        summaries: [optimal.summary, boxed.summary],
    })
}

fn rows(optimal: &WalkReport, boxed: &WalkReport) -> Result<Vec<FrameTimeRow>> {
    if optimal.frames.len() != boxed.frames.len() {
        return Err(Error::Invalid(format!(
            "the two walks of one path have {} and {} frames",
            optimal.frames.len(),
            boxed.frames.len()
        )));
    }
    Ok(optimal
        .frames
        .iter()
        .zip(&boxed.frames)
        .map(|(o, b)| FrameTimeRow {
            frame: o.frame,
            time: o.time,
            optimal_ms: o.frame_ms,
            box_ms: b.frame_ms,
            optimal_queried: o.queried,
            box_queried: b.queried,
        })
        .collect())
}

impl Report for FrameTimeReport {
    fn name(&self) -> &'static str {
        "csearch-frame-time"
    }

    /// One line per frame.
    fn to_csv(&self) -> String {
        let mut s = String::from("frame,time,optimal_ms,box_ms,optimal_queried,box_queried\n");
        for r in &self.rows {
            s.push_str(&format!(
                "{},{:.4},{:.4},{:.4},{},{}\n",
                r.frame,
                r.time,
                r.optimal_ms,
                r.box_ms,
                r.optimal_queried as u8,
                r.box_queried as u8
            ));
        }
        s
    }

    /// Fig. 4.21: time per frame along the path, a line per configuration, frame 0 left
    /// out; written to [`PLOT_FILE`] in `dir` (created if missing).
    fn plot(&self, dir: &Path) -> Result<()> {
        use super::plot::{line_plot, LinePlot, Series};
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let series = |name: &str, by: fn(&FrameTimeRow) -> f64| Series {
            name: name.into(),
            points: self
                .rows
                .iter()
                .skip(1)
                .map(|r| (r.frame as f64, by(r)))
                .collect(),
        };
        line_plot(
            &dir.join(PLOT_FILE),
            &LinePlot {
                title: "Time per frame along one path (Fig. 4.21; frame 0, the cold first load, left out)".into(),
                x_label: "frame".into(),
                y_label: "frame time (ms)".into(),
                series: vec![series(label(Preset::Box), |r| r.box_ms), series(label(Preset::Optimal), |r| r.optimal_ms)],
            },
        )
    }

    /// The figures beside the thesis's Fig. 4.21, described in words (it gives no numbers).
    fn markdown(&self) -> String {
        let c = &self.config;
        let mut s = String::from(
            "## Time per frame along one path, Optimal against BOX (Shou 2002, Fig. 4.21)\n\n",
        );
        s.push_str(&format!(
            "One {} walk: {}, SF {}. Optimal: {}; BOX: {}. Every frame's time is in the CSV; the plot leaves out \
             frame 0 (the first cell, loaded cold).\n\n",
            c.walk.patterns.iter().map(|p| p.name()).collect::<Vec<_>>().join(", "),
            c.walk.describe(),
            num(c.walk.sf),
            describe_review(&c.review(Preset::Optimal)),
            describe_review(&c.review(Preset::Box))
        ));
        s.push_str(
            "| configuration | frame 0, ms | mean frame, ms | variance, ms² | longest frame, ms | frames over 50 ms | queries |\n\
             |---|---|---|---|---|---|---|\n",
        );
        for (p, sum) in PRESETS.iter().zip(&self.summaries) {
            let first = self.rows.first().map_or(0.0, |r| {
                if *p == Preset::Box {
                    r.box_ms
                } else {
                    r.optimal_ms
                }
            });
            s.push_str(&format!(
                "| {} | {:.1} | {:.3} | {:.3} | {:.1} | {} | {} |\n",
                label(*p),
                first,
                sum.mean_frame_ms,
                sum.frame_ms_variance,
                sum.max_frame_ms,
                sum.frames_over_50ms,
                sum.queries
            ));
        }
        s.push_str(
            "\nThe thesis (Fig. 4.21): along one recorded user path, Optimal's frame time is shorter than BOX's and \
             much smoother; BOX's jumps at each query, since it moves the whole cell's result into its scene graph \
             where complement search moves only what the new cell adds. It gives no numbers for the figure.\n",
        );
        s
    }
}
