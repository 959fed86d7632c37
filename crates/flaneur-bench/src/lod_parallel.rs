//! The `lod-parallel` experiment (El-Sana & Varshney, Tables 1 and 2): the time to build
//! one large mesh's progressive mesh on 1, 2, … threads, the speed-up, and the load
//! balance between the threads; beside it, the serial build of the same mesh, and the
//! throughput of building many city objects' progressive meshes on one core and on all.
//!
//! Approach, named: the large meshes are procedural bumpy tori (`lod::bumpy_torus`), the
//! papers' scanned models not being at hand; each build runs in a rayon pool of exactly
//! the threads named, and each time is the median of `repeats` builds. The parallel
//! builds at every thread count must give the same progressive mesh (the module
//! promises it); the experiment checks that and fails if not. The serial build is
//! `ProgressiveMesh::build` in a one-thread pool: its single global heap against the
//! octree's cells, on the same core.

use std::path::Path;
use std::time::{Duration, Instant};

use citygen::{CityConfig, Mesh};

use crate::report::Report;
use flaneur::error::{Error, Result};
use flaneur::lod::{bumpy_torus, simplify_all, ParallelOptions, ParallelReport, ProgressiveMesh};

/// El-Sana & Varshney Table 1: model, triangles, seconds on 1, 2, 4, 8, 16 processors
/// (SGI Power Challenge, R10000).
pub const PAPER_TABLE_1: [(&str, usize, [f64; 5]); 6] = [
    ("Dragon", 202_520, [18.90, 12.21, 7.03, 4.67, 2.20]),
    ("Buddha", 293_520, [26.53, 16.89, 9.37, 5.94, 3.39]),
    ("Submarine", 339_444, [23.16, 14.96, 8.44, 4.45, 2.54]),
    ("Steve", 739_639, [75.19, 43.13, 24.41, 15.74, 8.33]),
    ("David", 1_172_699, [122.47, 72.01, 38.54, 24.32, 15.04]),
    ("Colon", 1_814_364, [48.84, 30.04, 15.95, 8.70, 5.99]),
];

/// The processor counts of [`PAPER_TABLE_1`]'s columns.
pub const PAPER_PROCESSORS: [usize; 5] = [1, 2, 4, 8, 16];

/// El-Sana & Varshney Table 2 (Steve): load imbalance, max / mean − 1, by processors.
pub const PAPER_TABLE_2: [(usize, f64); 5] = [
    (1, 0.0),
    (2, 0.0008),
    (4, 0.0049),
    (8, 0.0740),
    (16, 0.0382),
];

/// The PNG the experiment draws.
pub const PLOT_FILE: &str = "lod-parallel-speedup.png";

/// The settings of the experiment.
#[derive(Clone, Debug)]
pub struct LodParallelConfig {
    /// Triangles of each large mesh.
    pub triangles: Vec<usize>,
    /// Thread counts, in order; the first is the speed-ups' base.
    pub threads: Vec<usize>,
    /// Builds per measurement; the median counts.
    pub repeats: usize,
    /// City objects for the throughput rows (0: none).
    pub objects: u64,
    /// How the parallel build splits a mesh.
    pub options: ParallelOptions,
}

impl Default for LodParallelConfig {
    fn default() -> LodParallelConfig {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        LodParallelConfig {
            triangles: vec![250_000, 1_000_000],
            threads: if cores > 1 { vec![1, cores] } else { vec![1] },
            repeats: 3,
            objects: 2_000,
            options: ParallelOptions::default(),
        }
    }
}

impl LodParallelConfig {
    /// A clear error for settings the experiment cannot run.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: String| Err(Error::Invalid(format!("lod-parallel: {what}")));
        if self.triangles.is_empty() || self.triangles.iter().any(|&t| t < 1_000) {
            return bad(format!(
                "meshes need at least 1,000 triangles each, got {:?}",
                self.triangles
            ));
        }
        if self.threads.is_empty() || self.threads.iter().any(|&t| t == 0 || t > 1024) {
            return bad(format!(
                "thread counts must be 1 to 1024, got {:?}",
                self.threads
            ));
        }
        if self.repeats == 0 {
            return bad("repeats must be at least 1".into());
        }
        if self.options.leaf_triangles == 0
            || !(self.options.reach > 0.0 && self.options.reach <= 1.0)
        {
            return bad(format!(
                "leaf triangles must be positive and reach in (0, 1], got {} and {}",
                self.options.leaf_triangles, self.options.reach
            ));
        }
        Ok(())
    }
}

