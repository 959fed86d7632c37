//! Bad input of every kind gets a clear error naming what is wrong — never a panic,
//! never a silently wrong answer.

mod common;

use std::fs;
use std::io::Write;

use flaneur::geom::Aabb;
use flaneur::{BuildOptions, Database, Error};

fn city() -> common::City {
    common::city(
        200,
        3,
        &BuildOptions {
            page_size: 1024,
            ..Default::default()
        },
    )
}

fn flip(path: &std::path::Path, offset: u64) {
    let mut bytes = fs::read(path).unwrap();
    bytes[offset as usize] ^= 0x5a;
    fs::write(path, bytes).unwrap();
}

#[test]
fn a_flipped_byte_in_a_node_names_the_page() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    let root = db.tree().root;
    let page_size = db.store().page_size() as u64;
    drop(db);
    flip(&c.db, root * page_size + 40);
    let db = Database::open(&c.db).unwrap();
    let err = db.range(&c.bounds()).unwrap_err();
    assert!(
        matches!(err, Error::CorruptPage { page, .. } if page == root),
        "{err}"
    );
    assert!(err.to_string().contains(&format!("page {root}")), "{err}");
}

#[test]
fn a_flipped_byte_in_a_mesh_names_the_page() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    let obj = db.range(&c.bounds()).unwrap().objects[0];
    let page_size = db.store().page_size() as u64;
    drop(db);
    flip(&c.db, obj.mesh.first_page * page_size + 30);
    let db = Database::open(&c.db).unwrap();
    let err = db.mesh(&obj).unwrap_err();
    assert!(
        matches!(err, Error::CorruptPage { page, .. } if page == obj.mesh.first_page),
        "{err}"
    );
}

#[test]
fn truncated_databases_are_errors() {
    let c = city();
    let len = fs::metadata(&c.db).unwrap().len();
    for cut in [len - 1, len - 1024, 100, 0] {
        let f = fs::OpenOptions::new().write(true).open(&c.db).unwrap();
        f.set_len(cut).unwrap();
        drop(f);
        let err = Database::open(&c.db)
            .err()
            .unwrap_or_else(|| panic!("a file cut to {cut} bytes opened"));
        let msg = err.to_string();
        assert!(msg.contains(&c.db.display().to_string()), "{msg}");
    }
}

#[test]
fn bad_magic_and_foreign_files_are_errors() {
    let c = city();
    flip(&c.db, 0);
    assert!(matches!(
        Database::open(&c.db),
        Err(Error::NotADatabase { .. })
    ));
    let text = c.dir.path().join("notes.txt");
    fs::write(&text, "hello, this is not a database at all\n".repeat(200)).unwrap();
    assert!(Database::open(&text).is_err());
    assert!(Database::open(&c.dir.path().join("missing.flaneur")).is_err());
}

#[test]
fn bad_boxes_are_errors() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    let nan = Aabb {
        min: glam::Vec3::new(f32::NAN, 0.0, 0.0),
        max: glam::Vec3::ONE,
    };
    let inverted = Aabb {
        min: glam::Vec3::ONE,
        max: glam::Vec3::ZERO,
    };
    for bad in [nan, inverted] {
        assert!(matches!(db.range(&bad), Err(Error::BadBox(_))));
        assert!(matches!(db.csearch(&bad, &[]), Err(Error::BadBox(_))));
        assert!(matches!(
            db.csearch(&c.bounds(), &[bad]),
            Err(Error::BadBox(_))
        ));
    }
}

#[test]
fn malformed_obj_files_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("empty.obj", "# nothing here\n"),
        ("bad_vertex.obj", "v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n"),
        ("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"),
        ("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"),
    ];
    for (name, text) in cases {
        let obj = dir.path().join(name);
        fs::File::create(&obj)
            .unwrap()
            .write_all(text.as_bytes())
            .unwrap();
        let out = dir.path().join("out.flaneur");
        let err =
            flaneur::build_from_obj(std::slice::from_ref(&obj), &out, &BuildOptions::default())
                .err();
        let err = err.unwrap_or_else(|| panic!("{name} built"));
        assert!(err.to_string().contains(name), "{name}: {err}");
        assert!(!out.exists(), "{name}: a failed build left a database");
    }
}

