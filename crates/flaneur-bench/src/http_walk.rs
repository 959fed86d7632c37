//! The `http` experiment (ours): walks of a database read over HTTP by byte ranges,
//! through a loopback link of set round trip and bandwidth (`link`), against the same
//! walks on the local file.
//!
//! Each motion pattern is walked once per (round trip, bandwidth) with REVIEW's Optimal
//! configuration in its never-wait form (`ReviewConfig::never_wait`): the viewer's
//! thread never waits on a read, so what a slow link costs shows as visual misses and
//! frames drawn outside every loaded cell, not as long frames. Every walk opens the
//! database afresh (a cold client cache) through its own link. The figures:
//!
//! - frames over 50 ms on the viewer's thread (the goal is none at any setting), the
//!   longest frame, visual misses, frames drawn outside every loaded cell, and the time
//!   to the first complete frame (no visual miss), in real seconds;
//! - requests and bytes per second of the walk, the client cache's hit rate;
//! - bytes moved over bytes of the pages the walk used: body bytes received during the
//!   walk over the mesh pages it read times the page size (goal ≤ 1.2). The visual-miss
//!   oracle reads the whole index before the walk, so the index is in the client cache
//!   and its pages cost the walk no bytes; they are left out of both sides.
//!
//! The local rows walk the file itself, never waiting and waiting as the thesis does.

use std::net::SocketAddr;
use std::path::Path;
use std::time::{Duration, Instant};

use crate::plot::{line_plot, LinePlot, Series};
use crate::report::Report;
use crate::through_link::{check_link, open_through};
use crate::walk_setup::{num, walk_path, WalkSetup};
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::path::motion::Motion;
use flaneur::store::{HttpOptions, RemoteStats};
use flaneur::walk::review::{Preset, ReviewConfig, WalkReport};
use flaneur::walk::NoSink;

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct HttpBenchConfig {
    /// The walks: every pattern of `walk.patterns` at every setting.
    pub walk: WalkSetup,
    /// Round trips of the link, milliseconds.
    pub rtts_ms: Vec<u32>,
    /// Bandwidths of the link, Mbit/s each way.
    pub mbits: Vec<f64>,
    /// The client page cache, bytes.
    pub cache_bytes: usize,
    /// The index cache's policy and bytes, in place of the Optimal configuration's
    /// (DPLRU, 1 MiB): over HTTP an index page the index cache and the client cache both
    /// lack costs a request on the loader's thread.
    pub index_cache: Option<(String, usize)>,
}

impl Default for HttpBenchConfig {
    /// The normal and fast walks at round trips of 0 to 200 ms and 20 and 100 Mbit/s.
    fn default() -> HttpBenchConfig {
        HttpBenchConfig {
            walk: WalkSetup {
                patterns: vec![Motion::Normal, Motion::Fast],
                ..WalkSetup::default()
            },
            rtts_ms: vec![0, 20, 50, 100, 200],
            mbits: vec![20.0, 100.0],
            cache_bytes: HttpOptions::default().cache_bytes,
            index_cache: None,
        }
    }
}

impl HttpBenchConfig {
    /// Checks the walk and the link settings.
    pub fn validate(&self) -> Result<()> {
        self.walk.validate()?;
        if self.rtts_ms.is_empty() || self.mbits.is_empty() {
            return Err(Error::Invalid(
                "http: give at least one round trip and one bandwidth".into(),
            ));
        }
        check_link("http", &self.mbits, self.cache_bytes)?;
        if let Some((policy, bytes)) = &self.index_cache {
            flaneur::cache::policy_by_name(policy)?;
            if *bytes == 0 {
                return Err(Error::Invalid(
                    "http: the index cache must hold more than 0 bytes".into(),
                ));
            }
        }
        Ok(())
    }

    /// The walk of every row: Optimal with this experiment's walk and index cache,
    /// never waiting.
    pub fn review(&self) -> ReviewConfig {
        let optimal = self.walk.review(Preset::Optimal);
        ReviewConfig {
            never_wait: true,
            index_cache: self.index_cache.clone().or(optimal.index_cache.clone()),
            ..optimal
        }
    }
}

/// Where a row's walk read its pages.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum Source {
    /// The local file, the walk never waiting on a read.
    Local,
    /// The local file, the walk waiting on its reads as the thesis's does.
    LocalWaiting,
    /// Over HTTP through a link of this round trip (ms) and bandwidth (Mbit/s).
    Http { rtt_ms: u32, mbit: f64 },
}

