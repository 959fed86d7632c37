// The knobs of a generated city and their legal ranges. Everything that places or sizes
// an object derives from this one value, so that a config plus an id is all it takes to
// rebuild any object of any city, on any machine, in any order.

use crate::layout::Layout;
use flaneur_scene::SceneError;

/// The most objects a city may have. A million is the intended scale; ten times that
/// still streams in bounded memory, it only takes disk.
pub const MAX_OBJECTS: u64 = 10_000_000;

/// How a city is generated. Two equal configs give byte-identical scene files.
///
/// ```
/// let config = citygen::CityConfig { objects: 50, seed: 7, ..Default::default() };
/// config.validate().unwrap();
/// assert!(config.extent() > 0.0);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct CityConfig {
    /// Number of objects (one per lot), `1..=10_000_000`.
    pub objects: u64,
    /// The seed; any value.
    pub seed: u64,
    /// Side of the square city in metres; `None` derives the smallest square that
    /// holds every lot, block and street. A larger extent spreads the grid wider.
    pub extent: Option<f32>,
    /// Share of objects that are high-detail landmarks, `0.0..=1.0`.
    pub landmarks: f32,
    /// Lot pitch: metres between neighbouring building lots, `10.0..=30.0`.
    pub spacing: f32,
    /// Lots per block side, `1..=64`.
    pub block: u32,
    /// Width of the streets between blocks in metres, `0.0..=100.0`.
    pub street_width: f32,
}

impl Default for CityConfig {
    fn default() -> Self {
        CityConfig {
            objects: 1000,
            seed: 1,
            extent: None,
            landmarks: 0.001,
            spacing: 20.0,
            block: 4,
            street_width: 14.0,
        }
    }
}

impl CityConfig {
    /// The side of the city square in metres: the configured extent, or the derived one.
    /// Meaningful only for a config that passes [`validate`](Self::validate).
    pub fn extent(&self) -> f32 {
        self.extent
            .unwrap_or_else(|| Layout::derived_extent(self) as f32)
    }

    /// Checks every field's range, and that an explicit extent holds all the lots.
    pub fn validate(&self) -> Result<(), SceneError> {
        let bad = |what: String| Err(SceneError::Config(what));
        if self.objects == 0 || self.objects > MAX_OBJECTS {
            return bad(format!(
                "objects must be in 1..={MAX_OBJECTS}, not {}",
                self.objects
            ));
        }
        if !(0.0..=1.0).contains(&self.landmarks) {
            return bad(format!(
                "landmarks is a share of the objects, in 0..=1, not {}",
                self.landmarks
            ));
        }
        if !(10.0..=30.0).contains(&self.spacing) {
            return bad(format!(
                "spacing (the lot pitch) must be 10..=30 metres, not {}",
                self.spacing
            ));
        }
        if !(1..=64).contains(&self.block) {
            return bad(format!(
                "block (lots per block side) must be in 1..=64, not {}",
                self.block
            ));
        }
        if !(0.0..=100.0).contains(&self.street_width) {
            return bad(format!(
                "street width must be 0..=100 metres, not {}",
                self.street_width
            ));
        }
        if let Some(e) = self.extent {
            if !(e.is_finite() && e > 0.0) {
                return bad(format!(
                    "extent must be a positive number of metres, not {e}"
                ));
            }
            if e > 1.0e6 {
                return bad(format!("extent must be at most 1,000,000 metres, not {e}"));
            }
            let need = Layout::derived_extent(self);
            if Layout::new(self).is_none() {
                return bad(format!(
                    "extent {e} m is too small for {} objects at {} m spacing in blocks of {} \
                     with {} m streets: it needs about {need:.1} m",
                    self.objects, self.spacing, self.block, self.street_width
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_valid() {
        assert!(CityConfig::default().validate().is_ok());
    }

    #[test]
    fn bad_configs_are_config_errors() {
        let d = CityConfig::default();
        let cases = [
            CityConfig {
                objects: 0,
                ..d.clone()
            },
            CityConfig {
                objects: MAX_OBJECTS + 1,
                ..d.clone()
            },
            CityConfig {
                landmarks: 2.0,
                ..d.clone()
            },
            CityConfig {
                landmarks: -0.1,
                ..d.clone()
            },
            CityConfig {
                landmarks: f32::NAN,
                ..d.clone()
            },
            CityConfig {
                spacing: 5.0,
                ..d.clone()
            },
            CityConfig {
                spacing: f32::INFINITY,
                ..d.clone()
            },
            CityConfig {
                block: 0,
                ..d.clone()
            },
            CityConfig {
                street_width: -1.0,
                ..d.clone()
            },
            CityConfig {
                street_width: f32::NAN,
                ..d.clone()
            },
            CityConfig {
                extent: Some(f32::NAN),
                ..d.clone()
            },
            CityConfig {
                extent: Some(-5.0),
                ..d.clone()
            },
            CityConfig {
                extent: Some(50.0),
                ..d.clone()
            },
        ];
        for c in cases {
            match c.validate() {
                Err(SceneError::Config(msg)) => assert!(!msg.is_empty()),
                other => panic!("{c:?} gave {other:?}"),
            }
        }
    }

    #[test]
    fn explicit_extent_at_least_derived_is_valid() {
        let d = CityConfig {
            objects: 5000,
            ..Default::default()
        };
        let e = d.extent();
        assert!(CityConfig {
            extent: Some(e),
            ..d.clone()
        }
        .validate()
        .is_ok());
        assert!(CityConfig {
            extent: Some(e * 1.5),
            ..d.clone()
        }
        .validate()
        .is_ok());
        assert!(CityConfig {
            extent: Some(e * 0.7),
            ..d
        }
        .validate()
        .is_err());
    }
}