#[test]
fn a_scene_file_cut_short_fails_the_build_and_leaves_no_database() {
    let c = city();
    let len = fs::metadata(&c.scene).unwrap().len();
    let f = fs::OpenOptions::new().write(true).open(&c.scene).unwrap();
    f.set_len(len / 2).unwrap();
    drop(f);
    let out = c.dir.path().join("half.flaneur");
    let err = flaneur::build_from_scene(&c.scene, &out, &BuildOptions::default()).unwrap_err();
    assert!(err.to_string().contains("city.scene"), "{err}");
    assert!(!out.exists());
}

/// Plays a path, walking on past damaged objects when `skip` says so, and keeps what
/// the figures told of them and the ids the walk held.
struct Walker<'p> {
    path: &'p flaneur::path::CameraPath,
    skip: bool,
    damaged: Vec<String>,
    held: std::collections::HashSet<u64>,
}

impl<'p> Walker<'p> {
    fn new(path: &'p flaneur::path::CameraPath, skip: bool) -> Walker<'p> {
        Walker {
            path,
            skip,
            damaged: Vec::new(),
            held: Default::default(),
        }
    }
}

impl flaneur::walk::FrameSink for Walker<'_> {
    fn frame(
        &mut self,
        _: usize,
        _: &flaneur::geom::Camera,
        buffer: &flaneur::walk::ObjectBuffer,
        _: &mut flaneur::walk::Selection<'_>,
    ) -> flaneur::Result<()> {
        self.held.extend(buffer.iter().map(|o| o.entry.id));
        Ok(())
    }
}

impl flaneur::walk::Viewer for Walker<'_> {
    fn next_pose(&mut self, frame: usize) -> flaneur::Result<Option<flaneur::path::Pose>> {
        Ok(self.path.poses.get(frame).copied())
    }

    fn figures(&mut self, figures: &flaneur::walk::FrameFigures) {
        self.damaged.extend(figures.damaged.iter().cloned());
    }

    fn skips_damaged(&self) -> bool {
        self.skip
    }
}

/// Walks `c` whole, damages the first mesh page of an object the walk held, and walks
/// again: a walk for measuring stops with the page named; one whose viewer would rather
/// walk on goes all `frames` without that object, told of once. `walk(db, skip)` walks
/// and says how many frames it went.
fn damaged_mesh_met_by<'p>(
    c: &common::City,
    frames: usize,
    walk: impl Fn(&Database, bool) -> (flaneur::Result<usize>, Walker<'p>),
) {
    let db = Database::open(&c.db).unwrap();
    let (whole, w) = walk(&db, false);
    assert!(w.damaged.is_empty() && whole.unwrap() == frames);
    // An object the walk loads, somewhere along it.
    let all = db.range(&c.bounds()).unwrap().objects;
    let victim = *all
        .iter()
        .filter(|o| w.held.contains(&o.id))
        .nth(w.held.len() / 2)
        .unwrap();
    let page_size = db.store().page_size() as u64;
    drop(db);
    flip(&c.db, victim.mesh.first_page * page_size + 30);
    let db = Database::open(&c.db).unwrap();

    let err = walk(&db, false).0.unwrap_err();
    assert!(
        matches!(err, Error::CorruptPage { page, .. } if page == victim.mesh.first_page),
        "{err}"
    );
    // Small meshes are packed several to a page: a damaged page costs each object with
    // bytes on it that the walk loads, each told of once.
    let page = victim.mesh.first_page;
    let on_page: Vec<u64> = all
        .iter()
        .filter(|o| w.held.contains(&o.id))
        .filter(|o| {
            (o.mesh.first_page..o.mesh.first_page + o.mesh.page_count as u64).contains(&page)
        })
        .map(|o| o.id)
        .collect();
    let (walked, w) = walk(&db, true);
    assert_eq!(walked.unwrap(), frames, "the walk went on");
    assert!(on_page.iter().all(|id| !w.held.contains(id)));
    assert_eq!(w.damaged.len(), on_page.len(), "{:?}", w.damaged);
    for id in on_page {
        assert!(
            w.damaged
                .iter()
                .any(|said| said.contains(&format!("object {id} left out"))
                    && said.contains(&format!("page {page}"))),
            "{:?}",
            w.damaged
        );
    }
}

