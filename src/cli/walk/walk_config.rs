//! `flaneur walk`'s flags read into the one [`WalkConfig`] the walk runs: the mode's
//! defaults (or a preset of the thesis's), and what each flag changes of them.

use anyhow::{bail, Result};

use super::super::args::pace;
use super::WalkArgs;
use flaneur::walk::pvs::{PvsPrefetch, PvsWalkConfig};
use flaneur::walk::review::{Preset, ReviewConfig};
use flaneur::walk::scene::{SceneConfig, Traversal};
use flaneur::walk::visual::VisualConfig;
use flaneur::walk::{settings, WalkConfig, WalkMode};

impl WalkArgs {
    /// The walk the flags ask for: a `--config` preset is a REVIEW walk whatever
    /// `--mode` says.
    pub(super) fn walk_config(&self) -> Result<WalkConfig> {
        let mode = match self.config {
            Some(_) => WalkMode::Review,
            None => self.mode,
        };
        if self.never_wait
            && !matches!(
                mode,
                WalkMode::Review | WalkMode::Box | WalkMode::Pvs | WalkMode::Visual
            )
        {
            bail!(
                "--never-wait is for --mode review, box, pvs and visual; the {mode} walk \
                 still waits on its reads"
            );
        }
        Ok(match mode {
            WalkMode::Review | WalkMode::Box => WalkConfig::Review(self.review_config(mode)),
            WalkMode::Pvs => WalkConfig::Pvs(self.pvs_config()?),
            WalkMode::Visual => WalkConfig::Visual(self.visual_config()?),
            WalkMode::Vsc | WalkMode::Pb | WalkMode::Conv => {
                WalkConfig::Scene(self.scene_config(mode))
            }
        })
    }

    /// REVIEW or BOX (`mode`), or the `--config` preset, with the flags' changes.
    fn review_config(&self, mode: WalkMode) -> ReviewConfig {
        let preset = self.config.unwrap_or(match mode {
            WalkMode::Box => Preset::Box,
            _ => Preset::Optimal,
        });
        let mut cfg = ReviewConfig::preset(preset);
        self.set_cache(&mut cfg.index_cache, "dplru");
        if let Some(k) = self.k {
            cfg.prefetch_k = (k >= 0.0).then_some(k);
        }
        cfg.sf = self.sf.unwrap_or(cfg.sf);
        cfg.far = self.far.unwrap_or(cfg.far);
        cfg.memory_budget = self.budget_mb.map_or(cfg.memory_budget, |m| m << 20);
        cfg.pace = pace(self.speed);
        cfg.never_wait = self.never_wait;
        cfg
    }

    /// `cache` (a policy and its bytes, or none) as `--cache-bytes` and `--policy` say:
    /// a size sets it (0: none), under `--policy` or `default_policy`; a policy alone
    /// changes the default cache's.
    fn set_cache(&self, cache: &mut Option<(String, usize)>, default_policy: &str) {
        if let Some(bytes) = self.cache_bytes {
            *cache = (bytes > 0).then(|| {
                let policy = self.policy.clone();
                (policy.unwrap_or_else(|| default_policy.into()), bytes)
            });
        } else if let (Some(p), Some(c)) = (&self.policy, cache) {
            c.0 = p.clone();
        }
    }

    /// The PVS walk under `--prefetch` and `--border`.
    fn pvs_config(&self) -> Result<PvsWalkConfig> {
        let border = self.border;
        let prefetch = match self.prefetch.as_str() {
            "snp" => PvsPrefetch::Snp,
            "pbnp" => PvsPrefetch::Pbnp { border },
            "lanp" => PvsPrefetch::Lanp { border },
            other => bail!("unknown prefetch '{other}' (snp, pbnp, lanp)"),
        };
        let cfg = PvsWalkConfig {
            prefetch,
            never_wait: self.never_wait,
            // A waiting PVS walk plays its frames back to back, as the thesis's.
            pace: if self.never_wait {
                pace(self.speed)
            } else {
                None
            },
        };
        cfg.validate()?;
        Ok(cfg)
    }

    /// VISUAL under `--eta`, its node cache as `--cache-bytes` and `--policy` say.
    fn visual_config(&self) -> Result<VisualConfig> {
        let mut cfg = VisualConfig {
            eta: self.eta,
            pace: pace(self.speed),
            selection: self.selection,
            tau: self.lod_tau,
            never_wait: self.never_wait,
            ..VisualConfig::default()
        };
        self.visual.apply(&mut cfg)?;
        self.set_cache(&mut cfg.node_cache, "dovtime");
        cfg.far = self.far.unwrap_or(cfg.far);
        cfg.fallback_sf = self.sf.unwrap_or(cfg.fallback_sf);
        Ok(cfg)
    }

    /// VSC under `--eta`, PB under `--budget` or CONV (`mode`).
    fn scene_config(&self, mode: WalkMode) -> SceneConfig {
        let traversal = match mode {
            WalkMode::Vsc => Traversal::Vsc { eta: self.eta },
            WalkMode::Pb => Traversal::Pb {
                budget: self.budget,
            },
            _ => Traversal::Conv,
        };
        SceneConfig {
            far: self.far.unwrap_or(settings::DEFAULT_FAR),
            selection: self.selection,
            tau: self.lod_tau,
            ..SceneConfig::new(traversal)
        }
    }
}