impl Source {
    fn describe(&self) -> String {
        match self {
            Source::Local => "local, never waits".into(),
            Source::LocalWaiting => "local, waits (thesis)".into(),
            Source::Http { rtt_ms, mbit } => format!("HTTP {rtt_ms} ms, {mbit} Mbit/s"),
        }
    }
}

/// One walk's figures.
#[derive(Clone, Debug, serde::Serialize)]
pub struct HttpRow {
    pub pattern: Motion,
    pub source: Source,
    pub frames: usize,
    pub frames_over_50ms: usize,
    pub max_frame_ms: f64,
    pub visual_misses: u64,
    /// Frames with at least one visual miss.
    pub frames_missing: usize,
    /// Frames drawn outside every loaded cell.
    pub frames_outran: usize,
    /// Real seconds from the walk's start to its first frame without a visual miss.
    pub first_complete_s: Option<f64>,
    /// Searches on the viewer's thread (none when it never waits).
    pub sync_queries: usize,
    /// Opening the database, ms (HTTP: the first round trips).
    pub open_ms: f64,
    /// The walk's real time, seconds.
    pub walk_s: f64,
    /// The walk's network figures (HTTP only).
    pub requests: u64,
    pub round_trips: u64,
    pub bytes: u64,
    /// Bytes of the mesh and LOD pages the walk read (page size × pages).
    pub used_bytes: u64,
    /// Objects drawn at a coarse level while their full mesh came, summed over frames.
    pub coarse_draws: u64,
    /// The client page cache's hit rate over the walk (HTTP only).
    pub hit_rate: Option<f64>,
    pub failed_loads: usize,
    /// Index pages the walk read past its index cache (its misses), and that cache's
    /// hit rate.
    pub index_pages: u64,
    pub index_hit_rate: Option<f64>,
}

impl HttpRow {
    pub fn requests_per_s(&self) -> f64 {
        per(self.requests as f64, self.walk_s)
    }

    pub fn bytes_per_s(&self) -> f64 {
        per(self.bytes as f64, self.walk_s)
    }

    /// Bytes moved over bytes used; `None` for the local rows or a walk that used none.
    pub fn moved_over_used(&self) -> Option<f64> {
        (matches!(self.source, Source::Http { .. }) && self.used_bytes > 0)
            .then(|| self.bytes as f64 / self.used_bytes as f64)
    }
}

fn per(x: f64, s: f64) -> f64 {
    if s > 0.0 {
        x / s
    } else {
        0.0
    }
}

/// The experiment's rows.
#[derive(Clone, Debug, serde::Serialize)]
pub struct HttpReport {
    pub config: HttpBenchConfig,
    pub objects: u64,
    pub page_size: usize,
    pub rows: Vec<HttpRow>,
}

/// Walks `local` and the same file served at `origin` under `name` (any HTTP server
/// with byte ranges), once per pattern and setting. `progress` is told each walk as it
/// starts.
pub fn run(
    local: &Database,
    origin: SocketAddr,
    name: &str,
    cfg: &HttpBenchConfig,
    mut progress: impl FnMut(&str),
) -> Result<HttpReport> {
    cfg.validate()?;
    let page_size = local.store().page_size();
    let mut rows = Vec::new();
    for &pattern in &cfg.walk.patterns {
        let path = cfg.walk.path(local, pattern)?;
        for (source, wait) in [(Source::Local, true), (Source::LocalWaiting, false)] {
            progress(&format!("{} {}", pattern.name(), source.describe()));
            let walk_cfg = ReviewConfig {
                never_wait: wait,
                ..cfg.review()
            };
            let t = Instant::now();
            let report = walk_path(local, &path, walk_cfg, &mut NoSink)?;
            rows.push(row(
                pattern,
                source,
                &report,
                t.elapsed(),
                0.0,
                None,
                page_size,
            ));
        }
        for &rtt_ms in &cfg.rtts_ms {
            for &mbit in &cfg.mbits {
                let source = Source::Http { rtt_ms, mbit };
                progress(&format!("{} {}", pattern.name(), source.describe()));
                let t = Instant::now();
                let (_link, db) =
                    open_through("http", origin, name, (rtt_ms, mbit), cfg.cache_bytes)?;
                // The oracle's read of the whole index, before the walk's figures start.
                db.range(&db.bounds())?;
                let open_ms = t.elapsed().as_secs_f64() * 1e3;
                let before = db.remote_stats().unwrap_or_default();
                let t = Instant::now();
                let report = walk_path(&db, &path, cfg.review(), &mut NoSink)?;
                let took = t.elapsed();
                let net = db.remote_stats().map(|s| s.since(&before));
                rows.push(row(pattern, source, &report, took, open_ms, net, page_size));
            }
        }
    }
    Ok(HttpReport {
        config: cfg.clone(),
        objects: local.objects(),
        page_size,
        rows,
    })
}

