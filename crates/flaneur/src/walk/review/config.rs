//! What a REVIEW or BOX walk can vary: how it retrieves, the presets of Shou 2002 §4.4
//! and the settings each of them fixes.

use crate::error::{Error, Result};
use crate::walk::settings::{
    check_budget, check_far, check_k, check_pace, check_sf, DEFAULT_FAR, DEFAULT_K,
    DEFAULT_MEMORY_BUDGET, DEFAULT_PACE, DEFAULT_SF,
};

/// How a walk retrieves objects.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Retrieval {
    /// Plain range queries; every query reloads its whole cell.
    Box,
    /// Complement queries: only what the cell adds.
    CSearch,
}

/// The configurations of the thesis's experiments (§4.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Preset {
    /// CSearch + index cache + prefetching.
    Optimal,
    /// No index cache.
    Nc,
    /// No prefetching.
    Np,
    /// Plain BOX queries, nothing else.
    Box,
}

impl Preset {
    /// Every configuration, in the thesis's order.
    pub const ALL: [Preset; 4] = [Preset::Optimal, Preset::Nc, Preset::Np, Preset::Box];

    /// The configuration's name, as the CLI spells it and [`str::parse`] reads it:
    /// `optimal`, `nc`, `np` or `box`.
    pub fn name(&self) -> &'static str {
        match self {
            Preset::Optimal => "optimal",
            Preset::Nc => "nc",
            Preset::Np => "np",
            Preset::Box => "box",
        }
    }
}

impl std::str::FromStr for Preset {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Preset, String> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name() == s.to_ascii_lowercase())
            .ok_or_else(|| format!("unknown configuration '{s}' (optimal, nc, np, box)"))
    }
}

/// Everything a walk can vary.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ReviewConfig {
    /// How a new disk cell's objects are retrieved: BOX or CSearch.
    pub retrieval: Retrieval,
    /// Index cache: policy name and budget in bytes.
    pub index_cache: Option<(String, usize)>,
    /// Prefetch factor k, seconds: the prefetched cell is the disk cell of the frustum
    /// moved by k·velocity, whose far-plane centre is F' = F + k·velocity (§4.2.5; the
    /// thesis gives no unit). `None` disables prefetching.
    pub prefetch_k: Option<f32>,
    /// Scale factor SF: the disk cell is SF times the frustum cell on the ground.
    pub sf: f32,
    /// Object buffer budget, bytes.
    pub memory_budget: usize,
    /// Depth of the view frustum, metres (the thesis: 1 km).
    pub far: f32,
    /// Record the index cache's access trace (for replaying other policies and sizes).
    pub record_trace: bool,
    /// Play the path's clock this many times faster than real time, so that the
    /// prefetch thread has the time a viewer would give it (scaled down: a speed-up
    /// only handicaps prefetching). `None` runs frames back to back, as fast as the CPU
    /// goes: prefetches then rarely finish before the viewer arrives. Walks without
    /// prefetching are never paced (nothing runs beside them), unless they never wait.
    pub pace: Option<f32>,
    /// Ours: the viewer's thread never waits on a read. When the viewer outruns its
    /// prefetch, its own search is queued on a loader thread of its own, ahead of any
    /// prefetch, and the frame draws what the buffer holds (its misses counted); the
    /// prefetch horizon grows with the loader's measured latency; a load that fails on
    /// the network is counted and asked for again, and the walk goes on. `false` is the
    /// thesis's walk: the viewer searches for itself, waiting for its reads.
    pub never_wait: bool,
}

/// The thesis's index cache (§4.4): 1 MB, with distance-priority LRU.
pub const DEFAULT_INDEX_CACHE: usize = 1 << 20;
impl ReviewConfig {
    /// The configuration `p` of §4.4 at the walks' defaults (`walk::settings`): CSearch
    /// with the index cache and prefetching for `Optimal`, less the cache (`Nc`) or
    /// prefetching (`Np`), and plain BOX with neither (`Box`).
    pub fn preset(p: Preset) -> ReviewConfig {
        let cache = Some(("dplru".to_string(), DEFAULT_INDEX_CACHE));
        let base = ReviewConfig {
            retrieval: Retrieval::CSearch,
            index_cache: cache,
            prefetch_k: Some(DEFAULT_K),
            sf: DEFAULT_SF,
            memory_budget: DEFAULT_MEMORY_BUDGET,
            far: DEFAULT_FAR,
            record_trace: false,
            pace: Some(DEFAULT_PACE),
            never_wait: false,
        };
        match p {
            Preset::Optimal => base,
            Preset::Nc => ReviewConfig {
                index_cache: None,
                ..base
            },
            Preset::Np => ReviewConfig {
                prefetch_k: None,
                ..base
            },
            Preset::Box => ReviewConfig {
                retrieval: Retrieval::Box,
                index_cache: None,
                prefetch_k: None,
                ..base
            },
        }
    }

    /// Checks the settings, naming the first one out of range.
    pub fn validate(&self) -> Result<()> {
        check_sf(self.sf)?;
        if let Some(k) = self.prefetch_k {
            check_k(k)?;
            if self.retrieval == Retrieval::Box {
                return Err(Error::Invalid(
                    "BOX retrieval has no prefetching (the thesis's BOX has no optimisation): leave k unset".into(),
                ));
            }
        }
        check_far(self.far)?;
        if let Some(p) = self.pace {
            check_pace(p)?;
        }
        check_budget(self.memory_budget)
    }
}
