// What stands at each id. Every object is a pure function of (config, id): its random
// stream is ChaCha8 seeded from a hash of (seed, id), its lot comes from the layout, and
// whether it is a landmark from another hash. That independence is what lets `generate`
// build objects on any number of threads, and `export_obj` rebuild one region, and
// still agree byte for byte with a scene written on one core.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::archetypes::building;
use crate::bunny_landmark::bunny_landmark;
use crate::config::CityConfig;
use crate::layout::Layout;
use crate::sculpture::sculpture;
use flaneur_scene::SceneError;
use flaneur_scene::{Mesh, ObjectKind, SceneObject};

/// Salts that keep the independent per-id draws apart.
const STREAM_SALT: u64 = 0x6f62_6a65_6374_0001;
const LANDMARK_SALT: u64 = 0x6c61_6e64_6d61_726b;
const FORCED_SALT: u64 = 0x666f_7263_6564_0001;

/// SplitMix64's finaliser: a bijective 64-bit mix.
fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A hash of (seed, id, salt).
fn mix(seed: u64, id: u64, salt: u64) -> u64 {
    splitmix(splitmix(seed ^ salt) ^ id)
}

/// The id that is a landmark whatever the draw, so a city of 100 objects or more with a
/// non-zero landmark share always has at least one.
fn forced_landmark(config: &CityConfig) -> Option<u64> {
    (config.landmarks > 0.0 && config.objects >= 100)
        .then(|| mix(config.seed, 0, FORCED_SALT) % config.objects)
}

/// Whether object `id` of `config` is a high-detail landmark.
pub(crate) fn is_landmark(config: &CityConfig, id: u64) -> bool {
    if config.landmarks <= 0.0 {
        return false;
    }
    let u = (mix(config.seed, id, LANDMARK_SALT) >> 11) as f64 / (1u64 << 53) as f64;
    u < config.landmarks as f64 || forced_landmark(config) == Some(id)
}

/// The street layout of a checked `config`: a `Config` error when it is out of range.
pub(crate) fn checked_layout(config: &CityConfig) -> Result<Layout, SceneError> {
    config.validate()?;
    Layout::new(config)
        .ok_or_else(|| SceneError::Config("the city has no room for its lots".into()))
}

/// Object `id` of the city `config`: deterministic, and independent of every other id.
///
/// Ids at or past `config.objects` continue the street grid beyond the city.
///
/// A `SceneError::Config` when `config` fails [`CityConfig::validate`].
///
/// ```
/// let config = citygen::CityConfig { objects: 100, ..Default::default() };
/// let a = citygen::object(&config, 42)?;
/// assert_eq!(a, citygen::object(&config, 42)?);
/// assert!(a.mesh.validate().is_ok());
/// # Ok::<(), citygen::SceneError>(())
/// ```
pub fn object(config: &CityConfig, id: u64) -> Result<SceneObject, SceneError> {
    Ok(object_on(config, &checked_layout(config)?, id))
}

/// The first building of at least `triangles` triangles in the default city of 64
/// ordinary objects: flat-shaded, so that every corner and crease is a seam. The mesh
/// tests and fuzzers of crease handling share; `None` past what such a city holds.
///
/// ```
/// let b = citygen::sample_building(600).unwrap();
/// assert!(b.triangle_count() >= 600);
/// ```
pub fn sample_building(triangles: usize) -> Option<Mesh> {
    let config = CityConfig {
        objects: 64,
        landmarks: 0.0,
        ..Default::default()
    };
    let layout = checked_layout(&config).ok()?;
    (0..config.objects)
        .map(|id| object_on(&config, &layout, id).mesh)
        .find(|m| m.triangle_count() >= triangles)
}

/// [`object`] with the layout already built (it is the same for every id).
pub(crate) fn object_on(config: &CityConfig, layout: &Layout, id: u64) -> SceneObject {
    let mut rng = ChaCha8Rng::seed_from_u64(mix(config.seed, id, STREAM_SALT));
    let lot = layout.lot(id);
    let (kind, mesh) = if is_landmark(config, id) {
        if rng.gen_bool(1.0 / 3.0) {
            (ObjectKind::Bunny, bunny_landmark(&mut rng, &lot))
        } else {
            (ObjectKind::Sculpture, sculpture(&mut rng, &lot))
        }
    } else {
        building(&mut rng, &lot)
    };
    SceneObject { id, kind, mesh }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn landmark_share_is_respected() {
        let c = CityConfig {
            objects: 100_000,
            landmarks: 0.01,
            ..Default::default()
        };
        let n = (0..c.objects).filter(|&id| is_landmark(&c, id)).count();
        assert!((800..=1200).contains(&n), "{n}");
        let none = CityConfig {
            landmarks: 0.0,
            ..c.clone()
        };
        assert!((0..1000).all(|id| !is_landmark(&none, id)));
    }

    #[test]
    fn small_cities_get_at_least_one_landmark() {
        for seed in 0..20 {
            let c = CityConfig {
                objects: 100,
                seed,
                landmarks: 0.001,
                ..Default::default()
            };
            assert!((0..c.objects).any(|id| is_landmark(&c, id)), "seed {seed}");
        }
    }
}
