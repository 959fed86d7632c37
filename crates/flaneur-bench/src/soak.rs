//! The `soak` experiment (ours): an hour of walking, 108,000 frames at 30 frames a
//! second, played as fast as the machine goes, with the process's resident set sampled
//! along it. A walk keeps nothing per frame (its figures stream out as each frame ends,
//! its summary is tallied in constant memory, a motion pattern's poses are made as the
//! walk asks for them), so after the warm-up, the time the object buffer takes to fill,
//! the resident set must stay flat, within the buffer's budget plus the engine's fixed
//! overhead (code, the index cache, thread stacks, the allocator's slack).
//!
//! The resident set is read from `/proc/self/status`, so the experiment measures the
//! process that runs it: the `flaneur bench soak` command, alone. Its anonymous part
//! (`RssAnon`: the heap, the stacks) is what must stay flat; the rest is the database's
//! pages mapped by the `mmap` backend (`RssFile`), page cache the kernel may reclaim,
//! bounded by the file's size.

use std::path::Path;
use std::time::Instant;

use crate::plot::{line_plot, LinePlot, Series};
use crate::report::Report;
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::path::motion::{self, Motion};
use flaneur::walk::review::{Preset, ReviewConfig, WalkReport, WalkSummary};
use flaneur::walk::{self, Frame, Frames, Playback};

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SoakConfig {
    /// Frames walked: 108,000 is an hour at 30 frames a second.
    pub frames: usize,
    pub motion: Motion,
    pub fps: f32,
    pub seed: u64,
    /// Frames between two samples of the resident set.
    pub sample_every: usize,
    /// Frames of warm-up, after which the resident set must be flat.
    pub warm_up: usize,
    /// The walk (unpaced: the path's clock does not hold the frames back).
    pub review: ReviewConfig,
}

impl Default for SoakConfig {
    fn default() -> SoakConfig {
        SoakConfig {
            frames: 108_000,
            motion: Motion::Random,
            fps: 30.0,
            seed: 1,
            sample_every: 500,
            warm_up: 10_800,
            review: ReviewConfig {
                pace: None,
                ..ReviewConfig::preset(Preset::Optimal)
            },
        }
    }
}

/// One sample along the walk.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Sample {
    pub frame: usize,
    /// Seconds since the walk began.
    pub seconds: f64,
    /// The process's resident set, bytes.
    pub rss: u64,
    /// Its anonymous part (heap, stacks), bytes.
    pub anon: u64,
    /// What the object buffer held, bytes.
    pub buffer: u64,
}

/// What the experiment measured.
#[derive(Clone, Debug)]
pub struct SoakReport {
    pub config: SoakConfig,
    pub samples: Vec<Sample>,
    pub summary: WalkSummary,
    /// The resident set before the walk began (database open), bytes.
    pub rss_before: u64,
    pub seconds: f64,
}

impl SoakReport {
    /// The samples after the warm-up.
    fn settled(&self) -> impl Iterator<Item = &Sample> {
        self.samples
            .iter()
            .filter(move |s| s.frame >= self.config.warm_up)
    }

    /// The anonymous resident set at the first sample after the warm-up, bytes.
    pub fn anon_at_warm_up(&self) -> u64 {
        self.settled().next().map_or(0, |s| s.anon)
    }

    /// The largest anonymous resident set after the warm-up, bytes.
    pub fn anon_max_after_warm_up(&self) -> u64 {
        self.settled().map(|s| s.anon).max().unwrap_or(0)
    }

    /// How much the anonymous resident set grew after the warm-up, bytes: the largest
    /// less the first.
    pub fn growth_after_warm_up(&self) -> u64 {
        self.anon_max_after_warm_up()
            .saturating_sub(self.anon_at_warm_up())
    }

    /// The anonymous resident set beyond what the object buffer held at its largest,
    /// bytes: the engine's overhead.
    pub fn overhead(&self) -> u64 {
        self.anon_max_after_warm_up()
            .saturating_sub(self.summary.peak_buffer_bytes as u64)
    }
}

/// The process's resident set and its anonymous part, bytes (`VmRSS` and `RssAnon` of
/// `/proc/self/status`).
pub fn resident_set() -> Result<(u64, u64)> {
    let status = std::fs::read_to_string("/proc/self/status")
        .map_err(|e| Error::io(Path::new("/proc/self/status"), e))?;
    let field = |name: &str| {
        status
            .lines()
            .find_map(|l| l.strip_prefix(name))
            .and_then(|v| v.trim().strip_suffix("kB"))
            .and_then(|kb| kb.trim().parse::<u64>().ok())
            .map(|kb| kb * 1024)
            .ok_or_else(|| Error::Invalid(format!("/proc/self/status gives no {name}")))
    };
    Ok((field("VmRSS:")?, field("RssAnon:")?))
}

