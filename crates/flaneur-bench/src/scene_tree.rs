//! The `scene-tree` experiment (Shou 2002 §6.3, Table 6.1, Figs. 6.4, 6.5 and 6.7): the
//! memory HDoV scene tree walked along one path by CONV, VSC(η) at several thresholds
//! and PB(n) at several budgets: frame time, triangles drawn, nodes visited, and for PB
//! the frames within the budget.
//!
//! The tree is loaded once (every object with its stored levels, the k-D tree, the
//! internal LODs: its time is reported apart) and every walk runs over it unpaced, the
//! same path for all: a walk through the walkable viewcells at `speed` m/s. Frame time
//! is the walk's own (the VD update on a change of cell, the traversal, bringing the
//! object buffer to what it chose, culling), not drawing: the thesis's includes
//! rendering, where triangles are the cost; both are reported.

use std::path::Path;
use std::time::Instant;

use crate::report::Report;
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::path::cell_walk;
use flaneur::walk::scene::{SceneConfig, SceneReport, SceneTree, Traversal};
use flaneur::walk::{Frames, Playback, WalkState};

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SceneTreeConfig {
    pub frames: usize,
    pub fps: f32,
    /// The walker's speed, m/s.
    pub speed: f32,
    /// VSC's thresholds (Table 6.1's three by default).
    pub etas: Vec<f32>,
    /// PB's budgets, triangles (Fig. 6.7's by default).
    pub budgets: Vec<u64>,
    pub seed: u64,
    /// VSC's and PB's selection rule: ours (screen, the default) or the thesis's
    /// (Table 6.1's own), under the thesis's τ.
    pub selection: flaneur::hdov::Selection,
}

impl Default for SceneTreeConfig {
    fn default() -> Self {
        SceneTreeConfig {
            frames: 900,
            fps: 30.0,
            speed: 10.0,
            etas: vec![0.0001, 0.001, 0.01],
            budgets: vec![20_000, 40_000, 80_000],
            seed: 1,
            selection: flaneur::hdov::Selection::Screen,
        }
    }
}

impl SceneTreeConfig {
    /// Checks the settings, naming a bad one.
    pub fn validate(&self) -> Result<()> {
        if self.frames < 2 || !(self.fps > 0.0 && self.speed > 0.0) {
            return Err(Error::Invalid(format!(
                "scene-tree needs at least 2 frames and a positive fps and speed (got {}, {}, {})",
                self.frames, self.fps, self.speed
            )));
        }
        for t in self.traversals() {
            t.validate()?;
        }
        Ok(())
    }

    /// CONV, then VSC at each η, then PB at each budget.
    pub fn traversals(&self) -> Vec<Traversal> {
        let mut t = vec![Traversal::Conv];
        t.extend(self.etas.iter().map(|&eta| Traversal::Vsc { eta }));
        t.extend(self.budgets.iter().map(|&budget| Traversal::Pb { budget }));
        t
    }
}

/// One traversal's walk.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SceneRow {
    /// CONV, VSC(η) or PB(n).
    pub traversal: String,
    pub mean_frame_ms: f64,
    pub frame_ms_variance: f64,
    pub max_frame_ms: f64,
    pub mean_traverse_ms: f64,
    pub mean_triangles: f64,
    pub max_triangles: u64,
    pub mean_visited: f64,
    pub mean_drawn: f64,
    /// PB: the share of frames within the budget (1 otherwise).
    pub within_budget: f64,
    /// PB: frames whose traversal ran out of attempts and ended early.
    pub frames_ended: usize,
    /// PB: what the budget could not hold, in words.
    pub too_big: Option<String>,
}

/// What the experiment measured.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SceneTreeReport {
    pub config: SceneTreeConfig,
    pub objects: u64,
    pub nodes: usize,
    /// Loading the tree: objects, the k-D tree and its internal LODs, seconds.
    pub load_s: f64,
    pub rows: Vec<SceneRow>,
    /// Per walk: triangles and milliseconds of each frame.
    pub series: Vec<(String, Vec<(u64, f64)>)>,
}

