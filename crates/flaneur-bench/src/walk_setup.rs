//! The walk every walking experiment takes (Shou 2002 §4.4): a generated camera path —
//! frames, frame rate, seed, motion patterns (`path::motion`) — walked with the REVIEW
//! settings the thesis fixes for its runs — frustum depth, scale factor SF, memory
//! budget (`walk::review`). Each experiment's config embeds one [`WalkSetup`] and adds
//! only what it sweeps, so the settings are defined, defaulted and checked once.
//!
//! Also here: what the experiments' sweeps share (their checks and how a swept value is
//! printed), the thesis's names of the configurations, the figures of a walk that its
//! summary does not hold (mean wait and mean search time per query), and the call
//! most experiments walk a path with (`walk_path`).

use std::fmt::Display;

use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::path::motion::{self, Motion};
use flaneur::path::CameraPath;
use flaneur::walk::review::{FrameStats, Preset, Retrieval, ReviewConfig, WalkReport};
use flaneur::walk::settings::{self, check_budget, check_far, check_pace};
pub(super) use flaneur::walk::settings::{check_k, check_sf};
use flaneur::walk::{self, FrameSink, Frames, Playback, WalkConfig};

/// The five motion patterns of the thesis's sessions (Fig. 4.17, Table 4.1), in this
/// order; `Motion::ALL` also has a random walk, which the thesis did not use.
pub const THESIS_PATTERNS: [Motion; 5] = [
    Motion::Normal,
    Motion::Fast,
    Motion::Slow,
    Motion::Turning,
    Motion::Backward,
];

/// Frames of a walk by default: a minute at [`DEFAULT_FPS`], as long as the demo's walk.
pub const DEFAULT_FRAMES: usize = 1800;
/// Frames of the walks of the figures that walk a path once per configuration and per
/// cell size or city (`cell_size`, `frame_time`, `db_size`) by default: 20 s at
/// [`DEFAULT_FPS`]. BOX at SF 1 queries at every frame, and walks that prefetch are
/// paced against the path's clock, so a minute per walk would make these figures take
/// many minutes on the demo city.
pub const SHORT_FRAMES: usize = 600;
/// Frames of the `patterns` walks (Table 4.1) by default: two minutes. A slow viewer
/// (4 m/s) leaves a disk cell about once in ten seconds, and the first query of a walk
/// is always a whole cell (there is no history yet); a minute of slow walking has so few
/// queries that this cold one decides the mean.
pub const PATTERN_FRAMES: usize = 3600;
/// Frame rate of the generated paths by default, frames per second.
pub const DEFAULT_FPS: f32 = 30.0;
/// Seed of the generated paths by default.
pub const DEFAULT_SEED: u64 = 1;

/// The walk of an experiment: which paths, and the REVIEW settings they are walked with.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct WalkSetup {
    /// Frames of each walk.
    pub frames: usize,
    /// Frames per second of the generated paths.
    pub fps: f32,
    /// Seed of the generated paths (the same for every pattern, so that the patterns
    /// differ only in how the viewer moves).
    pub seed: u64,
    /// Depth of the view frustum, metres.
    pub far: f32,
    /// Scale factor SF of the disk cell (experiments that sweep SF replace it).
    pub sf: f32,
    /// Object buffer budget, bytes.
    pub memory_budget: usize,
    /// The motion patterns walked, in order (one, for the experiments that walk one path).
    pub patterns: Vec<Motion>,
    /// Playback speed of the walks that prefetch, times real time (`ReviewConfig::pace`).
    pub pace: Option<f32>,
}

impl Default for WalkSetup {
    /// The thesis's settings (§4.4, through `walk::review`'s defaults) on every one of
    /// its five patterns.
    fn default() -> WalkSetup {
        WalkSetup {
            frames: DEFAULT_FRAMES,
            fps: DEFAULT_FPS,
            seed: DEFAULT_SEED,
            far: settings::DEFAULT_FAR,
            sf: settings::DEFAULT_SF,
            memory_budget: settings::DEFAULT_MEMORY_BUDGET,
            patterns: THESIS_PATTERNS.to_vec(),
            pace: Some(settings::DEFAULT_PACE),
        }
    }
}

impl WalkSetup {
    /// The default setup walking only `pattern`.
    pub fn one_pattern(pattern: Motion) -> WalkSetup {
        WalkSetup {
            patterns: vec![pattern],
            ..WalkSetup::default()
        }
    }

    /// The default setup of the figures that repeat a walk per configuration and per cell
    /// size or city: [`SHORT_FRAMES`] frames of `pattern`.
    pub fn short(pattern: Motion) -> WalkSetup {
        WalkSetup {
            frames: SHORT_FRAMES,
            ..WalkSetup::one_pattern(pattern)
        }
    }