/// A mesh page damaged in the middle of a REVIEW walk.
#[test]
fn a_walk_meets_a_damaged_mesh() {
    use flaneur::path::motion::{self, Motion};
    use flaneur::walk::review::{Preset, ReviewConfig, WalkReport};
    use flaneur::walk::{self, Frames, WalkConfig};
    let c = city();
    let bounds = c.bounds();
    let path = motion::generate(&bounds, Motion::Normal, 90, 30.0, 1).unwrap();
    let cfg = ReviewConfig {
        pace: None,
        ..ReviewConfig::preset(Preset::Optimal)
    };
    damaged_mesh_met_by(&c, 90, |db, skip| {
        let mut w = Walker::new(&path, skip);
        let r = walk::run(db, &WalkConfig::Review(cfg.clone()), &mut w, Frames::Keep)
            .and_then(WalkReport::try_from)
            .map(|r| r.frames.len());
        (r, w)
    });
}

/// The PVS walk meeting a damaged mesh when it draws, as the REVIEW walk does.
#[test]
fn a_pvs_walk_meets_a_damaged_mesh() {
    use flaneur::path::cell_walk;
    use flaneur::walk::pvs::{PvsPrefetch, PvsWalkReport};
    use flaneur::walk::{self, Frames};
    let c = common::city(60, 3, &common::with_visibility());
    let path = cell_walk(&Database::open(&c.db).unwrap(), 120, 0.5, 30.0, 1).unwrap();
    let rule = PvsPrefetch::Pbnp { border: 0.25 };
    damaged_mesh_met_by(&c, 120, |db, skip| {
        let mut w = Walker::new(&path, skip);
        let r = walk::run(db, &rule.into(), &mut w, Frames::Keep)
            .and_then(PvsWalkReport::try_from)
            .map(|r| r.frames.len());
        (r, w)
    });
}

/// Counts the progress a build reports.
#[derive(Default)]
struct Steps(std::sync::atomic::AtomicU64);

impl flaneur::progress::Progress for Steps {
    fn update(&self, _: flaneur::progress::Step, _: u64, _: Option<u64>) {
        self.0.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }
}

#[test]
fn build_options_are_refused_before_any_work() {
    let c = city();
    let out = c.dir.path().join("refused.flaneur");
    let bad = [
        (
            BuildOptions {
                visibility: Some(flaneur::visibility::VisibilityOptions {
                    cell_size: 0.0,
                    ..Default::default()
                }),
                ..Default::default()
            },
            "viewcell size 0",
        ),
        (
            BuildOptions {
                visibility: Some(flaneur::visibility::VisibilityOptions {
                    resolution: 0,
                    ..Default::default()
                }),
                ..Default::default()
            },
            "resolution",
        ),
        (
            BuildOptions {
                visibility: Some(Default::default()),
                hdov: Some(flaneur::hdov::HdovOptions {
                    schemes: vec![],
                    ..Default::default()
                }),
                ..Default::default()
            },
            "at least one storage scheme",
        ),
        (
            BuildOptions {
                fill: 2.0,
                ..Default::default()
            },
            "fill factor 2",
        ),
    ];
    for (opts, says) in bad {
        let steps = Steps::default();
        let e = flaneur::build::build_from_scene_with_progress(&c.scene, &out, &opts, &steps)
            .unwrap_err();
        assert!(e.to_string().contains(says), "{e}");
        assert_eq!(
            steps.0.load(std::sync::atomic::Ordering::Relaxed),
            0,
            "{says}: refused after work began"
        );
        assert!(!out.exists());
    }
}

#[test]
fn obj_faces_of_under_three_vertices_and_text_not_utf8_are_errors_naming_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &[u8], &str); 3] = [
        (
            "line_face.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n",
            "line 5: a face of 2 vertices",
        ),
        (
            "point_face.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 3\nf 1 2 3\n",
            "line 4: a face of 1 vertex:",
        ),
        (
            "latin1.obj",
            b"v 0 0 0\nv 1 0 0\n# caf\xe9\nv 0 1 0\nf 1 2 3\n",
            "line 3: not UTF-8 text (byte 0xe9 at column 6)",
        ),
    ];
    for (name, bytes, says) in cases {
        let obj = dir.path().join(name);
        fs::write(&obj, bytes).unwrap();
        let err = flaneur::scene::load_obj(&obj).unwrap_err().to_string();
        assert!(err.contains(name) && err.contains(says), "{name}: {err}");
    }
}