/// One thread count's builds of one mesh.
#[derive(Clone, Debug)]
pub struct ThreadRun {
    pub threads: usize,
    /// Median wall time.
    pub seconds: f64,
    /// The report of the median build.
    pub report: ParallelReport,
}

/// One large mesh.
#[derive(Clone, Debug)]
pub struct ModelRow {
    pub triangles: usize,
    /// Median time of the serial build on one thread.
    pub serial_seconds: f64,
    /// Triangles of the serial build's base mesh, and of the parallel build's.
    pub serial_base: usize,
    pub parallel_base: usize,
    pub runs: Vec<ThreadRun>,
}

/// Many small objects' progressive meshes (`simplify_all`) on some threads.
#[derive(Clone, Debug)]
pub struct ThroughputRow {
    pub threads: usize,
    pub objects: u64,
    pub triangles: u64,
    pub seconds: f64,
}

impl ThroughputRow {
    pub fn triangles_per_second(&self) -> f64 {
        self.triangles as f64 / self.seconds.max(1e-12)
    }
}

/// What the experiment measured.
#[derive(Clone, Debug)]
pub struct LodParallelReport {
    pub config: LodParallelConfig,
    pub models: Vec<ModelRow>,
    pub throughput: Vec<ThroughputRow>,
}

/// Runs the experiment; `progress` hears (steps done, steps in all) after each step.
pub fn run(
    cfg: &LodParallelConfig,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<LodParallelReport> {
    cfg.validate()?;
    let threads = cfg.threads.len();
    let total = cfg.triangles.len() * (1 + threads) + if cfg.objects > 0 { threads } else { 0 };
    let mut done = 0;
    let mut step = || {
        done += 1;
        progress(done, total)
    };
    let mut models = Vec::new();
    for &n in &cfg.triangles {
        let mesh = bumpy_torus(n);
        let one = pool(1)?;
        let (serial_seconds, serial) = median_of(cfg.repeats, || {
            one.install(|| ProgressiveMesh::build(&mesh))
        })?;
        step();
        let mut runs = Vec::new();
        let mut first: Option<ProgressiveMesh> = None;
        for &threads in &cfg.threads {
            let pool = pool(threads)?;
            let (seconds, (pm, report)) = median_of(cfg.repeats, || {
                pool.install(|| ProgressiveMesh::build_parallel(&mesh, &cfg.options))
            })?;
            step();
            match &first {
                None => first = Some(pm),
                Some(f) if *f != pm => {
                    return Err(Error::Invalid(format!(
                        "lod-parallel: the build on {threads} threads differs from the build on {}",
                        cfg.threads[0]
                    )))
                }
                Some(_) => {}
            }
            runs.push(ThreadRun {
                threads,
                seconds,
                report,
            });
        }
        models.push(ModelRow {
            triangles: mesh.triangle_count(),
            serial_seconds,
            serial_base: serial.base.triangle_count(),
            parallel_base: first.map_or(0, |pm| pm.base.triangle_count()),
            runs,
        });
    }

    let mut throughput = Vec::new();
    if cfg.objects > 0 {
        let city = CityConfig {
            objects: cfg.objects,
            ..Default::default()
        };
        let meshes: Vec<Mesh> = (0..cfg.objects)
            .map(|id| citygen::object(&city, id).map(|o| o.mesh))
            .collect::<std::result::Result<_, _>>()?;
        let triangles = meshes.iter().map(|m| m.triangle_count() as u64).sum();
        for &threads in &cfg.threads {
            let pool = pool(threads)?;
            let (seconds, _) = median_of(cfg.repeats, || pool.install(|| simplify_all(&meshes)))?;
            step();
            throughput.push(ThroughputRow {
                threads,
                objects: cfg.objects,
                triangles,
                seconds,
            });
        }
    }
    Ok(LodParallelReport {
        config: cfg.clone(),
        models,
        throughput,
    })
}

/// A rayon pool of exactly `threads` threads, made before any timing starts.
fn pool(threads: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::Invalid(format!("lod-parallel: no pool of {threads} threads: {e}")))
}

/// Runs `f` `repeats` times; the median time, with the output of the run that took it.
fn median_of<T>(repeats: usize, mut f: impl FnMut() -> Result<T>) -> Result<(f64, T)> {
    let mut runs: Vec<(Duration, T)> = Vec::with_capacity(repeats);
    for _ in 0..repeats.max(1) {
        let started = Instant::now();
        let out = f()?;
        runs.push((started.elapsed(), out));
    }
    runs.sort_by_key(|r| r.0);
    let (t, out) = runs.swap_remove(runs.len() / 2);
    Ok((t.as_secs_f64(), out))
}

