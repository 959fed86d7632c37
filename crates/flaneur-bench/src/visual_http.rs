//! The `visual-http` experiment (ours): the VISUAL walk over the HDoV-tree (Shou 2002
//! §5.8.5) never waiting on a read, over HTTP by byte ranges through a loopback link of
//! set round trip and bandwidth (`link`), against the same walk on the local file,
//! waiting as the thesis's does and never waiting.
//!
//! A walk that never waits (`VisualConfig::never_wait`) searches the tree and reads the
//! finds on a loader thread, coarsest levels first, so that a round trip shows as
//! visual misses, not as long frames. Each network walk opens the database afresh
//! through its own link (a cold client cache). The figures: frames over 50 ms on the
//! viewer's thread, visual misses (finds × frames, in viewcells) in all and after the
//! first complete frame, the time to that frame, finds drawn coarser than they deserve,
//! frames outside every viewcell, pages, requests and bytes.

use std::net::SocketAddr;
use std::path::Path;
use std::time::Duration;

use crate::plot::{line_plot, LinePlot, Series};
use crate::pvs_http::Source;
use crate::report::Report;
use crate::through_link::{check_link, open_through, timed};
use crate::walk_setup::{walk_path, WalkSetup};
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::path::motion::Motion;
use flaneur::store::{HttpOptions, RemoteStats};
use flaneur::walk::settings::DEFAULT_K;
use flaneur::walk::visual::{VisualConfig, VisualReport, DEFAULT_ETA};
use flaneur::walk::{NoSink, WalkConfig};

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VisualHttpConfig {
    /// The walks: every pattern of `walk.patterns`, played at `walk.pace`.
    pub walk: WalkSetup,
    /// The DoV threshold η of the searches.
    pub eta: f32,
    /// The next-cell prefetch of every walk, seconds ahead (ours); `None`: off.
    pub prefetch_k: Option<f32>,
    /// Round trips of the link, milliseconds.
    pub rtts_ms: Vec<u32>,
    /// The link's bandwidth, Mbit/s each way.
    pub mbit: f64,
    /// The client page cache, bytes.
    pub cache_bytes: usize,
}

impl Default for VisualHttpConfig {
    /// The normal and fast walks at the thesis's η, the next cell prefetched 0.8 s
    /// ahead, at round trips of 0 to 200 ms and 100 Mbit/s.
    fn default() -> VisualHttpConfig {
        VisualHttpConfig {
            walk: WalkSetup {
                patterns: vec![Motion::Normal, Motion::Fast],
                ..WalkSetup::default()
            },
            eta: DEFAULT_ETA,
            prefetch_k: Some(DEFAULT_K),
            rtts_ms: vec![0, 20, 50, 100, 200],
            mbit: 100.0,
            cache_bytes: HttpOptions::default().cache_bytes,
        }
    }
}

impl VisualHttpConfig {
    /// Checks the walk and the link settings.
    pub fn validate(&self) -> Result<()> {
        self.walk.validate()?;
        if self.rtts_ms.is_empty() {
            return Err(Error::Invalid(
                "visual-http: give at least one round trip".into(),
            ));
        }
        if !(self.eta.is_finite() && self.eta >= 0.0) {
            return Err(Error::Invalid(format!(
                "visual-http: a DoV threshold η of {}: give a number ≥ 0",
                self.eta
            )));
        }
        if let Some(k) = self.prefetch_k.filter(|k| !(k.is_finite() && *k >= 0.0)) {
            return Err(Error::Invalid(format!(
                "visual-http: a prefetch of {k} s ahead: give a number ≥ 0"
            )));
        }
        check_link("visual-http", &[self.mbit], self.cache_bytes)
    }

    /// The walk's settings, never waiting or waiting as the thesis's.
    pub fn walk_config(&self, never_wait: bool) -> VisualConfig {
        VisualConfig {
            eta: self.eta,
            prefetch_k: self.prefetch_k,
            far: self.walk.far,
            pace: self.walk.pace,
            never_wait,
            ..VisualConfig::default()
        }
    }
}

