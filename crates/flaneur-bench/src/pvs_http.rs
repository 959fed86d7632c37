//! The `pvs-http` experiment (ours): the PVS walk's neighbour prefetchers, SNP, PBNP
//! and LANP (Zheng 2007 ch. 7, and ours), over HTTP by byte ranges through a loopback
//! link of set round trip and bandwidth (`link`), against the same walks on the local
//! file.
//!
//! Every walk over the network and one local walk per rule never wait on a read
//! (`PvsWalkConfig::never_wait`): the client runs on a loader thread that reads the
//! rows and meshes it asks for, so a round trip shows as visual misses, not as long
//! frames, and the client measures its round trip in frames. A local walk that waits,
//! as the thesis's does, is beside each rule. Each network walk opens the database
//! afresh through its own link (a cold client cache). The figures: frames over 50 ms
//! on the viewer's thread, visual misses (objects × frames) in all and after the first
//! complete frame (what prefetching missed once the start's first cell had come), the
//! time to that frame, transactions, cache swaps and objects sent, the round trip the
//! client measured, requests and bytes.

use std::net::SocketAddr;
use std::path::Path;
use std::time::Duration;

use crate::plot::{line_plot, LinePlot, Series};
use crate::report::Report;
use crate::through_link::{check_link, open_through, timed};
use crate::walk_setup::{walk_path, WalkSetup};
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::path::motion::Motion;
use flaneur::prefetch::pvs::DEFAULT_BORDER;
use flaneur::store::{HttpOptions, RemoteStats};
use flaneur::walk::pvs::{PvsPrefetch, PvsWalkConfig, PvsWalkReport};
use flaneur::walk::NoSink;

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PvsHttpConfig {
    /// The walks: every pattern of `walk.patterns`, played at `walk.pace`.
    pub walk: WalkSetup,
    /// The rules walked.
    pub rules: Vec<PvsPrefetch>,
    /// Round trips of the link, milliseconds.
    pub rtts_ms: Vec<u32>,
    /// The link's bandwidth, Mbit/s each way.
    pub mbit: f64,
    /// The client page cache, bytes.
    pub cache_bytes: usize,
}

impl Default for PvsHttpConfig {
    /// The fast walk, SNP, PBNP and LANP, at round trips of 0 to 200 ms and 100 Mbit/s.
    fn default() -> PvsHttpConfig {
        let border = DEFAULT_BORDER;
        PvsHttpConfig {
            walk: WalkSetup {
                patterns: vec![Motion::Fast],
                ..WalkSetup::default()
            },
            rules: vec![
                PvsPrefetch::Snp,
                PvsPrefetch::Pbnp { border },
                PvsPrefetch::Lanp { border },
            ],
            rtts_ms: vec![0, 20, 50, 100, 200],
            mbit: 100.0,
            cache_bytes: HttpOptions::default().cache_bytes,
        }
    }
}

impl PvsHttpConfig {
    /// Checks the walk, the rules and the link settings.
    pub fn validate(&self) -> Result<()> {
        self.walk.validate()?;
        if self.rules.is_empty() || self.rtts_ms.is_empty() {
            return Err(Error::Invalid(
                "pvs-http: give at least one rule and one round trip".into(),
            ));
        }
        for &prefetch in &self.rules {
            self.walk_config(prefetch).validate()?;
        }
        check_link("pvs-http", &[self.mbit], self.cache_bytes)
    }

    /// The never-wait walk of `prefetch`, at this experiment's pace.
    pub fn walk_config(&self, prefetch: PvsPrefetch) -> PvsWalkConfig {
        PvsWalkConfig {
            prefetch,
            never_wait: true,
            pace: self.walk.pace,
        }
    }
}

/// Where a row's walk read its pages.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum Source {
    /// The local file, the walk waiting on its reads as the thesis's does.
    LocalWaiting,
    /// The local file, never waiting.
    Local,
    /// Over HTTP through a link of this round trip, never waiting.
    Http { rtt_ms: u32 },
}

impl Source {
    /// Its kind and round trip, as a CSV's two columns.
    pub fn columns(&self) -> (&'static str, String) {
        match self {
            Source::LocalWaiting => ("local-waiting", String::new()),
            Source::Local => ("local", String::new()),
            Source::Http { rtt_ms } => ("http", rtt_ms.to_string()),
        }
    }

