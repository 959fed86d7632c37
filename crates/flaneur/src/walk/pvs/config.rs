//! What a PVS walk can vary: its neighbours' prefetching rule (SNP, PBNP, LANP), and
//! whether the viewer waits on reads.

use crate::error::{Error, Result};
use crate::prefetch::pvs::{Lanp, Pbnp, PrefetchArea, Snp};
use serde::Serialize;

/// Which neighbours the client prefetches.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum PvsPrefetch {
    /// All eight on every cell change.
    Snp,
    /// Those the viewer leans towards, by the region of its cell it is in.
    Pbnp {
        /// The width of the side and corner regions, a fraction of the cell's side in
        /// (0, 0.5] ([`DEFAULT_BORDER`](crate::prefetch::pvs::DEFAULT_BORDER): 0.25).
        border: f64,
    },
    /// PBNP's cells and every cell the viewer may reach before an answer comes, at its
    /// measured speed and round trip (ours, `prefetch::pvs::Lanp`).
    Lanp {
        /// PBNP's border, as above.
        border: f64,
    },
}

impl PvsPrefetch {
    /// The rule's name, as the CLI's `--prefetch` spells it: `snp`, `pbnp` or `lanp`.
    pub fn name(&self) -> &'static str {
        match self {
            PvsPrefetch::Snp => "snp",
            PvsPrefetch::Pbnp { .. } => "pbnp",
            PvsPrefetch::Lanp { .. } => "lanp",
        }
    }

    /// The rule itself. LANP is taken to start standing still: until the viewer has
    /// moved it looks as far as PBNP. An error for a border outside (0, 0.5].
    pub fn rule(&self) -> Result<Box<dyn PrefetchArea + Sync>> {
        Ok(match *self {
            PvsPrefetch::Snp => Box::new(Snp),
            PvsPrefetch::Pbnp { border } => Box::new(Pbnp::new(border)?),
            PvsPrefetch::Lanp { border } => Box::new(Lanp::new(border, 0.0)?),
        })
    }
}

/// How a PVS walk runs: its prefetching rule, and whether the viewer waits on reads.
/// A [`PvsPrefetch`] alone is a waiting, unpaced walk, as the thesis's.
///
/// ```
/// use flaneur::walk::pvs::{PvsPrefetch, PvsWalkConfig};
/// let cfg = PvsWalkConfig::never_waiting(PvsPrefetch::Lanp { border: 0.25 });
/// assert!(cfg.never_wait && cfg.pace == Some(4.0));
/// assert!(cfg.validate().is_ok());
/// let thesis: PvsWalkConfig = PvsPrefetch::Snp.into();
/// assert!(!thesis.never_wait && thesis.pace.is_none());
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PvsWalkConfig {
    /// Which neighbours the client prefetches.
    pub prefetch: PvsPrefetch,
    /// The viewer's thread never waits on a read (ours): the client and its reads run
    /// on a loader thread, and each frame draws what has arrived.
    pub never_wait: bool,
    /// The path's clock runs this many times faster than real time: a never-wait
    /// walk's loader works in real time, so frames are played at their poses' times
    /// over this. `None`: frames back to back.
    pub pace: Option<f32>,
}

impl From<PvsPrefetch> for PvsWalkConfig {
    fn from(prefetch: PvsPrefetch) -> PvsWalkConfig {
        PvsWalkConfig {
            prefetch,
            never_wait: false,
            pace: None,
        }
    }
}

impl PvsWalkConfig {
    /// A never-wait walk with `prefetch`, played at
    /// [`DEFAULT_PACE`](crate::walk::settings::DEFAULT_PACE) times real time.
    pub fn never_waiting(prefetch: PvsPrefetch) -> PvsWalkConfig {
        PvsWalkConfig {
            prefetch,
            never_wait: true,
            pace: Some(crate::walk::settings::DEFAULT_PACE),
        }
    }

    /// Checks the rule's border and the pace (finite, above 0).
    pub fn validate(&self) -> Result<()> {
        self.prefetch.rule()?;
        match self.pace {
            Some(p) if !(p.is_finite() && p > 0.0) => Err(Error::Invalid(format!(
                "a PVS walk's pace must be a finite number of times real time above 0, not {p}"
            ))),
            _ => Ok(()),
        }
    }
}
