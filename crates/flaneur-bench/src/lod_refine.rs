//! The `lod-refine` experiment (Zheng 2007 §4.6, Tables 4.1 and 4.3, Fig. 4.11 and
//! 4.12): a landmark refined view-dependently along a scripted orbit by the three
//! traversals — priority-oriented, linear and constant-time — with the thesis's
//! settings (τ = 0.1 % of the viewport, N = 500, a budget of 60,000 triangles, §4.6.1).
//! Per frame: traversal and update time, triangles, front nodes, updates; every 5th
//! frame the accuracy of each traversal against the priority-oriented one (Fig. 4.12).
//!
//! The run itself is `lod_orbit::refine_orbit` on `lod_orbit::orbit_path`; this module builds the
//! landmark, times the build, and writes the figures out. The landmark (our choice) is
//! a procedural bumpy torus (`lod::bumpy_torus`) of the Happy Buddha's 1,087,474
//! triangles by default, the model of Table 4.1's last column; the thesis's scanned
//! models are not shipped. The view cone is 60° wide.
//!
//! τ is swept (our addition): the thesis's 0.1 % first, then finer. The bumpy torus is
//! smooth at the scale of its triangles, so at 0.1 % it asks for far fewer triangles
//! than the budget and few updates per frame; at 0.03 % its fronts and updates per frame
//! are about those of Table 4.1; at 0.02 % the view asks for about the budget (59,000
//! triangles on average with no budget, the thesis's figure), and at 0.01 % for more than
//! twice it, so the budget binds hard. The model and its DAG are built once.
//!
//! The linear traversal's accuracy against the priority-oriented one falls as τ asks for
//! more than N operators a frame and the budget allow: the two then choose different
//! nodes among more that need an operator than they may apply (the priority-oriented one
//! the largest errors, the linear one the first in its queue). The thesis's "about 70 %"
//! is at its operating point, where the view asks for about the budget; ours is 75 % there
//! without a budget and 61 % with it, and 32 % at 0.01 %, where the view asks for 2.4
//! times the budget (docs/lod.md).
//!
//! The constant-time traversal bounds the nodes it evaluates, so its time per frame
//! should sit in a narrow band: the summary gives its 95th over its 5th percentile, over
//! the whole path and over the orbit alone (after the approach, the first sixth of the
//! path, while the fronts still grow from the base mesh).

use std::path::Path;
use std::time::{Duration, Instant};

use glam::Vec3;

use crate::lod_orbit::{
    orbit_path, refine_orbit, OrbitConfig, OrbitFrame, OrbitReport, TraversalSummary,
};
use crate::report::Report;
use crate::walk_setup::{check_sweep, num};
use flaneur::error::{Error, Result};
use flaneur::lod::{bumpy_torus, Dag, DagConstruction, ProgressiveMesh, Traversal, THESIS_TAU};

/// The Happy Buddha's triangles (Zheng 2007 Table 3.1), the model of Table 4.1's figures.
pub const DEFAULT_TRIANGLES: usize = 1_087_474;
/// The thesis's first path has 180 frames (§4.6.2).
pub const DEFAULT_FRAMES: usize = 180;
/// The full angle of the view cone, degrees.
pub const DEFAULT_FOV_DEGREES: f32 = 60.0;

/// One traversal's row of Zheng 2007 Table 4.1 on the Happy Buddha (1,087,474
/// triangles) and its front at the 160th frame of the first path (Table 4.3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThesisTraversal {
    pub traversal: Traversal,
    /// T_trav, ms (on the server, a Pentium 4 at 3.6 GHz).
    pub traversal_ms: f64,
    /// T_upd, ms (on the client, a Pentium 4 at 1.6 GHz).
    pub update_ms: f64,
    /// Num. Triangles.
    pub triangles: usize,
    /// Num. Updates.
    pub updates: usize,
    /// Table 4.3: triangles at the 160th frame.
    pub triangles_160: usize,
    /// Table 4.3: front nodes at the 160th frame.
    pub front_nodes_160: usize,
}