/// One walk's figures.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VisualHttpRow {
    pub pattern: Motion,
    pub source: Source,
    pub frames: usize,
    pub frames_over_50ms: usize,
    pub max_frame_ms: f64,
    pub visual_misses: usize,
    pub visual_misses_after_start: usize,
    /// Real seconds from the walk's start to its first frame in a viewcell without a
    /// visual miss.
    pub first_complete_s: Option<f64>,
    pub coarse_draws: usize,
    pub frames_outside: usize,
    pub searches_on_viewer: usize,
    pub pages: u64,
    /// The walk's network figures (HTTP only).
    pub requests: u64,
    pub bytes: u64,
    pub failed_loads: usize,
    /// The walk's real time, seconds.
    pub walk_s: f64,
}

/// The experiment's rows.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VisualHttpReport {
    pub config: VisualHttpConfig,
    pub objects: u64,
    pub rows: Vec<VisualHttpRow>,
}

/// Walks `local` and the same file served at `origin` under `name` (any HTTP server
/// with byte ranges), once per pattern and source. `progress` is told each walk as it
/// starts.
pub fn run(
    local: &Database,
    origin: SocketAddr,
    name: &str,
    cfg: &VisualHttpConfig,
    mut progress: impl FnMut(&str),
) -> Result<VisualHttpReport> {
    cfg.validate()?;
    if local.hdov()?.is_none() {
        return Err(Error::Invalid(format!(
            "{} has no HDoV-tree: build it with --visibility --hdov",
            local.store().path().display()
        )));
    }
    let mut rows = Vec::new();
    for &pattern in &cfg.walk.patterns {
        let path = cfg.walk.path(local, pattern)?;
        let mut walk = |db: &Database, source: Source| -> Result<()> {
            progress(&format!("{} {}", pattern.name(), source.describe()));
            let walk_cfg = cfg.walk_config(source != Source::LocalWaiting);
            // Made before the clock starts, so that only the walk is timed.
            let run_cfg = WalkConfig::from(walk_cfg.clone());
            let (r, took, net) = timed(db, || walk_path(db, &path, run_cfg, &mut NoSink))?;
            let speed = walk_cfg.pace.map_or(1.0, f64::from);
            let first = |i: usize| (path.poses[i].time - path.poses[0].time) / speed;
            rows.push(row(pattern, source, &r, took, net, first));
            Ok(())
        };
        walk(local, Source::LocalWaiting)?;
        walk(local, Source::Local)?;
        for &rtt_ms in &cfg.rtts_ms {
            let (_link, db) = open_through(
                "visual-http",
                origin,
                name,
                (rtt_ms, cfg.mbit),
                cfg.cache_bytes,
            )?;
            walk(&db, Source::Http { rtt_ms })?;
        }
    }
    Ok(VisualHttpReport {
        config: cfg.clone(),
        objects: local.objects(),
        rows,
    })
}

fn row(
    pattern: Motion,
    source: Source,
    r: &VisualReport,
    took: Duration,
    net: Option<RemoteStats>,
    real_s: impl Fn(usize) -> f64,
) -> VisualHttpRow {
    let s = &r.summary;
    VisualHttpRow {
        pattern,
        source,
        frames: s.frames,
        frames_over_50ms: s.frames_over_50ms,
        max_frame_ms: s.max_frame_ms,
        visual_misses: s.visual_misses,
        visual_misses_after_start: s.visual_misses_after_start,
        first_complete_s: s.first_complete_frame.map(real_s),
        coarse_draws: s.coarse_draws,
        frames_outside: s.frames_outside,
        searches_on_viewer: s.searches,
        pages: s.tree_pages + s.model_pages + s.other_pages,
        requests: net.as_ref().map_or(0, |n| n.requests),
        bytes: net.as_ref().map_or(0, |n| n.bytes),
        failed_loads: s.failed_loads,
        walk_s: took.as_secs_f64(),
    }
}

/// The plot's file name.
pub const PLOT: &str = "visual-http-misses-after-start.png";

