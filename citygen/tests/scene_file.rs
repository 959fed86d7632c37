// The scene file end to end, on real files: determinism, round trips, and that every
// kind of damage (a cut, a flipped byte, a wrong magic, an absurd count) is reported as
// the right error, naming the file, and never panics or allocates wildly.

use std::path::{Path, PathBuf};

use citygen::{generate, write_city, CityConfig, SceneError, SceneReader, SceneWriter};

fn small(seed: u64) -> CityConfig {
    CityConfig {
        objects: 60,
        seed,
        landmarks: 0.0,
        ..Default::default()
    }
}

fn write(dir: &Path, name: &str, config: &CityConfig) -> PathBuf {
    let path = dir.join(name);
    write_city(config, &path).unwrap();
    path
}

fn read_all(path: &Path) -> Result<Vec<citygen::SceneObject>, SceneError> {
    SceneReader::open(path)?.collect()
}

#[test]
fn same_seed_same_bytes_different_seed_different_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let a = std::fs::read(write(dir.path(), "a.scene", &small(5))).unwrap();
    let b = std::fs::read(write(dir.path(), "b.scene", &small(5))).unwrap();
    let c = std::fs::read(write(dir.path(), "c.scene", &small(6))).unwrap();
    assert!(a == b, "same config, different bytes");
    assert!(a != c, "different seeds, same bytes");
}

#[test]
fn parallel_generation_matches_one_object_at_a_time() {
    let dir = tempfile::tempdir().unwrap();
    let config = CityConfig {
        objects: 600,
        landmarks: 0.0,
        ..Default::default()
    };
    let parallel = std::fs::read(write(dir.path(), "parallel.scene", &config)).unwrap();
    // No rayon, no pipeline: each object built alone, in order, on this thread.
    let path = dir.path().join("serial.scene");
    let mut w = SceneWriter::create(&path).unwrap();
    for id in 0..config.objects {
        w.write(&citygen::object(&config, id).unwrap()).unwrap();
    }
    w.finish().unwrap();
    assert!(parallel == std::fs::read(path).unwrap());
}

#[test]
fn round_trip_keeps_everything_but_normal_precision() {
    let dir = tempfile::tempdir().unwrap();
    let config = CityConfig {
        objects: 120,
        seed: 11,
        landmarks: 0.02,
        ..Default::default()
    };
    let path = dir.path().join("city.scene");
    let summary = write_city(&config, &path).unwrap();
    assert_eq!(summary.objects, 120);
    assert_eq!(summary.bytes, std::fs::metadata(&path).unwrap().len());

    let reader = SceneReader::open(&path).unwrap();
    assert_eq!(reader.object_count(), 120);
    let mut read = reader;
    let mut triangles = 0;
    let mut landmarks = 0;
    generate(&config, |want| {
        let got = read.next().expect("an object per id").unwrap();
        assert_eq!((got.id, got.kind), (want.id, want.kind));
        assert_eq!(got.mesh.positions, want.mesh.positions);
        assert_eq!(got.mesh.indices, want.mesh.indices);
        for (g, w) in got.mesh.normals.iter().zip(&want.mesh.normals) {
            let dot: f32 = (0..3).map(|k| g[k] * w[k]).sum();
            assert!(dot > 0.999, "normal {w:?} came back as {g:?}");
        }
        triangles += got.mesh.triangle_count() as u64;
        landmarks += got.kind.is_landmark() as u32;
        Ok::<(), SceneError>(())
    })
    .unwrap();
    assert!(read.next().is_none());
    assert_eq!(triangles, summary.triangles);
    assert!(landmarks >= 1);
}

#[test]
fn a_file_cut_short_is_truncated_or_corrupt() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "city.scene", &small(1));
    let bytes = std::fs::read(&path).unwrap();
    let cut_path = dir.path().join("cut.scene");
    let len = bytes.len();
    for cut in [
        0,
        5,
        16,
        17,
        40,
        1000,
        len / 3,
        len / 2,
        len - 25,
        len - 24,
        len - 10,
        len - 1,
    ] {
        std::fs::write(&cut_path, &bytes[..cut]).unwrap();
        match read_all(&cut_path) {
            Err(SceneError::Truncated { path, what }) => {
                assert_eq!(path, cut_path);
                assert!(what.contains("object") || what.contains("header"), "{what}");
            }
            Err(SceneError::Corrupt { .. }) => {}
            other => panic!("cut at {cut} of {len}: {:?}", other.map(|v| v.len())),
        }
    }
    // A cut mid-file names the object it falls in.
    std::fs::write(&cut_path, &bytes[..len / 2]).unwrap();
    let err = read_all(&cut_path).unwrap_err();
    assert!(matches!(err, SceneError::Truncated { .. }), "{err}");
    let msg = err.to_string();
    assert!(
        msg.contains("cut.scene") && msg.contains("inside object"),
        "{msg}"
    );
}