/// Zheng 2007 Table 4.1 (Happy column) and Table 4.3 (Happy column), per traversal.
pub const THESIS_HAPPY: [ThesisTraversal; 3] = [
    ThesisTraversal {
        traversal: Traversal::Priority,
        traversal_ms: 10.9,
        update_ms: 5.4,
        triangles: 59_084,
        updates: 766,
        triangles_160: 59_618,
        front_nodes_160: 15_542,
    },
    ThesisTraversal {
        traversal: Traversal::Linear,
        traversal_ms: 5.2,
        update_ms: 5.5,
        triangles: 59_215,
        updates: 782,
        triangles_160: 58_709,
        front_nodes_160: 15_317,
    },
    ThesisTraversal {
        traversal: Traversal::ConstantTime,
        traversal_ms: 1.7,
        update_ms: 4.2,
        triangles: 59_742,
        updates: 584,
        triangles_160: 57_813,
        front_nodes_160: 15_102,
    },
];

/// The linear traversal's accuracy against the priority-oriented one, "about 70 %"
/// (§4.6.2, Fig. 4.12); the constant-time traversal's is "even lower", with no figure.
pub const THESIS_LINEAR_ACCURACY: f64 = 0.70;

/// The frame of Table 4.3 (the 160th, counted from 1).
pub const THESIS_FRONT_FRAME: usize = 160;

/// The τ values run by default, fractions of the viewport: the thesis's 0.1 %, then
/// 0.03 %, 0.02 % and 0.01 % (see the top comment).
pub const DEFAULT_TAUS: [f32; 4] = [THESIS_TAU, 0.0003, 0.0002, 0.0001];

/// The settings of the experiment.
#[derive(Clone, Debug, PartialEq)]
pub struct LodRefineConfig {
    /// Triangles of the bumpy torus (about: the torus rounds to its grid).
    pub triangles: usize,
    /// Views along the orbit.
    pub frames: usize,
    /// Full angle of the view cone, degrees.
    pub fov_degrees: f32,
    /// The τ values, one run of the three traversals each, in order.
    pub taus: Vec<f32>,
    /// N, the budget, the criteria and how often accuracy is measured: the thesis's by
    /// default. Its τ is not used: `taus` replaces it.
    pub orbit: OrbitConfig,
    /// Runs of each orbit: a frame's times are the shortest over the runs. The runs make
    /// the same operators frame by frame (checked), so what differs between them is the
    /// machine's noise — at tenths of a millisecond a frame, a scheduler tick or a cache
    /// flush is as long as the traversal itself.
    pub repeats: usize,
}

impl Default for LodRefineConfig {
    fn default() -> LodRefineConfig {
        LodRefineConfig {
            triangles: DEFAULT_TRIANGLES,
            frames: DEFAULT_FRAMES,
            fov_degrees: DEFAULT_FOV_DEGREES,
            taus: DEFAULT_TAUS.to_vec(),
            orbit: OrbitConfig::default(),
            repeats: 3,
        }
    }
}

impl LodRefineConfig {
    /// Checks the frames, the view cone and the τ sweep; N is checked by the refiner.
    pub fn validate(&self) -> Result<()> {
        if self.frames == 0 {
            return Err(Error::Invalid("lod-refine: no frames".into()));
        }
        if self.repeats == 0 {
            return Err(Error::Invalid(
                "lod-refine: repeats must be at least 1".into(),
            ));
        }
        if !(self.fov_degrees > 0.0 && self.fov_degrees < 180.0) {
            return Err(Error::Invalid(format!(
                "lod-refine: a view cone of {}°; it must be within (0°, 180°)",
                self.fov_degrees
            )));
        }
        check_sweep("τ", &self.taus, |tau| {
            if tau.is_finite() && tau > 0.0 {
                Ok(())
            } else {
                Err(Error::Invalid(format!(
                    "lod-refine: τ = {tau} must be a positive fraction of the viewport"
                )))
            }
        })
    }
}

/// Takes into `best` each frame's shorter traversal and update times from `other`, a
/// run of the same orbit; an error if the runs did not select the same meshes.
fn keep_fastest(best: &mut OrbitReport, other: &OrbitReport) -> Result<()> {
    for (i, (b, o)) in best.frames.iter_mut().zip(&other.frames).enumerate() {
        for (bs, os) in b.stats.iter_mut().zip(&o.stats) {
            if (bs.triangles, bs.updates()) != (os.triangles, os.updates()) {
                return Err(Error::Invalid(format!(
                    "lod-refine: two runs of the orbit differ at frame {i}"
                )));
            }
            bs.traversal = bs.traversal.min(os.traversal);
            bs.update = bs.update.min(os.update);
        }
    }
    Ok(())
}