fn row(
    pattern: Motion,
    source: Source,
    r: &WalkReport,
    took: Duration,
    open_ms: f64,
    net: Option<RemoteStats>,
    page_size: usize,
) -> HttpRow {
    let s = &r.summary;
    let speed = f64::from(r.config.pace.unwrap_or(1.0));
    let start = r.frames.first().map_or(0.0, |f| f.time);
    let net = net.as_ref();
    HttpRow {
        pattern,
        source,
        frames: s.frames,
        frames_over_50ms: s.frames_over_50ms,
        max_frame_ms: s.max_frame_ms,
        visual_misses: s.visual_misses,
        frames_missing: r.frames.iter().filter(|f| f.visual_misses > 0).count(),
        frames_outran: s.frames_outran,
        first_complete_s: s
            .first_complete_frame
            .map(|i| (r.frames[i].time - start) / speed),
        sync_queries: s.sync_queries,
        open_ms,
        walk_s: took.as_secs_f64(),
        requests: net.map_or(0, |n| n.requests),
        round_trips: net.map_or(0, |n| n.round_trips),
        bytes: net.map_or(0, |n| n.bytes),
        used_bytes: (s.mesh_pages + s.lod_pages) * page_size as u64,
        coarse_draws: s.coarse_draws,
        hit_rate: net.map(|n| n.hit_rate()),
        failed_loads: s.failed_loads,
        index_pages: s.index_pages,
        index_hit_rate: s.index_cache.map(|c| c.hit_rate()),
    }
}

/// One plotted figure of a row.
type Figure = Box<dyn Fn(&HttpRow) -> Option<f64>>;

/// The plots' file names.
pub const PLOTS: [&str; 3] = [
    "http-visual-misses.png",
    "http-frames-over-50ms.png",
    "http-moved-over-used.png",
];

