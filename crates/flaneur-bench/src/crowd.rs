//! The `crowd` experiment (ours): many viewers at once reading one database from one
//! plain HTTP server, as a CDN's edge or one nginx would carry them.
//!
//! Each walker is a thread of its own with a database opened afresh by URL (its own
//! connections and a cold client cache) and walks REVIEW's Optimal configuration that
//! never waits on a read (`ReviewConfig::never_wait`). Walker `i` takes pattern
//! `i mod patterns` and path seed `seed + i`, so the crowd spreads over the city rather
//! than asking for the same pages in step. The figures: per walker, the walk's frames
//! over 50 ms, visual misses, requests, bytes and its requests' p50/p99 time (sent to
//! last body byte); over the crowd, errors, total requests and bytes per second, the
//! merged p50/p99, and the server's CPU seconds over the wall-clock seconds of the run
//! when the experiment started the server itself.

use std::path::Path;
use std::thread;
use std::time::Instant;

use crate::report::Report;
use crate::walk_setup::{walk_path, WalkSetup};
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::path::motion::Motion;
use flaneur::store::{HttpOptions, RequestTimes};
use flaneur::walk::review::{Preset, ReviewConfig, WalkReport};
use flaneur::walk::NoSink;

/// Walkers by default: the 32.
pub const DEFAULT_WALKERS: usize = 32;
/// The client page cache of each walker by default, bytes.
pub const DEFAULT_CACHE_BYTES: usize = 64 << 20;

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CrowdConfig {
    /// Each walker's walk; the patterns are dealt out in turn.
    pub walk: WalkSetup,
    /// Walkers at once.
    pub walkers: usize,
    /// Each walker's client page cache, bytes.
    pub cache_bytes: usize,
}

impl Default for CrowdConfig {
    /// 32 walkers, the thesis's five patterns dealt out, 600 frames each.
    fn default() -> CrowdConfig {
        CrowdConfig {
            walk: WalkSetup {
                frames: crate::walk_setup::SHORT_FRAMES,
                ..WalkSetup::default()
            },
            walkers: DEFAULT_WALKERS,
            cache_bytes: DEFAULT_CACHE_BYTES,
        }
    }
}

impl CrowdConfig {
    /// Checks the walk, at least one walker, and a cache of some bytes.
    pub fn validate(&self) -> Result<()> {
        self.walk.validate()?;
        if self.walkers == 0 || self.walkers > 1024 {
            return Err(Error::Invalid(format!(
                "crowd: between 1 and 1024 walkers, not {}",
                self.walkers
            )));
        }
        if self.cache_bytes == 0 {
            return Err(Error::Invalid(
                "crowd: the client cache must hold more than 0 bytes".into(),
            ));
        }
        Ok(())
    }

    /// Walker `i`'s pattern and path seed.
    pub fn walker(&self, i: usize) -> (Motion, u64) {
        let p = self.walk.patterns[i % self.walk.patterns.len()];
        (p, self.walk.seed.wrapping_add(i as u64))
    }

    fn review(&self) -> ReviewConfig {
        ReviewConfig {
            never_wait: true,
            ..self.walk.review(Preset::Optimal)
        }
    }
}

/// One walker's figures.
#[derive(Clone, Debug, serde::Serialize)]
pub struct WalkerRow {
    pub walker: usize,
    pub pattern: Motion,
    pub seed: u64,
    /// Why the walker stopped, when it did not finish: opening or walking failed.
    pub error: Option<String>,
    pub frames: usize,
    pub frames_over_50ms: usize,
    pub max_frame_ms: f64,
    pub visual_misses: u64,
    /// Loads that failed on the network and were counted, the walk going on.
    pub failed_loads: usize,
    pub requests: u64,
    pub retries: u64,
    pub bytes: u64,
    pub p50_ms: f64,
    pub p99_ms: f64,
    /// The walk's real time, seconds.
    pub walk_s: f64,
    #[serde(skip)]
    times: Option<RequestTimes>,
}

/// The experiment's rows and totals.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CrowdReport {
    pub config: CrowdConfig,
    /// Who served: a name for the summary.
    pub server: String,
    pub objects: u64,
    pub rows: Vec<WalkerRow>,
    /// From the first walker's start to the last one's end, seconds.
    pub wall_s: f64,
    /// The server's CPU seconds over the run, when known.
    pub server_cpu_s: Option<f64>,
    /// This process's CPU seconds over the run: the walkers' (and an in-process
    /// server's), every thread's user and system time.
    pub client_cpu_s: f64,
    /// Every walker's requests: how many, p50 and p99, ms.
    pub requests: u64,
    pub p50_ms: f64,
    pub p99_ms: f64,
    pub max_ms: f64,
}

impl CrowdReport {
    /// Walkers that stopped on an error, plus loads that failed.
    pub fn errors(&self) -> usize {
        self.rows
            .iter()
            .map(|r| r.error.is_some() as usize + r.failed_loads)
            .sum()
    }

    /// Body bytes received by the whole crowd per second of the run.
    pub fn bytes_per_s(&self) -> f64 {
        let b: u64 = self.rows.iter().map(|r| r.bytes).sum();
        if self.wall_s > 0.0 {
            b as f64 / self.wall_s
        } else {
            0.0
        }
    }
}

