//! R-tree micro benches: bulk loading (objects/s), warm range queries against rstar in
//! memory on the same boxes, and CSearch against BOX on the same walk. Page counts of
//! the same queries are printed by `flaneur bench csearch`; here only time is measured.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use flaneur::geom::Aabb;
use flaneur::rtree::{History, RTree as PagedTree};
use flaneur::store::Store;
use flaneur::{path::street_walk, walk::disk_cell};
use flaneur::{BuildOptions, Database};
use rstar::{primitives::GeomWithData, primitives::Rectangle, RTree, AABB};

const OBJECTS: u64 = 20_000;

struct Fixture {
    _dir: tempfile::TempDir,
    db: Database,
    cells: Vec<Aabb>,
    rstar: RTree<GeomWithData<Rectangle<[f32; 3]>, u64>>,
}

fn fixture() -> Fixture {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("bench.scene");
    let path = dir.path().join("bench.flaneur");
    citygen::write_city(
        &citygen::CityConfig {
            objects: OBJECTS,
            landmarks: 0.0,
            ..Default::default()
        },
        &scene,
    )
    .unwrap();
    flaneur::build_from_scene(&scene, &path, &BuildOptions::default()).unwrap();
    let db = Database::open(&path).unwrap();
    let walk = street_walk(&db.bounds(), 200, 25.0, 24, 1).unwrap();
    let cells = walk
        .positions()
        .map(|p| disk_cell(p, 500.0, &db.bounds()).unwrap())
        .collect();
    let all = db.range(&db.bounds()).unwrap().objects;
    let rstar = RTree::bulk_load(
        all.iter()
            .map(|o| {
                GeomWithData::new(
                    Rectangle::from_corners(o.bounds.min.to_array(), o.bounds.max.to_array()),
                    o.id,
                )
            })
            .collect(),
    );
    Fixture {
        _dir: dir,
        db,
        cells,
        rstar,
    }
}

fn benches(c: &mut Criterion) {
    let f = fixture();
    let all = f.db.range(&f.db.bounds()).unwrap().objects;

    let mut g = c.benchmark_group("bulk_load");
    g.throughput(Throughput::Elements(all.len() as u64));
    g.sample_size(10);
    g.bench_function(BenchmarkId::new("str_4k_pages", all.len()), |b| {
        let dir = tempfile::tempdir().unwrap();
        b.iter(|| {
            let mut store = Store::create(&dir.path().join("bulk.flaneur"), 4096).unwrap();
            black_box(PagedTree::bulk_load(&mut store, all.clone(), 1.0).unwrap());
        })
    });
    g.finish();

    let mut g = c.benchmark_group("range_walk_200_cells");
    g.throughput(Throughput::Elements(f.cells.len() as u64));
    g.bench_function("paged_rtree_mmap_warm", |b| {
        b.iter(|| {
            for cell in &f.cells {
                black_box(f.db.range(cell).unwrap());
            }
        })
    });
    g.bench_function("rstar_in_memory", |b| {
        b.iter(|| {
            for cell in &f.cells {
                let q = AABB::from_corners(cell.min.to_array(), cell.max.to_array());
                black_box(
                    f.rstar
                        .locate_in_envelope_intersecting(&q)
                        .map(|g| g.data)
                        .collect::<Vec<u64>>(),
                );
            }
        })
    });
    g.bench_function("csearch_walk", |b| {
        b.iter(|| {
            let mut history = History::default();
            for cell in &f.cells {
                black_box(f.db.csearch_step(&mut history, cell).unwrap());
            }
        })
    });
    g.finish();
}

criterion_group! {
    name = rtree;
    config = Criterion::default().measurement_time(Duration::from_secs(4)).warm_up_time(Duration::from_secs(1));
    targets = benches
}
criterion_main!(rtree);
