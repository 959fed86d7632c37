//! CSearch and BOX against a brute-force scan of every object, and BOX against rstar,
//! over random boxes and random histories, on the page file, on both backends.

mod common;

use std::sync::OnceLock;

use flaneur::geom::Aabb;
use flaneur::rtree::Coverlap;
use flaneur::{Backend, BuildOptions, Database};
use proptest::prelude::*;
use proptest::strategy::ValueTree;
use rstar::{primitives::GeomWithData, primitives::Rectangle, RTree, AABB};

fn city() -> &'static common::City {
    static CITY: OnceLock<common::City> = OnceLock::new();
    // 1 KiB pages: a few hundred objects make a tree of three levels.
    CITY.get_or_init(|| {
        common::city(
            600,
            11,
            &BuildOptions {
                page_size: 1024,
                ..Default::default()
            },
        )
    })
}

fn backends() -> [Backend; 2] {
    [Backend::Mmap, Backend::Pread { direct: false }]
}

/// A random box around the city, from a point and a size (sizes from 0: flat and
/// point boxes included).
fn a_box() -> impl Strategy<Value = Aabb> {
    (
        0.0f32..1.0,
        0.0f32..1.0,
        0.0f32..1.0,
        0.0f32..0.5,
        0.0f32..1.0,
        0.0f32..0.5,
    )
        .prop_map(|(x, y, z, w, h, d)| {
            let b = city().bounds();
            let e = b.extent() * 1.2;
            let lo = b.min - e * 0.1 + glam::Vec3::new(x, y * 0.5, z) * e;
            Aabb {
                min: lo,
                max: lo + glam::Vec3::new(w, h, d) * e,
            }
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn range_equals_brute_force(q in a_box()) {
        for backend in backends() {
            let db = Database::open_with(&city().db, backend).unwrap();
            prop_assert_eq!(db.range(&q).unwrap().ids(), city().brute_range(&q));
        }
    }

    #[test]
    fn csearch_equals_the_set_difference(c in a_box(), history in prop::collection::vec(a_box(), 0..6)) {
        for backend in backends() {
            let db = Database::open_with(&city().db, backend).unwrap();
            let plain = db.range(&c).unwrap();
            let thesis = db.csearch_with(&c, &history, Coverlap::Thesis).unwrap();
            let clipped = db.csearch_with(&c, &history, Coverlap::Clipped).unwrap();
            for got in [&thesis, &clipped] {
                prop_assert_eq!(got.ids(), city().brute_complement(&c, &history));
                // CSearch never reads a page BOX would not.
                prop_assert!(got.pages.iter().all(|p| plain.pages.contains(p)));
            }
            // Clipping only ever prunes more.
            prop_assert!(clipped.pages.iter().all(|p| thesis.pages.contains(p)));
        }
    }

    #[test]
    fn csearch_history_near_the_cell(c in a_box(), shifts in prop::collection::vec((-0.3f32..0.3, -0.3f32..0.3), 1..5)) {
        // Histories of cells that overlap the query, as a walk makes them.
        let history: Vec<Aabb> = shifts.iter().map(|(dx, dz)| {
            let e = c.extent();
            let d = glam::Vec3::new(dx * e.x, 0.0, dz * e.z);
            Aabb { min: c.min + d, max: c.max + d }
        }).collect();
        let db = Database::open(&city().db).unwrap();
        for rule in [Coverlap::Thesis, Coverlap::Clipped] {
            prop_assert_eq!(db.csearch_with(&c, &history, rule).unwrap().ids(), city().brute_complement(&c, &history));
        }
    }
}

#[test]
fn range_equals_rstar_on_the_same_boxes() {
    let tree: RTree<GeomWithData<Rectangle<[f32; 3]>, u64>> = RTree::bulk_load(
        city()
            .boxes
            .iter()
            .map(|(id, b)| {
                GeomWithData::new(
                    Rectangle::from_corners(b.min.to_array(), b.max.to_array()),
                    *id,
                )
            })
            .collect(),
    );
    let db = Database::open(&city().db).unwrap();
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    for _ in 0..200 {
        let q = a_box().new_tree(&mut runner).unwrap().current();
        let mut expected: Vec<u64> = tree
            .locate_in_envelope_intersecting(&AABB::from_corners(
                q.min.to_array(),
                q.max.to_array(),
            ))
            .map(|g| g.data)
            .collect();
        expected.sort_unstable();
        assert_eq!(db.range(&q).unwrap().ids(), expected, "query {q}");
    }
}
