//! The I/O claim of CSearch (Shou 2002 §4.4): along a walk of consecutive,
//! overlapping cells it reads at most a quarter of the pages BOX reads. Page counts
//! are exact, so this compares counts, not times.

mod common;

use flaneur::rtree::History;
use flaneur::{path::street_walk, walk::disk_cell};
use flaneur::{BuildOptions, Database};
use flaneur_bench::csearch::{self, CsearchConfig};

fn small_city() -> common::City {
    // 1 KiB pages keep the tree's leaves small next to the cells, as 4 KiB pages are
    // next to kilometre cells in a big city.
    common::city(
        3000,
        5,
        &BuildOptions {
            page_size: 1024,
            ..Default::default()
        },
    )
}

#[test]
fn csearch_reads_at_most_a_quarter_of_box_pages_along_a_walk() {
    let city = small_city();
    let db = Database::open(&city.db).unwrap();
    let cfg = CsearchConfig {
        cell: 600.0,
        step: 10.0,
        steps: 120,
        ..Default::default()
    };
    let report = csearch::run(&db, &cfg).unwrap();
    assert!(report.box_pages > 0);
    assert!(
        report.csearch_pages * 4 <= report.box_pages,
        "CSearch read {} pages, BOX {} ({:.1}%)",
        report.csearch_pages,
        report.box_pages,
        report.ratio * 100.0
    );
    // And the same on the thesis's insertion-built tree.
    let ins = csearch::run_insertion_tree(&db, &cfg, &city.dir.path().join("ins.flaneur")).unwrap();
    assert!(
        ins.csearch_pages * 4 <= ins.box_pages,
        "insertion tree: {} of {}",
        ins.csearch_pages,
        ins.box_pages
    );
}

#[test]
fn pages_reported_are_the_pages_the_store_counted() {
    let city = small_city();
    let db = Database::open(&city.db).unwrap();
    let path = street_walk(&db.bounds(), 40, 15.0, 10, 3).unwrap();
    let mut history = History::default();
    for eye in path.positions() {
        let cell = disk_cell(eye, 300.0, &db.bounds()).unwrap();
        let before = db.io();
        let r = db.csearch_step(&mut history, &cell).unwrap();
        let io = db.io().since(&before);
        assert_eq!(io.page_reads, r.pages.len() as u64);
        assert_eq!(
            io.reads_of(flaneur::store::PageKind::RtreeNode),
            r.pages.len() as u64
        );
        let before = db.io();
        let b = db.range(&cell).unwrap();
        assert_eq!(db.io().since(&before).page_reads, b.pages.len() as u64);
    }
}

#[test]
fn history_filtering_never_changes_a_result() {
    let city = small_city();
    let db = Database::open(&city.db).unwrap();
    let path = street_walk(&db.bounds(), 150, 12.0, 6, 9).unwrap();
    let mut history = History::new(usize::MAX);
    let mut dropped = 0;
    for eye in path.positions() {
        let cell = disk_cell(eye, 250.0, &db.bounds()).unwrap();
        let unfiltered = history.cells();
        let expected = city.brute_complement(&cell, &unfiltered);
        let before = history.len();
        let got = db.csearch_step(&mut history, &cell).unwrap();
        dropped += before + 1 - history.len();
        assert_eq!(got.ids(), expected);
    }
    assert!(dropped > 0, "the walk should leave cells behind");
    assert!(
        history.len() < 40,
        "filtering keeps the history short: {}",
        history.len()
    );
}