    /// Where the walk read, in words.
    pub fn describe(&self) -> String {
        match self {
            Source::LocalWaiting => "local, waits (thesis)".into(),
            Source::Local => "local, never waits".into(),
            Source::Http { rtt_ms } => format!("HTTP {rtt_ms} ms"),
        }
    }
}

/// One walk's figures.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PvsHttpRow {
    pub pattern: Motion,
    pub rule: &'static str,
    pub source: Source,
    pub frames: usize,
    pub frames_over_50ms: usize,
    pub max_frame_ms: f64,
    pub visual_misses: usize,
    pub visual_misses_after_start: usize,
    /// Real seconds from the walk's start to its first frame without a visual miss.
    pub first_complete_s: Option<f64>,
    pub transactions: usize,
    pub swaps: usize,
    pub objects_sent: usize,
    /// The longest round trip the client measured, frames.
    pub round_trip_frames: u32,
    /// The walk's network figures (HTTP only).
    pub requests: u64,
    pub bytes: u64,
    pub failed_loads: usize,
    /// The walk's real time, seconds.
    pub walk_s: f64,
}

/// The experiment's rows.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PvsHttpReport {
    pub config: PvsHttpConfig,
    pub objects: u64,
    pub rows: Vec<PvsHttpRow>,
}

/// Walks `local` and the same file served at `origin` under `name` (any HTTP server
/// with byte ranges) with every rule, once per pattern and source. `progress` is told
/// each walk as it starts.
pub fn run(
    local: &Database,
    origin: SocketAddr,
    name: &str,
    cfg: &PvsHttpConfig,
    mut progress: impl FnMut(&str),
) -> Result<PvsHttpReport> {
    cfg.validate()?;
    if local.visibility()?.is_none() {
        return Err(Error::Pvs(format!(
            "{} has no precomputed visibility: build it with --visibility",
            local.store().path().display()
        )));
    }
    let mut rows = Vec::new();
    for &pattern in &cfg.walk.patterns {
        let path = cfg.walk.path(local, pattern)?;
        let mut walk = |db: &Database, source: Source, walk_cfg: PvsWalkConfig| -> Result<()> {
            progress(&format!(
                "{} {} {}",
                pattern.name(),
                walk_cfg.prefetch.name(),
                source.describe()
            ));
            let (r, took, net) = timed(db, || walk_path(db, &path, walk_cfg, &mut NoSink))?;
            let speed = walk_cfg.pace.map_or(1.0, f64::from);
            let first = |i: usize| (path.poses[i].time - path.poses[0].time) / speed;
            rows.push(row(pattern, source, &r, took, net, first));
            Ok(())
        };
        for &prefetch in &cfg.rules {
            walk(local, Source::LocalWaiting, prefetch.into())?;
            walk(local, Source::Local, cfg.walk_config(prefetch))?;
        }
        for &rtt_ms in &cfg.rtts_ms {
            for &prefetch in &cfg.rules {
                let (_link, db) = open_through(
                    "pvs-http",
                    origin,
                    name,
                    (rtt_ms, cfg.mbit),
                    cfg.cache_bytes,
                )?;
                walk(&db, Source::Http { rtt_ms }, cfg.walk_config(prefetch))?;
            }
        }
    }
    Ok(PvsHttpReport {
        config: cfg.clone(),
        objects: local.objects(),
        rows,
    })
}

fn row(
    pattern: Motion,
    source: Source,
    r: &PvsWalkReport,
    took: Duration,
    net: Option<RemoteStats>,
    real_s: impl Fn(usize) -> f64,
) -> PvsHttpRow {
    PvsHttpRow {
        pattern,
        rule: r.prefetch.name(),
        source,
        frames: r.frames.len(),
        frames_over_50ms: r.frames_over_50ms,
        max_frame_ms: r.max_frame_ms,
        visual_misses: r.visual_misses,
        visual_misses_after_start: r.visual_misses_after_start,
        first_complete_s: r.first_complete_frame.map(real_s),
        transactions: r.transactions,
        swaps: r.swaps,
        objects_sent: r.objects_sent,
        round_trip_frames: r.round_trip_frames,
        requests: net.as_ref().map_or(0, |n| n.requests),
        bytes: net.as_ref().map_or(0, |n| n.bytes),
        failed_loads: r.failed_loads,
        walk_s: took.as_secs_f64(),
    }
}

/// The plots' file names.
pub const PLOTS: [&str; 2] = [
    "pvs-http-misses-after-start.png",
    "pvs-http-round-trip-frames.png",
];

