//! Index-cache micro benches (Shou 2002 §4.2.4, §5.7): the cost of a `BufferPool::get`
//! served from the cache and of one that misses (a verified page read from an mmapped
//! store, plus the policy's choice of victim), per policy, at 256 pages — the thesis's
//! 1 MB of 4 KiB nodes; and the victim scan of distance-priority LRU at 256 and 4096
//! entries. Hit rates are not measured here: `flaneur bench index-cache` reports them.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use flaneur::cache::{policy_by_name, BufferPool, DpLru, Hint, Policy, POLICY_NAMES};
use flaneur::geom::Aabb;
use flaneur::store::{Backend, PageKind, PageSource, Store};

const PAGE: usize = 1024;
const PAGES: u64 = 8192;
const CAPACITY: usize = 256;
const HEIGHT: u32 = 3;

/// A tree-like hint for page index `i`: index 0 is the root, every 32nd an internal
/// node, the rest leaves, laid out on a 10 m grid.
fn hint(i: u64) -> Hint {
    let level = if i == 0 {
        2
    } else if i.is_multiple_of(32) {
        1
    } else {
        0
    };
    let (x, z) = ((i % 128) as f32 * 10.0, (i / 128) as f32 * 10.0);
    Hint {
        level,
        height: HEIGHT,
        mbr: Aabb::new([x, 0.0, z], [x + 10.0, 30.0, z + 10.0]).unwrap(),
        dov: (i % 97) as f32 / 970.0,
    }
}

fn query(step: u64) -> Aabb {
    let x = (step % 128) as f32 * 10.0;
    Aabb::new([x, 0.0, 0.0], [x + 100.0, 30.0, 300.0]).unwrap()
}

fn benches(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pages.flaneur");
    let mut store = Store::create(&path, PAGE).unwrap();
    let payload = vec![0x5Au8; PAGE - 64];
    let first = store.append_page(PageKind::RtreeNode, &payload).unwrap();
    for _ in 1..PAGES {
        store.append_page(PageKind::RtreeNode, &payload).unwrap();
    }
    store.finish().unwrap();
    let store = Store::open(&path, Backend::Mmap).unwrap();
    let hints: Vec<Hint> = (0..PAGES).map(hint).collect();

    let mut g = c.benchmark_group("cache_get_256_pages");
    for policy in POLICY_NAMES {
        g.bench_function(BenchmarkId::new("hit", policy), |b| {
            let pool =
                BufferPool::new(&store, CAPACITY * PAGE, policy_by_name(policy).unwrap()).unwrap();
            let mut buf = Vec::with_capacity(PAGE);
            for i in 0..CAPACITY as u64 {
                pool.get(first + i, PageKind::RtreeNode, &hints[i as usize], &mut buf)
                    .unwrap();
            }
            let mut i = 0u64;
            b.iter(|| {
                i = (i + 1) % CAPACITY as u64;
                if i == 0 {
                    pool.end_search();
                }
                pool.get(first + i, PageKind::RtreeNode, &hints[i as usize], &mut buf)
                    .unwrap();
                black_box(&buf);
            });
            assert_eq!(
                pool.stats().misses,
                CAPACITY as u64,
                "{policy}: every timed get is a hit"
            );
        });
        g.bench_function(BenchmarkId::new("miss", policy), |b| {
            let pool =
                BufferPool::new(&store, CAPACITY * PAGE, policy_by_name(policy).unwrap()).unwrap();
            let mut buf = Vec::with_capacity(PAGE);
            let mut i = 0u64;
            b.iter(|| {
                // A sweep over 32× the capacity: (almost) every get misses and evicts.
                i = (i + 1) % PAGES;
                if i.is_multiple_of(64) {
                    pool.end_search();
                    pool.begin_search(&query(i / 64));
                }
                pool.get(first + i, PageKind::RtreeNode, &hints[i as usize], &mut buf)
                    .unwrap();
                black_box(&buf);
            });
            let s = pool.stats();
            assert!(s.hit_rate() < 0.05, "{policy}: {s:?}");
        });
    }
    g.finish();

    let mut g = c.benchmark_group("dplru_victim_then_insert");
    for n in [256u64, 4096] {
        g.bench_function(BenchmarkId::from_parameter(n), |b| {
            let mut p = DpLru::default();
            for k in 0..n {
                p.on_insert(k, &hints[k as usize]);
                if k % 64 == 0 {
                    p.end_search();
                }
            }
            let q = query(3);
            let mut next = n;
            b.iter(|| {
                let v = p.victim(black_box(&q)).unwrap();
                p.on_insert(next, &hints[(next % PAGES) as usize]);
                next += 1;
                black_box(v)
            });
            assert_eq!(p.len() as u64, n);
        });
    }
    g.finish();
}

criterion_group!(cache, benches);
criterion_main!(cache);
