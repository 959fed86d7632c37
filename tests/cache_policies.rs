//! The index cache on a real walk (Shou 2002 §4.2.4, §4.4): a buffer pool under the
//! R-tree changes no result, its misses are exactly the store's physical reads, it
//! stays within its budget, a recorded trace replays to the live pool's counts, and
//! no online policy beats Belady's optimum on it.

mod common;

use flaneur::cache::{belady_replay, policy_by_name, BufferPool, CacheStats, Trace, POLICY_NAMES};
use flaneur::geom::Aabb;
use flaneur::rtree::{Coverlap, History, QueryResult};
use flaneur::store::PageSource;
use flaneur::{path::street_walk, walk::disk_cell};
use flaneur::{BuildOptions, Database};

const PAGE: usize = 1024;

fn small_city() -> (common::City, Database) {
    let city = common::city(
        3000,
        5,
        &BuildOptions {
            page_size: PAGE,
            ..Default::default()
        },
    );
    let db = Database::open(&city.db).unwrap();
    (city, db)
}

/// The walk's queries: per step, a CSearch disk cell and a smaller BOX around the eye.
fn walk_cells(db: &Database) -> Vec<(Aabb, Aabb)> {
    let path = street_walk(&db.bounds(), 200, 15.0, 10, 3).unwrap();
    path.positions()
        .map(|eye| {
            (
                disk_cell(eye, 300.0, &db.bounds()).unwrap(),
                disk_cell(eye, 120.0, &db.bounds()).unwrap(),
            )
        })
        .collect()
}

/// Runs the walk through `pages`, calling `after` after every query.
fn walk<P: PageSource + ?Sized>(
    db: &Database,
    pages: &P,
    cells: &[(Aabb, Aabb)],
    mut after: impl FnMut(),
) -> Vec<QueryResult> {
    let mut history = History::default();
    let mut out = Vec::new();
    for (disk, view) in cells {
        out.push(
            db.tree()
                .csearch_step(pages, &mut history, disk, Coverlap::default())
                .unwrap(),
        );
        after();
        out.push(db.tree().range(pages, view).unwrap());
        after();
    }
    out
}

/// The walk through a fresh pool of `capacity` pages with `policy`: its results,
/// counts and trace.
fn live(
    db: &Database,
    cells: &[(Aabb, Aabb)],
    policy: &str,
    capacity: usize,
) -> (Vec<QueryResult>, CacheStats, Trace) {
    let pool =
        BufferPool::new(db.store(), capacity * PAGE, policy_by_name(policy).unwrap()).unwrap();
    pool.set_trace(true);
    db.reset_io();
    let results = walk(db, &pool, cells, || {
        assert!(pool.resident_bytes() <= pool.budget_bytes())
    });
    let stats = pool.stats();
    assert_eq!(
        db.io().page_reads,
        stats.misses,
        "{policy} at {capacity} pages: physical reads against misses"
    );
    (results, stats, pool.take_trace())
}

#[test]
fn the_pool_changes_no_result_and_its_misses_are_the_physical_reads() {
    let (_city, db) = small_city();
    let cells = walk_cells(&db);
    let direct = walk(&db, db.store(), &cells, || {});
    assert!(direct.iter().map(|r| r.objects.len()).sum::<usize>() > 0);
    for policy in POLICY_NAMES {
        for capacity in [1, 8, 32] {
            let (results, stats, _) = live(&db, &cells, policy, capacity);
            assert_eq!(results, direct, "{policy} at {capacity} pages");
            let pages: u64 = direct.iter().map(|r| r.pages.len() as u64).sum();
            assert_eq!(stats.accesses(), pages);
        }
    }
}

#[test]
fn a_trace_survives_csv_and_no_policy_beats_belady() {
    let (city, db) = small_city();
    let cells = walk_cells(&db);
    let (_, _, trace) = live(&db, &cells, "lru", 16);
    assert!(
        trace.len() > 500 && trace.distinct_pages() > 40,
        "{} accesses of {} pages",
        trace.len(),
        trace.distinct_pages()
    );
    let path = city.dir.path().join("walk.trace.csv");
    trace.write_csv(&path).unwrap();
    let back = Trace::read_csv(&path).unwrap();
    assert_eq!(back, trace);
    for capacity in [1, 2, 4, 8, 16, 32, 64, 128, 1024] {
        let best = belady_replay(&back, capacity);
        assert_eq!(best.accesses(), back.len() as u64);
        for policy in POLICY_NAMES {
            let got = back.replay(policy_by_name(policy).unwrap(), capacity);
            assert_eq!(got.accesses(), best.accesses());
            assert!(
                got.hit_rate() <= best.hit_rate(),
                "{policy} at {capacity} pages: {:.4} above Belady's {:.4}",
                got.hit_rate(),
                best.hit_rate()
            );
        }
    }
    // With room for every page, every policy misses each page once.
    let all = back.distinct_pages();
    for policy in POLICY_NAMES {
        assert_eq!(
            back.replay(policy_by_name(policy).unwrap(), all).misses,
            all as u64
        );
    }
}

#[test]
fn a_replay_gives_the_live_pools_counts() {
    let (_city, db) = small_city();
    let cells = walk_cells(&db);
    let mut report = String::new();
    for capacity in [8, 16, 32] {
        let mut trace = None;
        for policy in POLICY_NAMES {
            let (_, stats, t) = live(&db, &cells, policy, capacity);
            assert_eq!(
                t.replay(policy_by_name(policy).unwrap(), capacity),
                stats,
                "{policy} at {capacity} pages"
            );
            report += &format!(
                "{capacity:>4} pages  {policy:<8} hit rate {:.4}  ({stats:?})\n",
                stats.hit_rate()
            );
            // The access sequence does not depend on the policy.
            if let Some(prev) = &trace {
                assert_eq!(&t, prev);
            }
            trace = Some(t);
        }
        let best = belady_replay(trace.as_ref().unwrap(), capacity);
        report += &format!(
            "{capacity:>4} pages  {:<8} hit rate {:.4}  ({best:?})\n",
            "belady",
            best.hit_rate()
        );
    }
    // Shown with --nocapture: the figures the policies reach on this walk.
    eprintln!("{report}");
}