impl Report for VisualHttpReport {
    fn name(&self) -> &'static str {
        "visual-http"
    }

    fn to_csv(&self) -> String {
        let mut s = String::from("pattern,source,rtt_ms,frames,frames_over_50ms,max_frame_ms,visual_misses,visual_misses_after_start,first_complete_s,coarse_draws,frames_outside,searches_on_viewer,pages,requests,bytes,failed_loads,walk_s\n");
        for r in &self.rows {
            let (kind, rtt) = r.source.columns();
            s.push_str(&format!(
                "{},{kind},{rtt},{},{},{:.3},{},{},{},{},{},{},{},{},{},{},{:.3}\n",
                r.pattern.name(),
                r.frames,
                r.frames_over_50ms,
                r.max_frame_ms,
                r.visual_misses,
                r.visual_misses_after_start,
                r.first_complete_s
                    .map_or(String::new(), |x| format!("{x:.3}")),
                r.coarse_draws,
                r.frames_outside,
                r.searches_on_viewer,
                r.pages,
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
            "# The VISUAL walk over HTTP (ours)\n\n{} objects. {}, played {}, η = {}, next-cell \
             prefetch {}. VISUAL walks that never wait on a read, through a loopback link of \
             the round trip given at {} Mbit/s, each from a cold client cache of {} MiB; \
             beside them the local walks, never waiting and waiting as the thesis's. Visual \
             misses are finds × frames: at every frame in a viewcell, the cell's finds not \
             yet arrived at any level (the waiting walk reads them before the frame).\n\n",
            self.objects,
            c.walk.describe(),
            c.walk
                .pace
                .map_or("unpaced".to_string(), |p| format!("{p}x real time")),
            c.eta,
            c.prefetch_k
                .map_or("off".to_string(), |k| format!("{k} s ahead")),
            c.mbit,
            c.cache_bytes >> 20
        );
        md.push_str("| pattern | source | frames > 50 ms | max frame ms | visual misses | after start | first complete s | coarse draws | frames outside | searches on the viewer's thread | pages | requests | MiB | failed loads |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
        for r in &self.rows {
            md.push_str(&format!(
                "| {} | {} | {} | {:.1} | {} | {} | {} | {} | {} | {} | {} | {} | {:.1} | {} |\n",
                r.pattern.name(),
                r.source.describe(),
                r.frames_over_50ms,
                r.max_frame_ms,
                r.visual_misses,
                r.visual_misses_after_start,
                r.first_complete_s
                    .map_or("–".to_string(), |x| format!("{x:.2}")),
                r.coarse_draws,
                r.frames_outside,
                r.searches_on_viewer,
                r.pages,
                r.requests,
                r.bytes as f64 / f64::from(1 << 20),
                r.failed_loads
            ));
        }
        let over: usize = self
            .rows
            .iter()
            .filter(|r| r.source != Source::LocalWaiting)
            .map(|r| r.frames_over_50ms)
            .sum();
        md.push_str(&format!(
            "\nGoal: no frame over 50 ms on the viewer's thread of a walk that never waits (in \
             all: {over}). Frame times and what arrives when are wall-clock on this machine; \
             a waiting walk's page counts are exact.\n"
        ));
        md
    }

    fn plot(&self, dir: &Path) -> Result<()> {
        let series = self
            .config
            .walk
            .patterns
            .iter()
            .map(|&pattern| Series {
                name: pattern.name().to_string(),
                points: self
                    .rows
                    .iter()
                    .filter(|r| r.pattern == pattern)
                    .filter_map(|r| match r.source {
                        Source::Http { rtt_ms } => {
                            Some((f64::from(rtt_ms), r.visual_misses_after_start as f64))
                        }
                        _ => None,
                    })
                    .collect(),
            })
            .collect();
        line_plot(
            &dir.join(PLOT),
            &LinePlot {
                title: "VISUAL's visual misses after the first complete frame, over HTTP".into(),
                x_label: "round trip (ms)".into(),
                y_label: "visual misses (finds × frames)".into(),
                series,
            },
        )
    }
}