impl Report for PvsHttpReport {
    fn name(&self) -> &'static str {
        "pvs-http"
    }

    fn to_csv(&self) -> String {
        let mut s = String::from("pattern,rule,source,rtt_ms,frames,frames_over_50ms,max_frame_ms,visual_misses,visual_misses_after_start,first_complete_s,transactions,swaps,objects_sent,round_trip_frames,requests,bytes,failed_loads,walk_s\n");
        for r in &self.rows {
            let (kind, rtt) = r.source.columns();
            s.push_str(&format!(
                "{},{},{kind},{rtt},{},{},{:.3},{},{},{},{},{},{},{},{},{},{},{:.3}\n",
                r.pattern.name(),
                r.rule,
                r.frames,
                r.frames_over_50ms,
                r.max_frame_ms,
                r.visual_misses,
                r.visual_misses_after_start,
                r.first_complete_s
                    .map_or(String::new(), |x| format!("{x:.3}")),
                r.transactions,
                r.swaps,
                r.objects_sent,
                r.round_trip_frames,
                r.requests,
                r.bytes,
                r.failed_loads,
                r.walk_s
            ));
        }
        s
    }

    fn markdown(&self) -> String {
        let c = &self.config;
        let mut md = format!(
            "# The PVS walk over HTTP (ours)\n\n{} objects. {}, played {}. SNP, PBNP and \
             LANP walks that never wait on a read, through a loopback link of the round trip \
             given at {} Mbit/s, each from a cold client cache of {} MiB; beside them the \
             local walks, never waiting and waiting as the thesis's. Visual misses are \
             objects × frames: at every frame, the objects of the current cell's PVS not yet \
             arrived (the waiting walk counts them on entering a cell).\n\n",
            self.objects,
            c.walk.describe(),
            c.walk
                .pace
                .map_or("unpaced".to_string(), |p| format!("{p}x real time")),
            c.mbit,
            c.cache_bytes >> 20
        );
        md.push_str("| pattern | rule | source | frames > 50 ms | max frame ms | visual misses | after start | first complete s | transactions | swaps | objects sent | round trip (frames) | requests | MiB | failed loads |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
        for r in &self.rows {
            md.push_str(&format!(
                "| {} | {} | {} | {} | {:.1} | {} | {} | {} | {} | {} | {} | {} | {} | {:.1} | {} |\n",
                r.pattern.name(),
                r.rule.to_uppercase(),
                r.source.describe(),
                r.frames_over_50ms,
                r.max_frame_ms,
                r.visual_misses,
                r.visual_misses_after_start,
                r.first_complete_s
                    .map_or("–".to_string(), |x| format!("{x:.2}")),
                r.transactions,
                r.swaps,
                r.objects_sent,
                r.round_trip_frames,
                r.requests,
                r.bytes as f64 / f64::from(1 << 20),
                r.failed_loads
            ));
        }
        let over: usize = self.rows.iter().map(|r| r.frames_over_50ms).sum();
        md.push_str(&format!(
            "\nGoal: no frame over 50 ms on the viewer's thread (in all: {over}). Frame times \
             and what arrives when are wall-clock on this machine; a waiting walk's counts \
             are exact.\n"
        ));
        md
    }

    fn plot(&self, dir: &Path) -> Result<()> {
        type Figure = fn(&PvsHttpRow) -> f64;
        let figures: [(&str, &str, Figure); 2] = [
            (
                "Visual misses after the first complete frame, over HTTP",
                "visual misses (objects × frames)",
                |r| r.visual_misses_after_start as f64,
            ),
            (
                "The round trip the client measured",
                "round trip (frames)",
                |r| f64::from(r.round_trip_frames),
            ),
        ];
        for ((title, y, f), file) in figures.into_iter().zip(PLOTS) {
            let mut series = Vec::new();
            for &pattern in &self.config.walk.patterns {
                for &rule in &self.config.rules {
                    let points = self
                        .rows
                        .iter()
                        .filter(|r| r.pattern == pattern && r.rule == rule.name())
                        .filter_map(|r| match r.source {
                            Source::Http { rtt_ms } => Some((f64::from(rtt_ms), f(r))),
                            _ => None,
                        })
                        .collect();
                    series.push(Series {
                        name: format!("{} {}", pattern.name(), rule.name().to_uppercase()),
                        points,
                    });
                }
            }
            line_plot(
                &dir.join(file),
                &LinePlot {
                    title: title.into(),
                    x_label: "round trip (ms)".into(),
                    y_label: y.into(),
                    series,
                },
            )?;
        }
        Ok(())
    }
}
