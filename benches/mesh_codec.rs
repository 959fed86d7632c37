//! Mesh decoding (format versions 1 and 2): a citygen city's meshes decoded from the
//! bytes a database's mesh extents hold, raw floats against meshoptimizer's codecs
//! without and with zstd. Throughput is counted in the bytes the codecs decode to:
//! meshoptimizer's buffers (8-byte positions, 4-byte normals, 4-byte indices), the
//! unit of the "1 GB/s of decoded buffers a core"; the raw reader's bytes are
//! its extent's. Each decode also dequantises into the engine's f32 mesh.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use flaneur::scene::{Mesh, MeshCodec, SceneError, SceneObject};

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
        ("meshopt_zstd3", MeshCodec::meshopt()),
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
    group.finish();
}

criterion_group!(benches, decode);
criterion_main!(benches);