/// Loads `db`'s scene tree and walks it under every traversal; `tick(done, total)`
/// after each walk.
pub fn run(
    db: &Database,
    cfg: &SceneTreeConfig,
    mut tick: impl FnMut(usize, usize),
) -> Result<SceneTreeReport> {
    cfg.validate()?;
    let path = cell_walk(db, cfg.frames, cfg.speed / cfg.fps, cfg.fps, cfg.seed)?;
    let t = Instant::now();
    let tree = SceneTree::load(db, &flaneur::progress::Silent)?;
    let load_s = t.elapsed().as_secs_f64();
    let nodes = tree.nodes.len();
    // One state, the tree loaded once, for every traversal: the walks draw nothing, so
    // no LOD selection runs and nothing but the tree passes from one walk to the next.
    let mut state = WalkState::new(db).with_scene_tree(tree);
    let traversals = cfg.traversals();
    let total = traversals.len();
    let mut rows = Vec::with_capacity(traversals.len());
    let mut series = Vec::new();
    for how in traversals {
        let sc = SceneConfig {
            selection: cfg.selection,
            ..SceneConfig::new(how)
        };
        let r: SceneReport = state
            .run(&sc.into(), &mut Playback::path(&path), Frames::Keep)?
            .try_into()?;
        let s = &r.summary;
        series.push((
            how.label(),
            r.frames.iter().map(|f| (f.triangles, f.frame_ms)).collect(),
        ));
        rows.push(SceneRow {
            traversal: how.label(),
            mean_frame_ms: s.mean_frame_ms,
            frame_ms_variance: s.frame_ms_variance,
            max_frame_ms: s.max_frame_ms,
            mean_traverse_ms: s.mean_traverse_ms,
            mean_triangles: s.mean_triangles,
            max_triangles: s.max_triangles,
            mean_visited: s.mean_visited,
            mean_drawn: s.mean_drawn,
            within_budget: r.within_budget(),
            frames_ended: s.frames_ended,
            too_big: r.too_big(),
        });
        tick(rows.len(), total);
    }
    Ok(SceneTreeReport {
        config: cfg.clone(),
        objects: db.objects(),
        nodes,
        load_s,
        rows,
        series,
    })
}

/// The plots' file names.
pub const PLOT_TRIANGLES: &str = "scene-tree-triangles.png";
pub const PLOT_FRAMES: &str = "scene-tree-frames.png";

impl SceneTreeReport {
    /// The row of traversal `label` (CONV, VSC(η), PB(n)).
    pub fn row(&self, label: &str) -> Option<&SceneRow> {
        self.rows.iter().find(|r| r.traversal == label)
    }
}