/// The threads' busy times: least, most and mean, in seconds.
fn busy_spread(report: &ParallelReport) -> (f64, f64, f64) {
    let busy: Vec<f64> = report.busy.iter().map(Duration::as_secs_f64).collect();
    let min = busy.iter().copied().fold(f64::MAX, f64::min);
    let max = busy.iter().copied().fold(0.0, f64::max);
    (
        min,
        max,
        busy.iter().sum::<f64>() / busy.len().max(1) as f64,
    )
}

impl ModelRow {
    /// The speed-up of `run` over the first thread count's run.
    pub fn speedup(&self, run: &ThreadRun) -> f64 {
        self.runs[0].seconds / run.seconds.max(1e-12)
    }
}

/// The paper's mean 2-processor speed-up over its six models, and its range.
pub fn paper_two_processor_speedup() -> (f64, f64, f64) {
    let s: Vec<f64> = PAPER_TABLE_1.iter().map(|m| m.2[0] / m.2[1]).collect();
    let mean = s.iter().sum::<f64>() / s.len() as f64;
    let (lo, hi) = s
        .iter()
        .fold((f64::MAX, f64::MIN), |(lo, hi), &x| (lo.min(x), hi.max(x)));
    (mean, lo, hi)
}

impl Report for LodParallelReport {
    fn name(&self) -> &'static str {
        "lod-parallel"
    }

    /// One row per mesh and thread count, then one per throughput run.
    fn to_csv(&self) -> String {
        let mut s = String::from(
            "kind,triangles,threads,seconds,speedup,serial_seconds,speedup_over_serial,busy_min_s,busy_max_s,busy_mean_s,imbalance,depth,leaf_cells,triangles_per_s\n",
        );
        for m in &self.models {
            for r in &m.runs {
                let (min, max, mean) = busy_spread(&r.report);
                s.push_str(&format!(
                    "mesh,{},{},{:.4},{:.3},{:.4},{:.3},{:.4},{:.4},{:.4},{:.4},{},{},{:.0}\n",
                    m.triangles,
                    r.threads,
                    r.seconds,
                    m.speedup(r),
                    m.serial_seconds,
                    m.serial_seconds / r.seconds.max(1e-12),
                    min,
                    max,
                    mean,
                    r.report.imbalance(),
                    r.report.depth,
                    r.report.levels.first().map_or(0, |l| l.cells),
                    m.triangles as f64 / r.seconds.max(1e-12),
                ));
            }
        }
        for t in &self.throughput {
            s.push_str(&format!(
                "objects,{},{},{:.4},,,,,,,,,,{:.0}\n",
                t.triangles,
                t.threads,
                t.seconds,
                t.triangles_per_second()
            ));
        }
        s
    }

    /// The tables, beside the paper's.
    fn markdown(&self) -> String {
        let c = &self.config;
        let mut s = String::from(
            "# lod-parallel — one large mesh's progressive mesh on several threads (El-Sana & Varshney, Tables 1–2)\n\n",
        );
        s.push_str(&format!(
            "Bumpy tori; octree leaves of at most {} triangles on average, reach {} of a cell's side; median of {} builds each.\n\n",
            c.options.leaf_triangles, c.options.reach, c.repeats
        ));
        s.push_str("| triangles | threads | time (s) | speed-up | over serial | busy min / max (s) | imbalance | depth | leaf cells | base triangles |\n|---|---|---|---|---|---|---|---|---|---|\n");
        for m in &self.models {
            s.push_str(&format!(
                "| {} | serial | {:.2} | — | 1.00 | — | — | — | — | {} |\n",
                m.triangles, m.serial_seconds, m.serial_base
            ));
            for r in &m.runs {
                let (min, max, _) = busy_spread(&r.report);
                s.push_str(&format!(
                    "| {} | {} | {:.2} | {:.2}× | {:.2}× | {:.2} / {:.2} | {:.3} | {} | {} | {} |\n",
                    m.triangles,
                    r.threads,
                    r.seconds,
                    m.speedup(r),
                    m.serial_seconds / r.seconds.max(1e-12),
                    min,
                    max,
                    r.report.imbalance(),
                    r.report.depth,
                    r.report.levels.first().map_or(0, |l| l.cells),
                    m.parallel_base
                ));
            }
        }
        let (mean, lo, hi) = paper_two_processor_speedup();
        s.push_str(&format!(
            "\nThe paper (Table 1): on 2 processors {lo:.2}–{hi:.2}× (mean {mean:.2}×) over 1, on models of 0.2–1.8M triangles; load imbalance on 2 processors 0.0008 (Table 2, Steve).\n"
        ));
        if !self.throughput.is_empty() {
            s.push_str("\n## Many objects (`simplify_all`): progressive meshes of city objects\n\n| objects | triangles | threads | time (s) | triangles/s |\n|---|---|---|---|---|\n");
            for t in &self.throughput {
                s.push_str(&format!(
                    "| {} | {} | {} | {:.2} | {:.0} |\n",
                    t.objects,
                    t.triangles,
                    t.threads,
                    t.seconds,
                    t.triangles_per_second()
                ));
            }
        }
        s
    }

    /// Speed-up against threads, ours per mesh and the paper's per model.
    fn plot(&self, dir: &Path) -> Result<()> {
        use super::plot::{line_plot, LinePlot, Series};
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let mut series: Vec<Series> = self
            .models
            .iter()
            .map(|m| Series {
                name: format!("torus {}k triangles", m.triangles / 1000),
                points: m
                    .runs
                    .iter()
                    .map(|r| (r.threads as f64, m.speedup(r)))
                    .collect(),
            })
            .collect();
        let max_threads = self.config.threads.iter().copied().max().unwrap_or(1);
        for (name, _, t) in PAPER_TABLE_1
            .iter()
            .filter(|m| m.0 == "Dragon" || m.0 == "David")
        {
            series.push(Series {
                name: format!("paper: {name}"),
                points: PAPER_PROCESSORS
                    .iter()
                    .zip(t)
                    .filter(|(p, _)| **p <= max_threads.max(2))
                    .map(|(&p, &secs)| (p as f64, t[0] / secs))
                    .collect(),
            });
        }
        line_plot(
            &dir.join(PLOT_FILE),
            &LinePlot {
                title: "Parallel progressive-mesh build: speed-up against threads".into(),
                x_label: "threads (processors)".into(),
                y_label: "speed-up over one".into(),
                series,
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_run_reports_every_thread_count_and_agrees() {
        let cfg = LodParallelConfig {
            triangles: vec![20_000],
            threads: vec![1, 2],
            repeats: 1,
            objects: 20,
            options: ParallelOptions {
                leaf_triangles: 1_000,
                ..Default::default()
            },
        };
        let mut steps = Vec::new();
        let r = run(&cfg, &mut |done, total| steps.push((done, total))).unwrap();
        assert_eq!(steps, (1..=5).map(|d| (d, 5)).collect::<Vec<_>>());
        assert_eq!(r.models.len(), 1);
        let m = &r.models[0];
        assert_eq!(m.runs.len(), 2);
        assert!(m.runs[1].report.depth >= 1);
        assert_eq!(m.runs[1].report.busy.len(), 2);
        assert!((m.speedup(&m.runs[0]) - 1.0).abs() < 1e-12);
        assert_eq!(r.throughput.len(), 2);
        assert!(r.throughput[0].triangles > 0);
        let csv = r.to_csv();
        assert_eq!(csv.lines().count(), 1 + 2 + 2);
        assert!(r.markdown().contains(&format!("| {} | 2 |", m.triangles)));
        let dir = tempfile::tempdir().unwrap();
        r.plot(dir.path()).unwrap();
        assert!(dir.path().join(PLOT_FILE).exists());
    }

    #[test]
    fn bad_settings_are_named() {
        let mut cfg = LodParallelConfig {
            threads: vec![0],
            ..Default::default()
        };
        assert!(cfg.validate().unwrap_err().to_string().contains("thread"));
        cfg.threads = vec![1];
        cfg.triangles = vec![10];
        assert!(cfg.validate().unwrap_err().to_string().contains("1,000"));
        cfg.triangles = vec![5_000];
        cfg.options.reach = 0.0;
        assert!(cfg.validate().unwrap_err().to_string().contains("reach"));
    }

    #[test]
    fn paper_speedups_are_the_tables() {
        let (mean, lo, hi) = paper_two_processor_speedup();
        assert!(
            (lo - 1.548).abs() < 0.01 && (hi - 1.743).abs() < 0.01,
            "{lo} {hi}"
        );
        assert!(mean > lo && mean < hi);
    }
}