/// Runs `cfg.walkers` walkers at once against `url`, `server` naming who serves it and
/// `server_cpu` reading the server's CPU seconds so far (`None` when not known).
pub fn run(
    url: &str,
    server: &str,
    cfg: &CrowdConfig,
    server_cpu: impl Fn() -> Option<f64>,
) -> Result<CrowdReport> {
    cfg.validate()?;
    let opts = HttpOptions {
        cache_bytes: cfg.cache_bytes,
        ..HttpOptions::default()
    };
    // The walkers' paths come from the city's bounds: one open to learn them, and a
    // clear error for a bad URL before 32 threads each meet it.
    let first = Database::open_url_with(url, &opts)?;
    let objects = first.objects();
    let paths = (0..cfg.walkers)
        .map(|i| {
            let (pattern, seed) = cfg.walker(i);
            let setup = WalkSetup {
                seed,
                ..cfg.walk.clone()
            };
            setup.path(&first, pattern)
        })
        .collect::<Result<Vec<_>>>()?;
    drop(first);
    let walk_cfg = cfg.review();
    let cpu_before = server_cpu();
    let client_before = process_cpu_seconds();
    let start = Instant::now();
    let rows: Vec<WalkerRow> = thread::scope(|s| {
        let handles: Vec<_> = paths
            .iter()
            .enumerate()
            .map(|(i, path)| {
                let (opts, walk_cfg) = (&opts, &walk_cfg);
                s.spawn(move || walker(i, cfg, url, opts, path, walk_cfg))
            })
            .collect();
        handles
            .into_iter()
            .enumerate()
            .map(|(i, h)| {
                h.join()
                    .unwrap_or_else(|_| failed(i, cfg, "the walker's thread panicked".into()))
            })
            .collect()
    });
    let wall_s = start.elapsed().as_secs_f64();
    let client_cpu_s = process_cpu_seconds() - client_before;
    let server_cpu_s = match (cpu_before, server_cpu()) {
        (Some(a), Some(b)) => Some(b - a),
        _ => None,
    };
    let mut all = RequestTimes::default();
    for t in rows.iter().filter_map(|r| r.times.as_ref()) {
        all.merge(t);
    }
    Ok(CrowdReport {
        config: cfg.clone(),
        server: server.to_string(),
        objects,
        rows,
        wall_s,
        server_cpu_s,
        client_cpu_s,
        requests: all.count(),
        p50_ms: all.quantile_ms(0.5),
        p99_ms: all.quantile_ms(0.99),
        max_ms: all.max_ms(),
    })
}

/// User and system CPU seconds of this process so far, every thread's, ended ones too.
fn process_cpu_seconds() -> f64 {
    let mut usage = std::mem::MaybeUninit::<libc::rusage>::zeroed();
    // SAFETY: getrusage writes a whole rusage into the pointer it is given, which
    // points to one; RUSAGE_SELF is always a valid target.
    let usage = unsafe {
        if libc::getrusage(libc::RUSAGE_SELF, usage.as_mut_ptr()) != 0 {
            return 0.0;
        }
        usage.assume_init()
    };
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    secs(usage.ru_utime) + secs(usage.ru_stime)
}

/// Walker `i`'s row before it has walked: who it is, every figure 0.
fn blank(i: usize, cfg: &CrowdConfig) -> WalkerRow {
    let (pattern, seed) = cfg.walker(i);
    WalkerRow {
        walker: i,
        pattern,
        seed,
        error: None,
        frames: 0,
        frames_over_50ms: 0,
        max_frame_ms: 0.0,
        visual_misses: 0,
        failed_loads: 0,
        requests: 0,
        retries: 0,
        bytes: 0,
        p50_ms: 0.0,
        p99_ms: 0.0,
        walk_s: 0.0,
        times: None,
    }
}

/// Walker `i`'s row when it stopped for `why`.
fn failed(i: usize, cfg: &CrowdConfig, why: String) -> WalkerRow {
    WalkerRow {
        error: Some(why),
        ..blank(i, cfg)
    }
}

/// One walker: its own open, its own walk.
fn walker(
    i: usize,
    cfg: &CrowdConfig,
    url: &str,
    opts: &HttpOptions,
    path: &flaneur::path::CameraPath,
    walk_cfg: &ReviewConfig,
) -> WalkerRow {
    let t = Instant::now();
    let walked = Database::open_url_with(url, opts).and_then(|db| {
        walk_path::<WalkReport>(&db, path, walk_cfg.clone(), &mut NoSink).map(|r| (db, r))
    });
    let (db, report) = match walked {
        Ok(x) => x,
        Err(e) => return failed(i, cfg, e.to_string()),
    };
    let net = db.remote_stats().unwrap_or_default();
    let times = db.remote_request_times().unwrap_or_default();
    let s = &report.summary;
    WalkerRow {
        frames: s.frames,
        frames_over_50ms: s.frames_over_50ms,
        max_frame_ms: s.max_frame_ms,
        visual_misses: s.visual_misses,
        failed_loads: s.failed_loads,
        requests: net.requests,
        retries: net.retries,
        bytes: net.bytes,
        p50_ms: times.quantile_ms(0.5),
        p99_ms: times.quantile_ms(0.99),
        walk_s: t.elapsed().as_secs_f64(),
        times: Some(times),
        ..blank(i, cfg)
    }
}