#[test]
fn a_flipped_byte_is_corrupt() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "city.scene", &small(2));
    let bytes = std::fs::read(&path).unwrap();
    let bad = dir.path().join("bad.scene");
    // In the first record's positions, in a later record, in the trailer's count.
    for at in [16 + 30, bytes.len() / 2, bytes.len() - 24 + 9] {
        let mut b = bytes.clone();
        b[at] ^= 0x10;
        std::fs::write(&bad, &b).unwrap();
        match read_all(&bad) {
            Err(SceneError::Corrupt { path, what, .. }) => {
                assert_eq!(path, bad);
                assert!(!what.is_empty());
            }
            other => panic!("flip at {at}: {:?}", other.map(|v| v.len())),
        }
    }
    // Anywhere at all: some error, never a panic and never a clean read.
    for at in (0..bytes.len()).step_by(997) {
        let mut b = bytes.clone();
        b[at] ^= 0x01;
        std::fs::write(&bad, &b).unwrap();
        assert!(read_all(&bad).is_err(), "flip at {at} went unnoticed");
    }
}

#[test]
fn wrong_magic_is_not_a_scene() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "city.scene", &small(3));
    let mut bytes = std::fs::read(&path).unwrap();
    bytes[0] = b'X';
    std::fs::write(&path, &bytes).unwrap();
    assert!(matches!(
        SceneReader::open(&path),
        Err(SceneError::NotAScene { .. })
    ));
    let text = dir.path().join("notes.txt");
    std::fs::write(
        &text,
        "just some text, long enough to have a trailer-sized tail",
    )
    .unwrap();
    let err = SceneReader::open(&text).err().expect("not a scene");
    assert!(matches!(err, SceneError::NotAScene { .. }));
    assert!(err.to_string().contains("notes.txt"));
    let missing = SceneReader::open(&dir.path().join("missing.scene"))
        .err()
        .expect("no file");
    assert!(matches!(missing, SceneError::Io { .. }));
}

#[test]
fn a_huge_corrupt_count_is_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "city.scene", &small(4));
    let mut bytes = std::fs::read(&path).unwrap();
    // The first record's vertex count (header 16 + id 8 + kind 1 + flags 1).
    for count in [u32::MAX, 15 << 20] {
        bytes[26..30].copy_from_slice(&count.to_le_bytes());
        std::fs::write(&path, &bytes).unwrap();
        match read_all(&path) {
            Err(SceneError::Corrupt {
                object: 0, what, ..
            }) => assert!(what.contains("vert") || what.contains("need"), "{what}"),
            other => panic!("{:?}", other.map(|v| v.len())),
        }
    }
}

#[test]
fn writer_refuses_bad_objects() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("w.scene");
    let mut w = SceneWriter::create(&path).unwrap();
    let o = citygen::object(&small(1), 3).unwrap();
    w.write(&o).unwrap();
    assert!(w.write(&o).is_err(), "repeated id");
    let mut broken = citygen::object(&small(1), 4).unwrap();
    broken.mesh.indices.push(0);
    assert!(w.write(&broken).is_err(), "invalid mesh");
    let s = w.finish().unwrap();
    assert_eq!(s.objects, 1);
    assert_eq!(read_all(&path).unwrap().len(), 1);
}

#[test]
fn an_empty_scene_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("empty.scene");
    let s = SceneWriter::create(&path).unwrap().finish().unwrap();
    assert_eq!(
        s,
        citygen::SceneSummary {
            objects: 0,
            triangles: 0,
            bytes: 40
        }
    );
    let r = SceneReader::open(&path).unwrap();
    assert_eq!(r.object_count(), 0);
    assert_eq!(r.count(), 0);
}