impl Report for HttpReport {
    fn name(&self) -> &'static str {
        "http"
    }

    fn to_csv(&self) -> String {
        let mut s = String::from("pattern,source,rtt_ms,mbit,frames,frames_over_50ms,max_frame_ms,visual_misses,frames_missing,frames_outran,first_complete_s,sync_queries,open_ms,walk_s,requests,round_trips,bytes,used_bytes,requests_per_s,bytes_per_s,moved_over_used,hit_rate,failed_loads,coarse_draws,index_pages,index_hit_rate\n");
        for r in &self.rows {
            let (kind, rtt, mbit) = match r.source {
                Source::Local => ("local", String::new(), String::new()),
                Source::LocalWaiting => ("local-waiting", String::new(), String::new()),
                Source::Http { rtt_ms, mbit } => ("http", rtt_ms.to_string(), mbit.to_string()),
            };
            let opt = |x: Option<f64>| x.map_or(String::new(), |x| format!("{x:.4}"));
            s.push_str(&format!(
                "{},{kind},{rtt},{mbit},{},{},{:.3},{},{},{},{},{},{:.1},{:.3},{},{},{},{},{:.2},{:.0},{},{},{},{},{},{}\n",
                r.pattern.name(),
                r.frames,
                r.frames_over_50ms,
                r.max_frame_ms,
                r.visual_misses,
                r.frames_missing,
                r.frames_outran,
                opt(r.first_complete_s),
                r.sync_queries,
                r.open_ms,
                r.walk_s,
                r.requests,
                r.round_trips,
                r.bytes,
                r.used_bytes,
                r.requests_per_s(),
                r.bytes_per_s(),
                opt(r.moved_over_used()),
                opt(r.hit_rate),
                r.failed_loads,
                r.coarse_draws,
                r.index_pages,
                opt(r.index_hit_rate)
            ));
        }
        s
    }

    fn markdown(&self) -> String {
        let c = &self.config;
        let mut md = format!(
            "# A walk over HTTP (ours)\n\n{} objects, {} B pages. {}, played {}. REVIEW's \
             Optimal configuration that never waits on a read (`--never-wait`), through a \
             loopback link of the round trip and bandwidth given, each walk from a cold \
             client cache of {} MiB, index cache {}; beside it the walks of the local file.\n\n",
            self.objects,
            self.page_size,
            c.walk.describe(),
            c.walk
                .pace
                .map_or("unpaced".to_string(), |p| format!("{p}x real time")),
            c.cache_bytes >> 20,
            c.review()
                .index_cache
                .map_or("none".to_string(), |(p, b)| format!("{p}, {} KiB", b >> 10))
        );
        md.push_str("| pattern | source | frames > 50 ms | max frame ms | visual misses | frames missing | frames outside | coarse draws | first complete s | viewer's own searches | requests/s | KiB/s | moved / used | hit rate | failed loads | index pages read (index cache hit rate) |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
        for r in &self.rows {
            let opt =
                |x: Option<f64>, d: usize| x.map_or("–".to_string(), |x| format!("{x:.d$}"));
            md.push_str(&format!(
                "| {} | {} | {} | {:.1} | {} | {} | {} | {} | {} | {} | {:.1} | {:.0} | {} | {} | {} | {} ({}) |\n",
                r.pattern.name(),
                r.source.describe(),
                r.frames_over_50ms,
                r.max_frame_ms,
                r.visual_misses,
                r.frames_missing,
                r.frames_outran,
                r.coarse_draws,
                opt(r.first_complete_s, 2),
                r.sync_queries,
                r.requests_per_s(),
                r.bytes_per_s() / 1024.0,
                opt(r.moved_over_used(), 2),
                opt(r.hit_rate, 3),
                r.failed_loads,
                r.index_pages,
                opt(r.index_hit_rate, 3)
            ));
        }
        let http = || {
            self.rows
                .iter()
                .filter(|r| matches!(r.source, Source::Http { .. }))
        };
        let over: usize = http().map(|r| r.frames_over_50ms).sum();
        let worst_ratio = http()
            .filter_map(|r| r.moved_over_used())
            .fold(0.0f64, f64::max);
        md.push_str(&format!(
            "\nGoals: no frame over 50 ms on the viewer's thread at any setting (over HTTP: \
             {over} in all); bytes moved over bytes used at most 1.2 (the worst: {}). Frame \
             times are wall-clock on this machine; counts are exact for a run.\n",
            num(worst_ratio as f32)
        ));
        md
    }

    fn plot(&self, dir: &Path) -> Result<()> {
        let series = |f: &dyn Fn(&HttpRow) -> Option<f64>| -> Vec<Series> {
            let mut out = Vec::new();
            for &pattern in &self.config.walk.patterns {
                for &mbit in &self.config.mbits {
                    let points: Vec<(f64, f64)> = self
                        .rows
                        .iter()
                        .filter(|r| r.pattern == pattern)
                        .filter_map(|r| match r.source {
                            Source::Http { rtt_ms, mbit: m } if m == mbit => {
                                f(r).map(|y| (f64::from(rtt_ms), y))
                            }
                            _ => None,
                        })
                        .collect();
                    out.push(Series {
                        name: format!("{} {mbit} Mbit/s", pattern.name()),
                        points,
                    });
                }
            }
            out
        };
        let plots: [(&str, &str, Figure); 3] = [
            (
                "Visual misses over HTTP",
                "visual misses (objects × frames)",
                Box::new(|r| Some(r.visual_misses as f64)),
            ),
            (
                "Frames over 50 ms on the viewer's thread",
                "frames over 50 ms",
                Box::new(|r| Some(r.frames_over_50ms as f64)),
            ),
            (
                "Bytes moved over bytes used",
                "bytes received / mesh bytes read",
                Box::new(|r| r.moved_over_used()),
            ),
        ];
        for ((title, y, f), file) in plots.into_iter().zip(PLOTS) {
            line_plot(
                &dir.join(file),
                &LinePlot {
                    title: title.into(),
                    x_label: "round trip (ms)".into(),
                    y_label: y.into(),
                    series: series(&*f),
                },
            )?;
        }
        Ok(())
    }
}