impl Report for CrowdReport {
    fn name(&self) -> &'static str {
        "crowd"
    }

    fn to_csv(&self) -> String {
        let mut s = String::from("walker,pattern,seed,error,frames,frames_over_50ms,max_frame_ms,visual_misses,failed_loads,requests,retries,bytes,p50_ms,p99_ms,walk_s\n");
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{},{},{},{},{:.3},{},{},{},{},{},{:.3},{:.3},{:.3}\n",
                r.walker,
                r.pattern.name(),
                r.seed,
                r.error
                    .as_deref()
                    .map(|e| format!("\"{}\"", e.replace('"', "'")))
                    .unwrap_or_default(),
                r.frames,
                r.frames_over_50ms,
                r.max_frame_ms,
                r.visual_misses,
                r.failed_loads,
                r.requests,
                r.retries,
                r.bytes,
                r.p50_ms,
                r.p99_ms,
                r.walk_s
            ));
        }
        s
    }

    fn markdown(&self) -> String {
        let c = &self.config;
        let n = self.rows.len().max(1) as f64;
        let sum = |f: &dyn Fn(&WalkerRow) -> f64| self.rows.iter().map(f).sum::<f64>();
        let max = |f: &dyn Fn(&WalkerRow) -> f64| self.rows.iter().map(f).fold(0.0, f64::max);
        let mut md = format!(
            "# A crowd over HTTP (ours)\n\n{} walkers at once against {} on loopback, {} \
             objects. Each walker: its own open and a cold {} MiB client cache, REVIEW's \
             Optimal walk that never waits on a read, {}, played {}; patterns {} dealt out \
             in turn, path seed {} + walker.\n\n",
            self.rows.len(),
            self.server,
            self.objects,
            c.cache_bytes >> 20,
            c.walk.describe(),
            c.walk
                .pace
                .map_or("unpaced".to_string(), |p| format!("{p}x real time")),
            c.walk
                .patterns
                .iter()
                .map(|p| p.name())
                .collect::<Vec<_>>()
                .join(", "),
            c.walk.seed
        );
        md.push_str("| figure | value |\n|---|---|\n");
        let rows = [
            (
                "errors (walkers stopped + loads failed)",
                self.errors().to_string(),
            ),
            ("wall time of the run, s", format!("{:.1}", self.wall_s)),
            (
                "requests, all walkers (per second)",
                format!(
                    "{} ({:.0}/s)",
                    self.requests,
                    self.requests as f64 / self.wall_s.max(1e-9)
                ),
            ),
            (
                "bytes per walker, mean (max)",
                format!(
                    "{:.1} MiB ({:.1} MiB)",
                    sum(&|r| r.bytes as f64) / n / 1048576.0,
                    max(&|r| r.bytes as f64) / 1048576.0
                ),
            ),
            (
                "crowd's bytes per second",
                format!("{:.1} MiB/s", self.bytes_per_s() / 1048576.0),
            ),
            (
                "request time p50 / p99 / max, ms",
                format!(
                    "{:.2} / {:.2} / {:.1}",
                    self.p50_ms, self.p99_ms, self.max_ms
                ),
            ),
            (
                "server CPU, s (share of one core over the run)",
                self.server_cpu_s.map_or("not known".into(), |s| {
                    format!("{s:.2} ({:.0} %)", 100.0 * s / self.wall_s.max(1e-9))
                }),
            ),
            (
                "walkers' CPU, s (cores busy over the run)",
                format!(
                    "{:.1} ({:.2} of {})",
                    self.client_cpu_s,
                    self.client_cpu_s / self.wall_s.max(1e-9),
                    std::thread::available_parallelism().map_or(1, |n| n.get())
                ),
            ),
            (
                "frames over 50 ms, all walkers (worst walker)",
                format!(
                    "{} ({})",
                    sum(&|r| r.frames_over_50ms as f64),
                    max(&|r| r.frames_over_50ms as f64)
                ),
            ),
            (
                "longest frame, ms",
                format!("{:.1}", max(&|r| r.max_frame_ms)),
            ),
            (
                "visual misses per walker, mean",
                format!("{:.0}", sum(&|r| r.visual_misses as f64) / n),
            ),
        ];
        for (k, v) in rows {
            md.push_str(&format!("| {k} | {v} |\n"));
        }
        if let Some(r) = self.rows.iter().find(|r| r.error.is_some()) {
            md.push_str(&format!(
                "\nWalker {} stopped: {}\n",
                r.walker,
                r.error.as_deref().unwrap_or("")
            ));
        }
        md.push_str(
            "\nThe walkers share this machine's cores with the server and with each other, so \
             frame times include waiting for a core; counts and bytes are exact for a run.\n",
        );
        md
    }

    fn plot(&self, _dir: &Path) -> Result<()> {
        Ok(())
    }
}