    /// Checks every setting: at least one frame, a frame rate the path generator takes,
    /// a frustum deeper than a metre, SF ≥ 1, a non-zero budget, and at least one
    /// pattern, none twice.
    pub fn validate(&self) -> Result<()> {
        if self.frames == 0 {
            return Err(Error::Invalid("a walk needs at least one frame".into()));
        }
        if !(self.fps.is_finite() && (motion::MIN_FPS..=motion::MAX_FPS).contains(&self.fps)) {
            return Err(Error::Invalid(format!(
                "frame rate {} must be in {}..={} frames per second",
                self.fps,
                motion::MIN_FPS,
                motion::MAX_FPS
            )));
        }
        check_far(self.far)?;
        check_sf(self.sf)?;
        check_budget(self.memory_budget)?;
        if let Some(p) = self.pace {
            check_pace(p)?;
        }
        if self.patterns.is_empty() {
            return Err(Error::Invalid("no motion pattern to walk".into()));
        }
        for (i, p) in self.patterns.iter().enumerate() {
            if self.patterns[..i].contains(p) {
                return Err(Error::Invalid(format!(
                    "motion pattern '{}' is listed twice",
                    p.name()
                )));
            }
        }
        Ok(())
    }

    /// The one pattern of an experiment that walks a single path; an error naming
    /// `experiment` when the setup lists none or several.
    pub fn single_pattern(&self, experiment: &str) -> Result<Motion> {
        match self.patterns[..] {
            [p] => Ok(p),
            _ => Err(Error::Invalid(format!(
                "{experiment} walks one path: give one motion pattern, not {} ({})",
                self.patterns.len(),
                self.patterns
                    .iter()
                    .map(|p| p.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))),
        }
    }

    /// The generated path of `pattern` through the database's city.
    pub fn path(&self, db: &Database, pattern: Motion) -> Result<CameraPath> {
        motion::generate(&db.bounds(), pattern, self.frames, self.fps, self.seed)
    }

    /// The walk settings of configuration `preset` with this setup's frustum, SF and
    /// budget; the rest (retrieval, index cache, k) is the preset's.
    pub fn review(&self, preset: Preset) -> ReviewConfig {
        ReviewConfig {
            sf: self.sf,
            far: self.far,
            memory_budget: self.memory_budget,
            pace: self.pace,
            ..ReviewConfig::preset(preset)
        }
    }

    /// The setup in words, for the experiments' summaries: frames, frame rate, seed,
    /// frustum and budget (not SF, which some experiments sweep).
    pub fn describe(&self) -> String {
        format!(
            "{} frames at {} fps (seed {}), frustum {} m deep, object buffer {} MiB",
            self.frames,
            self.fps,
            self.seed,
            self.far,
            self.memory_budget >> 20
        )
    }
}

/// Walks `path` through `db` under `cfg` into `sink` ([`NoSink`](flaneur::walk::NoSink)
/// where nothing is drawn) and gives the walked mode's own report (`R`:
/// `review::WalkReport`, `visual::VisualReport`, ...). Every frame is kept: several
/// experiments read their figures from the frames, not the summary.
pub(super) fn walk_path<R>(
    db: &Database,
    path: &CameraPath,
    cfg: impl Into<WalkConfig>,
    sink: &mut dyn FrameSink,
) -> Result<R>
where
    R: TryFrom<walk::Report, Error = Error>,
{
    let viewer = &mut Playback::path(path).drawn_by(sink);
    walk::run(db, &cfg.into(), viewer, Frames::Keep)?.try_into()
}

/// The viewer's mean wait per query, ms: `query_ms` averaged over the frames that
/// queried (0 when none did). With prefetching a frame waits only for the rest of a
/// prefetch still running — its index search and the loading of its meshes — which is
/// what the thesis's Optimal configuration saves.
pub fn mean_query_ms(walk: &WalkReport) -> f64 {
    mean_over(walk, |f| f.queried)
}

/// The mean time of the index searches that ran while the viewer waited, ms: `query_ms`
/// over the frames that queried on their own thread, not from a prefetch (0 when none
/// did). There `query_ms` is the search alone, whatever the configuration, so this
/// compares configurations that prefetch with those that do not.
pub fn mean_search_ms(walk: &WalkReport) -> f64 {
    mean_over(walk, searched_on_frame)
}

/// How many searches [`mean_search_ms`] averages.
pub fn searches_timed(walk: &WalkReport) -> usize {
    walk.frames.iter().filter(|f| searched_on_frame(f)).count()
}

/// The frame queried on its own thread: its `query_ms` is a search.
fn searched_on_frame(f: &FrameStats) -> bool {
    f.queried && !f.prefetch_used
}

fn mean_over(walk: &WalkReport, which: impl Fn(&FrameStats) -> bool) -> f64 {
    let (sum, n) = walk
        .frames
        .iter()
        .filter(|f| which(f))
        .fold((0.0, 0usize), |(s, n), f| (s + f.query_ms, n + 1));
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

/// A configuration of §4.4 as the thesis writes it: Optimal, NC, NP, BOX.
pub fn label(p: Preset) -> &'static str {
    match p {
        Preset::Optimal => "Optimal",
        Preset::Nc => "NC",
        Preset::Np => "NP",
        Preset::Box => "BOX",
    }
}

/// What a configuration does, in words: its retrieval, index cache and prefetching
/// (e.g. "CSearch, a 1024 KiB dplru index cache, prefetching at k = 0.8", or "plain
/// range queries, no index cache, no prefetching").
pub fn describe_review(cfg: &ReviewConfig) -> String {
    let retrieval = match cfg.retrieval {
        Retrieval::Box => "plain range queries",
        Retrieval::CSearch => "CSearch",
    };
    let cache = match &cfg.index_cache {
        Some((policy, bytes)) => format!("a {} KiB {policy} index cache", bytes >> 10),
        None => "no index cache".into(),
    };
    let prefetch = cfg.prefetch_k.map_or("no prefetching".to_string(), |k| {
        format!("prefetching at k = {}", num(k))
    });
    format!("{retrieval}, {cache}, {prefetch}")
}

/// `pages` over `queries` (0 when there was no query).
pub fn per_query(pages: u64, queries: usize) -> f64 {
    if queries == 0 {
        0.0
    } else {
        pages as f64 / queries as f64
    }
}

/// A sweep: not empty, every value passing `check`, no value twice.
pub(super) fn check_sweep<T: Copy + PartialEq + Display>(
    what: &str,
    values: &[T],
    check: impl Fn(T) -> Result<()>,
) -> Result<()> {
    if values.is_empty() {
        return Err(Error::Invalid(format!("the {what} sweep is empty")));
    }
    for (i, &v) in values.iter().enumerate() {
        check(v)?;
        if values[..i].contains(&v) {
            return Err(Error::Invalid(format!("the {what} sweep has {v} twice")));
        }
    }
    Ok(())
}

/// A swept value as the tables show it: at least one decimal, at most three.
pub(super) fn num(v: f32) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0');
    if s.ends_with('.') {
        format!("{s}0")
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_and_sweeps() {
        assert_eq!(num(0.8), "0.8");
        assert_eq!(num(1.0), "1.0");
        assert_eq!(num(0.25), "0.25");
        assert!(check_sweep("k", &[], check_k).is_err());
        assert!(check_sweep("k", &[0.2, 0.2], check_k).is_err());
        assert!(check_sweep("k", &[f32::NAN], check_k).is_err());
        assert!(check_sweep("k", &[-0.1], check_k).is_err());
        assert!(check_sweep("SF", &[0.9], check_sf).is_err());
        assert!(check_sweep("SF", &[1.0, 1.5], check_sf).is_ok());
        assert!(check_sweep("size", &[3u64, 3], |_| Ok(())).is_err());
    }

    #[test]
    fn setups_are_checked() {
        let ok = WalkSetup {
            frames: 10,
            far: 100.0,
            memory_budget: 1 << 20,
            ..WalkSetup::default()
        };
        assert!(ok.validate().is_ok());
        let bad = |f: fn(&mut WalkSetup)| {
            let mut s = ok.clone();
            f(&mut s);
            matches!(s.validate(), Err(Error::Invalid(_)))
        };
        assert!(bad(|s| s.frames = 0));
        assert!(bad(|s| s.fps = f32::NAN));
        assert!(bad(|s| s.fps = 0.0));
        assert!(bad(|s| s.far = 0.5));
        assert!(bad(|s| s.sf = 0.9));
        assert!(bad(|s| s.memory_budget = 0));
        assert!(bad(|s| s.patterns.clear()));
        assert!(bad(|s| s.patterns = vec![Motion::Fast, Motion::Fast]));

        assert_eq!(
            WalkSetup::one_pattern(Motion::Slow)
                .single_pattern("x")
                .unwrap(),
            Motion::Slow
        );
        assert!(ok.single_pattern("x").is_err());
        let cfg = ok.review(Preset::Box);
        assert_eq!(
            (cfg.sf, cfg.far, cfg.memory_budget),
            (ok.sf, ok.far, ok.memory_budget)
        );
        assert_eq!(cfg.prefetch_k, ReviewConfig::preset(Preset::Box).prefetch_k);
    }
}