/// Walks `db` for `cfg.frames` frames, sampling the resident set.
pub fn run(db: &Database, cfg: &SoakConfig) -> Result<SoakReport> {
    if cfg.sample_every == 0 || cfg.warm_up >= cfg.frames {
        return Err(Error::Invalid(format!(
            "a soak of {} frames samples every {} frames after a warm-up of {}: give \
             a sample interval from 1 and a warm-up shorter than the walk",
            cfg.frames, cfg.sample_every, cfg.warm_up
        )));
    }
    let rss_before = resident_set()?.0;
    let poses = motion::poses(&db.bounds(), cfg.motion, cfg.frames, cfg.fps, cfg.seed)?;
    let walk_cfg = cfg.review.clone().into();
    let start = Instant::now();
    let mut samples = Vec::with_capacity(cfg.frames / cfg.sample_every + 2);
    let mut sample = |f: &Frame| -> Result<()> {
        let Frame::Review(f) = f else {
            unreachable!("a REVIEW walk's frames are REVIEW frames")
        };
        if f.frame % cfg.sample_every == 0 || f.frame + 1 == cfg.frames {
            let (rss, anon) = resident_set()?;
            samples.push(Sample {
                frame: f.frame,
                seconds: start.elapsed().as_secs_f64(),
                rss,
                anon,
                buffer: f.buffer_bytes as u64,
            });
        }
        Ok(())
    };
    // Each frame handed on and none kept, so that the walk's memory stays flat.
    let report: WalkReport = walk::run(
        db,
        &walk_cfg,
        &mut Playback::poses(poses),
        Frames::Each(&mut sample),
    )?
    .try_into()?;
    Ok(SoakReport {
        config: cfg.clone(),
        samples,
        summary: report.summary,
        rss_before,
        seconds: start.elapsed().as_secs_f64(),
    })
}

fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1 << 20) as f64
}

impl Report for SoakReport {
    fn name(&self) -> &'static str {
        "soak"
    }

    fn to_csv(&self) -> String {
        let mut s = String::from("frame,seconds,rss_bytes,anon_bytes,buffer_bytes\n");
        for x in &self.samples {
            s.push_str(&format!(
                "{},{:.3},{},{},{}\n",
                x.frame, x.seconds, x.rss, x.anon, x.buffer
            ));
        }
        s
    }

    fn markdown(&self) -> String {
        let c = &self.config;
        let s = &self.summary;
        format!(
            "# Soak: {} frames ({:.0} minutes of path at {} fps), {} pattern, unpaced\n\n\
             | figure | value |\n|---|---|\n\
             | walk time | {:.1} s ({:.3} ms a frame) |\n\
             | resident set before the walk | {:.1} MiB |\n\
             | anonymous resident set after the warm-up ({} frames) | {:.1} MiB |\n\
             | largest anonymous resident set after the warm-up | {:.1} MiB |\n\
             | its growth after the warm-up | {:.2} MiB |\n\
             | object buffer: budget, largest held | {:.0} MiB, {:.1} MiB |\n\
             | anonymous resident set beyond the buffer (overhead) | {:.1} MiB |\n\
             | largest resident set, the mapped file's pages included | {:.1} MiB |\n\
             | queries, pages read (index + mesh) | {}, {} + {} |\n\n\
             The walk keeps nothing per frame: after the warm-up its heap is what the \
             object buffer holds plus the engine's fixed overhead.\n",
            s.frames,
            s.frames as f64 / c.fps as f64 / 60.0,
            c.fps,
            c.motion,
            self.seconds,
            1e3 * self.seconds / s.frames.max(1) as f64,
            mib(self.rss_before),
            c.warm_up,
            mib(self.anon_at_warm_up()),
            mib(self.anon_max_after_warm_up()),
            mib(self.growth_after_warm_up()),
            mib(c.review.memory_budget as u64),
            mib(s.peak_buffer_bytes as u64),
            mib(self.overhead()),
            mib(self.samples.iter().map(|x| x.rss).max().unwrap_or(0)),
            s.queries,
            s.index_pages,
            s.mesh_pages,
        )
    }

    fn plot(&self, dir: &Path) -> Result<()> {
        let series = |name: &str, f: fn(&Sample) -> u64| Series {
            name: name.to_string(),
            points: self
                .samples
                .iter()
                .map(|s| (s.frame as f64, mib(f(s))))
                .collect(),
        };
        line_plot(
            &dir.join("soak-rss.png"),
            &LinePlot {
                title: format!("Resident set over a walk of {} frames", self.summary.frames),
                x_label: "frame".into(),
                y_label: "MiB".into(),
                series: vec![
                    series("resident set", |s| s.rss),
                    series("anonymous resident set", |s| s.anon),
                    series("object buffer", |s| s.buffer),
                ],
            },
        )
    }
}
