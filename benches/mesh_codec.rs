//! Mesh decoding (format versions 1 and 2): a citygen city's meshes decoded from the
//! bytes a database's mesh extents hold, raw floats against meshoptimizer's codecs
//! without and with zstd, and as a built database stores them (zstd with the dictionaries
//! its build trained on the city). Throughput is counted in the bytes the codecs decode to:
//! meshoptimizer's buffers (8-byte positions, 4-byte normals, 4-byte indices), the
//! unit of the "1 GB/s of decoded buffers a core"; the raw reader's bytes are
//! its extent's. Each decode also dequantises into the engine's f32 mesh.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use flaneur::scene::{Mesh, MeshCodec, SceneError, SceneObject};
use flaneur::store::PageKind;
use flaneur::{BuildOptions, Database};

/// The meshes of a 200-object city.
fn city() -> Vec<Mesh> {
    let config = citygen::CityConfig {
        objects: 200,
        seed: 1,
        ..Default::default()
    };
    let mut meshes = Vec::new();
    citygen::generate(&config, |o: SceneObject| -> Result<(), SceneError> {
        meshes.push(o.mesh);
        Ok(())
    })
    .unwrap();
    meshes
}

fn decode(c: &mut Criterion) {
    let meshes = city();
    let decoded: u64 = meshes
        .iter()
        .map(|m| (m.positions.len() * 12 + m.indices.len() * 4) as u64)
        .sum();
    let mut group = c.benchmark_group("mesh_decode");
    for (name, codec) in [
        ("raw", MeshCodec::Raw),
        ("meshopt", MeshCodec::Meshopt { zstd: None }),
        ("meshopt_zstd", MeshCodec::meshopt()),
    ] {
        let blobs: Vec<Vec<u8>> = meshes.iter().map(|m| codec.to_bytes(m).unwrap()).collect();
        let stored: u64 = blobs.iter().map(|b| b.len() as u64).sum();
        let bytes = if codec == MeshCodec::Raw {
            stored
        } else {
            decoded
        };
        group.throughput(Throughput::Bytes(bytes));
        group.bench_with_input(BenchmarkId::new(name, stored), &blobs, |b, blobs| {
            b.iter(|| {
                for blob in blobs {
                    black_box(MeshCodec::from_bytes(black_box(blob)).unwrap());
                }
            })
        });
    }
    // The same city built (format version 2's default zstd), its mesh extents as they lie
    // in the file, decoded with the file's dictionaries.
    let dir = tempfile::tempdir().unwrap();
    let (scene, db) = (
        dir.path().join("city.scene"),
        dir.path().join("city.flaneur"),
    );
    citygen::write_city(
        &citygen::CityConfig {
            objects: 200,
            seed: 1,
            ..Default::default()
        },
        &scene,
    )
    .unwrap();
    let opts = BuildOptions {
        codec: MeshCodec::meshopt(),
        ..Default::default()
    };
    flaneur::build_from_scene(&scene, &db, &opts).unwrap();
    let db = Database::open(&db).unwrap();
    let dict = db.store().dictionaries().unwrap();
    assert!(dict.is_some(), "the build trained no dictionaries");
    let blobs: Vec<Vec<u8>> = db
        .range(&db.bounds())
        .unwrap()
        .objects
        .iter()
        .map(|o| db.store().read_extent(&o.mesh, PageKind::Mesh).unwrap())
        .collect();
    let stored: u64 = blobs.iter().map(|b| b.len() as u64).sum();
    let decoded_here: u64 = blobs
        .iter()
        .map(|b| {
            let m = MeshCodec::from_bytes_with(b, dict.as_ref()).unwrap();
            (m.positions.len() * 12 + m.indices.len() * 4) as u64
        })
        .sum();
    group.throughput(Throughput::Bytes(decoded_here));
    group.bench_with_input(
        BenchmarkId::new("meshopt_zstd_dictionaries", stored),
        &blobs,
        |b, blobs| {
            b.iter(|| {
                for blob in blobs {
                    black_box(MeshCodec::from_bytes_with(black_box(blob), dict.as_ref()).unwrap());
                }
            })
        },
    );
    group.finish();
}

criterion_group!(benches, decode);
criterion_main!(benches);