/// The three traversals along the orbit at one τ.
#[derive(Clone, Debug)]
pub struct TauRun {
    /// τ, a fraction of the viewport.
    pub tau: f32,
    /// The run, frame by frame.
    pub orbit: OrbitReport,
}

/// The result of [`run`].
#[derive(Clone, Debug)]
pub struct LodRefineReport {
    pub config: LodRefineConfig,
    /// The full model's triangles.
    pub model_triangles: usize,
    /// The base mesh's triangles, where every traversal starts.
    pub base_triangles: usize,
    /// DAG nodes (mini-redundant).
    pub dag_nodes: usize,
    /// Time to build the progressive mesh.
    pub pm_build: Duration,
    /// Time to build the mini-redundant DAG with its attributes.
    pub dag_build: Duration,
    /// One run per τ, in the order of the config.
    pub runs: Vec<TauRun>,
}

/// Runs the experiment: builds the landmark, its progressive mesh and its
/// mini-redundant DAG, then refines it along the orbit with each traversal, once per τ.
pub fn run(cfg: &LodRefineConfig) -> Result<LodRefineReport> {
    cfg.validate()?;
    let mesh = bumpy_torus(cfg.triangles);
    let started = Instant::now();
    let pm = ProgressiveMesh::build(&mesh)?;
    let pm_build = started.elapsed();
    let started = Instant::now();
    let dag = Dag::build(&pm, DagConstruction::MiniRedundant)?;
    let dag_build = started.elapsed();
    let (lo, hi) = mesh.bounds();
    let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
    let views = orbit_path(
        (lo + hi) * 0.5,
        (hi - lo).length() * 0.5,
        cfg.frames,
        cfg.fov_degrees.to_radians(),
    )?;
    let runs = cfg
        .taus
        .iter()
        .map(|&tau| {
            let config = OrbitConfig { tau, ..cfg.orbit };
            let mut orbit = refine_orbit(&pm, &dag, &views, &config)?;
            for _ in 1..cfg.repeats {
                keep_fastest(&mut orbit, &refine_orbit(&pm, &dag, &views, &config)?)?;
            }
            Ok(TauRun { tau, orbit })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(LodRefineReport {
        config: cfg.clone(),
        model_triangles: mesh.triangle_count(),
        base_triangles: pm.base.triangle_count(),
        dag_nodes: dag.node_count(),
        pm_build,
        dag_build,
        runs,
    })
}

/// What [`LodRefineReport::plot`] draws, per τ: Fig. 4.11, Fig. 4.12, and the triangles.
pub const PLOTS: [&str; 3] = ["traversal-time", "accuracy", "triangles"];

/// The file of plot `what` (one of [`PLOTS`]) at `tau`, e.g.
/// `lod-refine-accuracy-tau-0.1pc.png` for τ = 0.1 %.
pub fn plot_file(what: &str, tau: f32) -> String {
    format!("lod-refine-{what}-tau-{}pc.png", num(100.0 * tau))
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

impl TauRun {
    /// Each traversal's averages over the whole path, in the order of
    /// [`Traversal::ALL`].
    pub fn summaries(&self) -> [TraversalSummary; 3] {
        Traversal::ALL.map(|t| self.orbit.summary(t))
    }

    /// The first frame of the orbit proper: `orbit_path` spends the first sixth of the
    /// path approaching.
    pub fn orbit_start(&self) -> usize {
        self.orbit.frames.len() / 6
    }

    /// Each traversal's averages over the orbit alone, after the approach.
    pub fn orbit_summaries(&self) -> [TraversalSummary; 3] {
        let settled = OrbitReport {
            frames: self.orbit.frames[self.orbit_start()..].to_vec(),
            ..self.orbit.clone()
        };
        Traversal::ALL.map(|t| settled.summary(t))
    }

    /// One series per traversal in `which` (indices into [`Traversal::ALL`]): `by` of
    /// each frame where it gives a value.
    fn series(
        &self,
        which: &[usize],
        by: impl Fn(usize, &OrbitFrame) -> Option<f64>,
    ) -> Vec<crate::plot::Series> {
        which
            .iter()
            .map(|&i| crate::plot::Series {
                name: Traversal::ALL[i].name().into(),
                points: self
                    .orbit
                    .frames
                    .iter()
                    .enumerate()
                    .filter_map(|(f, fr)| by(i, fr).map(|y| (f as f64, y)))
                    .collect(),
            })
            .collect()
    }

    /// This τ's section of the summary: Tables 4.1 and 4.3 and the time bands.
    fn markdown(&self, budget: Option<usize>) -> String {
        let mut s = format!("## τ = {} % of the viewport\n\n", num(100.0 * self.tau));
        s.push_str(
            "Means per frame (Table 4.1; \"thesis\": its Happy column):\n\n\
             | traversal | T_trav ms | thesis | median | T_upd ms | thesis | triangles | thesis | max triangles | \
             updates | thesis | front nodes | accuracy | thesis |\n\
             |---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        );
        for (sm, th) in self.summaries().iter().zip(&THESIS_HAPPY) {
            let thesis_accuracy = match th.traversal {
                Traversal::Priority => "100 %".to_string(),
                Traversal::Linear => format!("about {:.0} %", 100.0 * THESIS_LINEAR_ACCURACY),
                Traversal::ConstantTime => "below linear".to_string(),
            };
            s.push_str(&format!(
                "| {} | {:.3} | {} | {:.3} | {:.3} | {} | {:.0} | {} | {} | {:.0} | {} | {:.0} | {:.1} % | {} |\n",
                th.traversal.name(),
                sm.traversal_ms,
                th.traversal_ms,
                sm.traversal_ms_median,
                sm.update_ms,
                th.update_ms,
                sm.triangles,
                th.triangles,
                sm.max_triangles,
                sm.updates,
                th.updates,
                sm.front_nodes,
                100.0 * sm.accuracy,
                thesis_accuracy,
            ));
        }
        let frame = (THESIS_FRONT_FRAME - 1).min(self.orbit.frames.len().saturating_sub(1));
        s.push_str(&format!(
            "\nFront at frame {} (Table 4.3: the 160th frame; the thesis finds the fronts always about 1/4 to 1/3 \
             of the triangles):\n\n\
             | traversal | triangles | thesis | front nodes | thesis | front / triangles | thesis |\n\
             |---|---|---|---|---|---|---|\n",
            frame + 1
        ));
        for (i, th) in THESIS_HAPPY.iter().enumerate() {
            let Some(st) = self.orbit.frames.get(frame).map(|f| &f.stats[i]) else {
                break;
            };
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} | {:.2} | {:.2} |\n",
                th.traversal.name(),
                st.triangles,
                th.triangles_160,
                st.front_nodes(),
                th.front_nodes_160,
                st.front_nodes() as f64 / st.triangles.max(1) as f64,
                th.front_nodes_160 as f64 / th.triangles_160 as f64,
            ));
        }
        s.push_str(
            "\nTraversal time per frame, ms (p5 – median – p95, and p95 / p5; the constant-time traversal's N bounds \
             the nodes each of its two passes evaluates, so up to 2N a frame):\n\n| traversal | whole path | p95 / p5 | orbit only | p95 / p5 | most evaluated in a pass |\n\
             |---|---|---|---|---|---|\n",
        );
        for (all, orbit) in self.summaries().iter().zip(self.orbit_summaries()) {
            let band = |t: &TraversalSummary| {
                (
                    format!(
                        "{:.3} – {:.3} – {:.3}",
                        t.traversal_ms_p5_p95.0, t.traversal_ms_median, t.traversal_ms_p5_p95.1
                    ),
                    t.traversal_ms_p5_p95.1 / t.traversal_ms_p5_p95.0.max(1e-9),
                )
            };
            let (a, ar) = band(all);
            let (b, br) = band(&orbit);
            s.push_str(&format!(
                "| {} | {a} | {ar:.2}× | {b} | {br:.2}× | {} |\n",
                all.traversal.name(),
                all.max_evaluated_per_pass
            ));
        }
        let over: Vec<&str> = self
            .summaries()
            .iter()
            .filter(|t| budget.is_some_and(|b| t.max_triangles > b))
            .map(|t| t.traversal.name())
            .collect();
        s.push_str(&match budget {
            Some(b) if over.is_empty() => {
                format!("\nNo traversal went over the budget of {b} triangles in any frame.\n\n")
            }
            Some(b) => format!(
                "\nOver the budget of {b} triangles in some frame: {}.\n\n",
                over.join(", ")
            ),
            None => "\nNo budget (fidelity alone).\n\n".to_string(),
        });
        s
    }
}

impl Report for LodRefineReport {
    fn name(&self) -> &'static str {
        "lod-refine"
    }

    /// One line per τ, frame and traversal; the accuracy only on the frames it was
    /// measured.
    fn to_csv(&self) -> String {
        let mut s = String::from(
            "tau,frame,traversal,traversal_ms,update_ms,triangles,front_nodes,updates,evaluated,accuracy\n",
        );
        for r in &self.runs {
            for (f, frame) in r.orbit.frames.iter().enumerate() {
                for (i, t) in Traversal::ALL.iter().enumerate() {
                    let st = &frame.stats[i];
                    s.push_str(&format!(
                        "{},{f},{},{:.4},{:.4},{},{},{},{},{}\n",
                        r.tau,
                        t.name(),
                        ms(st.traversal),
                        ms(st.update),
                        st.triangles,
                        st.front_nodes(),
                        st.updates(),
                        st.evaluated(),
                        frame
                            .accuracy
                            .map_or(String::new(), |a| format!("{:.4}", a[i])),
                    ));
                }
            }
        }
        s
    }

    /// Per τ: Fig. 4.11 (traversal time per frame, the three traversals), Fig. 4.12
    /// (accuracy against the priority-oriented traversal on the measured frames) and
    /// the triangles per frame, into `dir` (created if missing) as [`plot_file`] names
    /// them.
    fn plot(&self, dir: &Path) -> Result<()> {
        use super::plot::{line_plot, LinePlot};
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        for r in &self.runs {
            let on = format!(
                "{}-triangle torus, τ = {} %",
                self.model_triangles,
                num(100.0 * r.tau)
            );
            let [time, accuracy, triangles] = PLOTS.map(|what| dir.join(plot_file(what, r.tau)));
            line_plot(
                &time,
                &LinePlot {
                    title: format!("Traversal time per frame ({on})"),
                    x_label: "frame".into(),
                    y_label: "traversal time (ms)".into(),
                    series: r.series(&[0, 1, 2], |i, fr| Some(ms(fr.stats[i].traversal))),
                },
            )?;
            line_plot(
                &accuracy,
                &LinePlot {
                    title: format!("Accuracy against priority ({on})"),
                    x_label: "frame".into(),
                    y_label: "accuracy (%)".into(),
                    // Priority, the reference, is the 100 % line; kept so that each
                    // traversal has the same colour in every plot.
                    series: r.series(&[0, 1, 2], |i, fr| fr.accuracy.map(|a| 100.0 * a[i])),
                },
            )?;
            line_plot(
                &triangles,
                &LinePlot {
                    title: format!("Triangles per frame ({on})"),
                    x_label: "frame".into(),
                    y_label: "triangles".into(),
                    series: r.series(&[0, 1, 2], |i, fr| Some(fr.stats[i].triangles as f64)),
                },
            )?;
        }
        Ok(())
    }

    /// Our figures beside Tables 4.1 and 4.3 of the thesis, one section per τ.
    fn markdown(&self) -> String {
        let c = &self.config;
        let o = &c.orbit;
        let mut s = String::from(
            "# lod-refine — priority, linear and constant-time traversals (Zheng 2007 Table 4.1, 4.3, Fig. 4.11, 4.12)\n\n",
        );
        s.push_str(&format!(
            "A bumpy torus of {} triangles (base mesh {}, {} DAG nodes; progressive mesh built in {:.1} s, \
             mini-redundant DAG in {:.1} s), {} frames of the scripted orbit (a sixth approaching, then once round), \
             a {}° view cone; N = {}, budget {}; accuracy every {} frames; τ = {} % of the viewport; each frame's times \
             the shortest of {} runs. The thesis: \
             the Happy Buddha (1,087,474 triangles), 180 frames, τ = 0.1 %, N = 500, budget 60,000.\n\n",
            self.model_triangles,
            self.base_triangles,
            self.dag_nodes,
            self.pm_build.as_secs_f64(),
            self.dag_build.as_secs_f64(),
            c.frames,
            c.fov_degrees,
            o.max_work,
            o.budget.map_or("none".to_string(), |b| b.to_string()),
            o.accuracy_every,
            c.taus
                .iter()
                .map(|&t| num(100.0 * t))
                .collect::<Vec<_>>()
                .join(", "),
            c.repeats,
        ));
        for r in &self.runs {
            s.push_str(&r.markdown(o.budget));
        }
        s.push_str(
            "The thesis's times are from 2007 hardware (traversal on a Pentium 4 at 3.6 GHz, updates on one at \
             1.6 GHz); compare the ratios between the traversals rather than the milliseconds. Accuracy is the share \
             of the priority-oriented traversal's triangles that a traversal also selects (Fig. 4.12). The thesis's \
             runs keep about 59,000 of the 60,000-triangle budget: the τ at which ours does too is the one to set \
             beside Table 4.1.\n",
        );
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_torus_keeps_the_budget_and_priority_is_its_own_reference() {
        let mut cfg = LodRefineConfig {
            triangles: 20_000,
            frames: 12,
            taus: vec![THESIS_TAU, 0.0001],
            repeats: 2,
            ..LodRefineConfig::default()
        };
        // Small enough that the finer τ reaches it.
        cfg.orbit.budget = Some(4_000);
        cfg.orbit.max_work = 200;
        let r = run(&cfg).unwrap();
        assert_eq!(r.runs.len(), 2);
        // Runs that selected different meshes are not merged.
        let mut best = r.runs[0].orbit.clone();
        let mut other = best.clone();
        other.frames[3].stats[1].triangles += 1;
        let e = keep_fastest(&mut best, &other).unwrap_err().to_string();
        assert!(e.contains("frame 3"), "{e}");
        let budget = cfg.orbit.budget.unwrap();
        for run in &r.runs {
            assert_eq!(run.orbit.frames.len(), 12);
            for frame in &run.orbit.frames {
                assert!(frame.stats.iter().all(|s| s.triangles <= budget));
            }
            let measured: Vec<[f64; 3]> =
                run.orbit.frames.iter().filter_map(|f| f.accuracy).collect();
            assert_eq!(measured.len(), 12_usize.div_ceil(cfg.orbit.accuracy_every));
            for a in &measured {
                assert_eq!(a[0], 1.0);
                assert!(a.iter().all(|x| (0.0..=1.0).contains(x)));
            }
            let summaries = run.summaries();
            assert!(summaries.iter().all(|s| s.max_triangles <= budget));
            assert_eq!(summaries[0].accuracy, 1.0);
        }
        // The budget is reached, so the check above is not empty.
        assert!(r.runs[1].summaries()[0].max_triangles > budget * 3 / 4);
        assert_eq!(r.to_csv().lines().count(), 1 + 2 * 3 * 12);
        let md = r.markdown();
        assert_eq!(md.matches("No traversal went over the budget").count(), 2);
        let dir = tempfile::tempdir().unwrap();
        r.plot(dir.path()).unwrap();
        for tau in &cfg.taus {
            for what in PLOTS {
                let f = plot_file(what, *tau);
                assert!(dir.path().join(&f).exists(), "{f}");
            }
        }
        assert_eq!(
            plot_file("accuracy", 0.001),
            "lod-refine-accuracy-tau-0.1pc.png"
        );
    }

    #[test]
    fn settings_are_checked() {
        let d = LodRefineConfig::default();
        assert!(d.validate().is_ok());
        let bad = |cfg: LodRefineConfig| matches!(run(&cfg), Err(Error::Invalid(_)));
        assert!(bad(LodRefineConfig {
            frames: 0,
            ..d.clone()
        }));
        assert!(bad(LodRefineConfig {
            repeats: 0,
            ..d.clone()
        }));
        assert!(bad(LodRefineConfig {
            fov_degrees: 180.0,
            ..d.clone()
        }));
        assert!(bad(LodRefineConfig {
            taus: vec![],
            ..d.clone()
        }));
        assert!(bad(LodRefineConfig {
            taus: vec![0.001, 0.0],
            ..d
        }));
    }
}
