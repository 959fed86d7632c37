// Streaming a whole city: objects are built in ordered chunks on the rayon pool while
// the caller's sink consumes the previous chunk on this thread, so both cores stay busy,
// output stays in id order (and so byte-identical at any thread count), and memory
// holds at most a few chunks whatever the object count.

use std::path::Path;
use std::sync::mpsc::sync_channel;

use rayon::prelude::*;

use crate::config::CityConfig;
use crate::recipe::{checked_layout, object_on};
use flaneur_scene::SceneError;
use flaneur_scene::SceneObject;
use flaneur_scene::{SceneSummary, SceneWriter};

/// Objects built together in one parallel batch.
const CHUNK: u64 = 256;
/// Finished chunks that may wait for the sink (bounds memory).
const CHUNKS_IN_FLIGHT: usize = 2;

/// Streams every object of `config` to `sink`, in id order `0..objects`, stopping at the
/// sink's first error and returning it. Memory stays bounded: a few chunks of objects.
/// A config that fails [`CityConfig::validate`] is a `SceneError::Config`, converted
/// into the sink's error type.
///
/// ```
/// let config = citygen::CityConfig { objects: 30, seed: 9, ..Default::default() };
/// let mut ids = Vec::new();
/// citygen::generate(&config, |o| {
///     ids.push(o.id);
///     Ok::<(), citygen::SceneError>(())
/// })
/// .unwrap();
/// assert_eq!(ids, (0..30).collect::<Vec<u64>>());
/// ```
pub fn generate<E: From<SceneError>>(
    config: &CityConfig,
    mut sink: impl FnMut(SceneObject) -> Result<(), E>,
) -> Result<(), E> {
    let layout = checked_layout(config)?;
    let objects = config.objects;
    std::thread::scope(|scope| {
        let (tx, rx) = sync_channel::<Vec<SceneObject>>(CHUNKS_IN_FLIGHT);
        let layout = &layout;
        scope.spawn(move || {
            let mut start = 0;
            while start < objects {
                let len = CHUNK.min(objects - start);
                let chunk: Vec<SceneObject> = (0..len as usize)
                    .into_par_iter()
                    .map(|k| object_on(config, layout, start + k as u64))
                    .collect();
                if tx.send(chunk).is_err() {
                    return; // the sink stopped
                }
                start += len;
            }
        });
        for chunk in rx {
            for object in chunk {
                sink(object)?;
            }
        }
        Ok(())
    })
}

/// Generates the city `config` into a scene file at `path`.
pub fn write_city(config: &CityConfig, path: &Path) -> Result<SceneSummary, SceneError> {
    write_city_with_progress(config, path, |_| {})
}

/// [`write_city`], telling `progress` how many objects are written so far (of
/// `config.objects`), so that a caller can draw a bar: the library draws none.
///
/// ```
/// let dir = tempfile::tempdir().unwrap();
/// let config = citygen::CityConfig { objects: 30, landmarks: 0.0, ..Default::default() };
/// let mut last = 0;
/// citygen::write_city_with_progress(&config, &dir.path().join("c.scene"), |n| last = n).unwrap();
/// assert_eq!(last, 30);
/// ```
pub fn write_city_with_progress(
    config: &CityConfig,
    path: &Path,
    mut progress: impl FnMut(u64),
) -> Result<SceneSummary, SceneError> {
    config.validate()?;
    let mut writer = SceneWriter::create(path)?;
    let mut written = 0u64;
    generate(config, |object| {
        writer.write(&object)?;
        written += 1;
        progress(written);
        Ok::<(), SceneError>(())
    })?;
    writer.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sink_error_stops_generation_and_is_returned() {
        let config = CityConfig {
            objects: 5000,
            landmarks: 0.0,
            ..Default::default()
        };
        let mut seen = 0u64;
        let result = generate(&config, |o| {
            assert_eq!(o.id, seen);
            seen += 1;
            if o.id == 300 {
                Err(SceneError::Config(format!("stop at {}", o.id)))
            } else {
                Ok(())
            }
        });
        assert!(matches!(result, Err(SceneError::Config(m)) if m == "stop at 300"));
        assert_eq!(seen, 301);
    }

    #[test]
    fn a_bad_config_is_an_error_not_a_panic() {
        let config = CityConfig {
            objects: 0,
            ..Default::default()
        };
        assert!(matches!(
            generate(&config, |_| Ok::<(), SceneError>(())),
            Err(SceneError::Config(_))
        ));
        assert!(matches!(
            crate::object(&config, 0),
            Err(SceneError::Config(_))
        ));
    }

    #[test]
    fn write_city_refuses_a_bad_config_before_creating_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.scene");
        let config = CityConfig {
            objects: 0,
            ..Default::default()
        };
        assert!(matches!(
            write_city(&config, &path),
            Err(SceneError::Config(_))
        ));
        assert!(!path.exists());
    }
}
