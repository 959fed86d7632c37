//! Insertion into an open database: a library user adds objects, the index grows by
//! the linear split, and every query still equals a brute-force scan — after reopen too.

mod common;

use flaneur::geom::Aabb;
use flaneur::scene::Mesh;
use flaneur::{Backend, BuildOptions, Database};

fn cube(x: f32, z: f32, size: f32) -> Mesh {
    common::box_mesh([x, 0.0, z], [x + size, size, z + size])
}

#[test]
fn inserted_objects_are_found_and_survive_reopen() {
    for backend in [Backend::Mmap, Backend::Pread { direct: false }] {
        let mut c = common::city(
            150,
            8,
            &BuildOptions {
                page_size: 1024,
                ..Default::default()
            },
        );
        let mut db = Database::open_writable(&c.db, backend).unwrap();
        let height = db.tree().height;
        let bounds = c.bounds();
        for i in 0..400u64 {
            let x = bounds.min.x + (i % 20) as f32 * bounds.extent().x / 20.0;
            let z = bounds.min.z + (i / 20) as f32 * bounds.extent().z / 20.0;
            let mesh = cube(x, z, 3.0);
            let e = db.insert(10_000 + i, &mesh).unwrap();
            c.boxes.push((e.id, e.bounds));
        }
        assert!(
            db.tree().height > height,
            "400 inserts into 1 KiB pages must split the root"
        );
        assert_eq!(db.objects(), 550);
        let q = Aabb::new(
            [bounds.min.x, 0.0, bounds.min.z],
            [bounds.center().x, 10.0, bounds.center().z],
        )
        .unwrap();
        assert_eq!(db.range(&q).unwrap().ids(), c.brute_range(&q));
        drop(db);

        let db = Database::open(&c.db).unwrap();
        assert_eq!(db.objects(), 550);
        assert_eq!(db.range(&db.bounds()).unwrap().objects.len(), 550);
        assert_eq!(db.range(&q).unwrap().ids(), c.brute_range(&q));
        let found = db
            .range(
                &Aabb::new(
                    [bounds.min.x, 0.0, bounds.min.z],
                    [bounds.min.x + 1.0, 1.0, bounds.min.z + 1.0],
                )
                .unwrap(),
            )
            .unwrap();
        let inserted = found
            .objects
            .iter()
            .find(|o| o.id == 10_000)
            .expect("the first inserted cube");
        assert_eq!(db.mesh(inserted).unwrap().triangle_count(), 12);
    }
}

#[test]
fn a_tree_built_by_insertion_answers_like_a_packed_one() {
    let packed = common::city(
        500,
        4,
        &BuildOptions {
            page_size: 1024,
            ..Default::default()
        },
    );
    let inserted = common::city(
        500,
        4,
        &BuildOptions {
            page_size: 1024,
            insertion: true,
            ..Default::default()
        },
    );
    let (a, b) = (
        Database::open(&packed.db).unwrap(),
        Database::open(&inserted.db).unwrap(),
    );
    let bounds = packed.bounds();
    for i in 0..50 {
        let t = i as f32 / 50.0;
        let lo = bounds.min + bounds.extent() * glam::Vec3::new(t, 0.0, 1.0 - t) * 0.8;
        let q = Aabb {
            min: lo,
            max: lo + bounds.extent() * 0.2,
        };
        assert_eq!(a.range(&q).unwrap().ids(), b.range(&q).unwrap().ids());
        assert_eq!(b.range(&q).unwrap().ids(), packed.brute_range(&q));
    }
    let (ia, ib) = (a.info().unwrap(), b.info().unwrap());
    assert!(
        ia.tree.fill > ib.tree.fill,
        "packing fills pages better: {} vs {}",
        ia.tree.fill,
        ib.tree.fill
    );
}