impl Report for SceneTreeReport {
    fn name(&self) -> &'static str {
        "scene-tree"
    }

    fn to_csv(&self) -> String {
        let mut s = String::from(
            "traversal,mean_frame_ms,frame_ms_variance,max_frame_ms,mean_traverse_ms,mean_triangles,max_triangles,mean_visited,mean_drawn,within_budget,frames_ended\n",
        );
        for r in &self.rows {
            s.push_str(&format!(
                "{},{:.4},{:.4},{:.3},{:.4},{:.0},{},{:.1},{:.1},{:.4},{}\n",
                r.traversal,
                r.mean_frame_ms,
                r.frame_ms_variance,
                r.max_frame_ms,
                r.mean_traverse_ms,
                r.mean_triangles,
                r.max_triangles,
                r.mean_visited,
                r.mean_drawn,
                r.within_budget,
                r.frames_ended
            ));
        }
        s
    }

    fn extra_csvs(&self) -> Vec<(&'static str, String)> {
        let mut s = String::from("traversal,frame,triangles,frame_ms\n");
        for (name, frames) in &self.series {
            for (i, (t, ms)) in frames.iter().enumerate() {
                s.push_str(&format!("{name},{i},{t},{ms:.4}\n"));
            }
        }
        vec![("scene-tree-frames.csv", s)]
    }

    fn markdown(&self) -> String {
        let c = &self.config;
        let mut s = format!(
            "# The memory HDoV scene tree: CONV, VSC and PB (Shou 2002 §6.3, Table 6.1, Fig. 6.7)\n\n\
             A walk of {} frames through the walkable viewcells of a city of {} objects at {} m/s \
             (seed {}), VSC and PB under the {} selection; the scene tree has {} nodes and took \
             {:.1} s to load. Frame time is the walk's own, not drawing; the thesis's includes \
             rendering.\n\n\
             | traversal | mean frame ms | variance | traversal ms | triangles a frame | most | nodes visited | nodes drawn | within budget | ended early |\n\
             |---|---|---|---|---|---|---|---|---|---|\n",
            c.frames,
            self.objects,
            c.speed,
            c.seed,
            c.selection.name(),
            self.nodes,
            self.load_s
        );
        for r in &self.rows {
            s.push_str(&format!(
                "| {} | {:.3} | {:.4} | {:.3} | {:.0} | {} | {:.1} | {:.1} | {:.1} % | {} |\n",
                r.traversal,
                r.mean_frame_ms,
                r.frame_ms_variance,
                r.mean_traverse_ms,
                r.mean_triangles,
                r.max_triangles,
                r.mean_visited,
                r.mean_drawn,
                r.within_budget * 100.0,
                r.frames_ended
            ));
        }
        for r in &self.rows {
            if let Some(t) = &r.too_big {
                s.push_str(&format!("\n{}: {t}.\n", r.traversal));
            }
        }
        if let (Some(conv), Some(vsc)) = (self.row("CONV"), self.row("VSC(0.001)")) {
            s.push_str(&format!(
                "\nVSC(0.001) against CONV: {:.1}× fewer triangles, frames {:.1}× faster to prepare. \
                 The thesis (Table 6.1): 13,210 against 136,004 triangles (10.3×), 18.23 ms against \
                 63.66 ms (3.5×).\n",
                conv.mean_triangles / vsc.mean_triangles.max(1.0),
                conv.mean_frame_ms / vsc.mean_frame_ms.max(1e-9)
            ));
            if let Some(pb) = self.row("PB(20000)") {
                s.push_str(&format!(
                    "PB(20000) against CONV: frames {:.1}× faster to prepare, {:.1}× fewer \
                     triangles. The thesis: 2.7× faster.\n",
                    conv.mean_frame_ms / pb.mean_frame_ms.max(1e-9),
                    conv.mean_triangles / pb.mean_triangles.max(1.0)
                ));
            }
        }
        s
    }

    fn plot(&self, dir: &Path) -> Result<()> {
        use crate::plot::{line_plot, LinePlot, Series};
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let series = |f: fn(&(u64, f64)) -> f64| -> Vec<Series> {
            self.series
                .iter()
                .map(|(name, frames)| Series {
                    name: name.clone(),
                    points: frames
                        .iter()
                        .enumerate()
                        .skip(1)
                        .map(|(i, x)| (i as f64, f(x)))
                        .collect(),
                })
                .collect()
        };
        line_plot(
            &dir.join(PLOT_TRIANGLES),
            &LinePlot {
                title: "Triangles drawn each frame (Figs. 6.4, 6.7)".into(),
                x_label: "frame".into(),
                y_label: "triangles".into(),
                series: series(|x| x.0 as f64),
            },
        )?;
        line_plot(
            &dir.join(PLOT_FRAMES),
            &LinePlot {
                title: "Frame time, the walk's own (Fig. 6.5)".into(),
                x_label: "frame".into(),
                y_label: "ms".into(),
                series: series(|x| x.1),
            },
        )
    }
}
