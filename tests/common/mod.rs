//! Small cities for the integration tests, generated with citygen and built into
//! real database files in temporary folders.
#![allow(dead_code)]

use std::path::PathBuf;

pub mod recorder;

use flaneur::geom::Aabb;
use flaneur::BuildOptions;

/// Runs the `flaneur` binary this test run built, with `args`; its whole output.
pub fn flaneur(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_flaneur"))
        .args(args)
        .output()
        .unwrap()
}

/// Runs `flaneur walk DB --render` under τ = 0.1 %, its frames drawn at 64 × 64 into
/// `frames` (one of them written), with `extra` arguments; its whole output.
pub fn drawn_walk(
    db: &std::path::Path,
    frames: &std::path::Path,
    extra: &[&str],
) -> std::process::Output {
    let (db, frames) = (db.to_str().unwrap(), frames.to_str().unwrap());
    let mut args = vec![
        "walk",
        db,
        "--quiet",
        "--lod-tau",
        "0.001",
        "--render",
        "--size",
        "64x64",
        "--frames-dir",
        frames,
        "--every",
        "1000",
    ];
    args.extend_from_slice(extra);
    flaneur(&args)
}

/// The standard output of a command that must have succeeded (a test's failure with
/// its standard error otherwise).
pub fn succeeded(out: &std::process::Output) -> String {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The number just before `what` in `text` (a count in a command's report).
pub fn number_before(text: &str, what: &str) -> u64 {
    text.split(what)
        .next()
        .filter(|before| before.len() < text.len())
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no number before '{what}' in {text}"))
}

/// A build where every object above 1,000 triangles also stores its progressive mesh
/// and DAG: a test city's buildings become landmarks refined view by view.
pub fn with_landmarks() -> BuildOptions {
    BuildOptions {
        lod: Some(flaneur::lod::LodOptions {
            pm_threshold: 1_000,
            ..Default::default()
        }),
        ..Default::default()
    }
}

/// A bench's CSV file read back, each field found by its column's name.
pub struct Csv {
    head: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl Csv {
    pub fn read(path: &std::path::Path) -> Csv {
        let text =
            std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut lines = text
            .lines()
            .map(|l| l.split(',').map(String::from).collect());
        Csv {
            head: lines.next().unwrap_or_default(),
            rows: lines.collect(),
        }
    }

    /// Field `name` of `row`.
    pub fn get<'r>(&self, row: &'r [String], name: &str) -> &'r str {
        let col = self.head.iter().position(|h| h == name);
        &row[col.unwrap_or_else(|| panic!("no column {name} in {:?}", self.head))]
    }

    /// Field `name` of `row`, a number.
    pub fn num(&self, row: &[String], name: &str) -> f64 {
        let field = self.get(row, name);
        field
            .parse()
            .unwrap_or_else(|_| panic!("{name} is not a number: {field:?}"))
    }
}

pub struct City {
    pub dir: tempfile::TempDir,
    pub scene: PathBuf,
    pub db: PathBuf,
    /// Every object's id and box, read from the scene file: the brute-force truth.
    pub boxes: Vec<(u64, Aabb)>,
}

/// Build options for a small city's visibility: 12 m viewcells, a coarse DoV, no LODs
/// (seconds for 60 objects).
pub fn with_visibility() -> BuildOptions {
    BuildOptions {
        lod: None,
        visibility: Some(flaneur::visibility::VisibilityOptions {
            cell_size: 12.0,
            resolution: 16,
            ..Default::default()
        }),
        ..Default::default()
    }
}

pub fn city(objects: u64, seed: u64, opts: &BuildOptions) -> City {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("city.scene");
    let db = dir.path().join("city.flaneur");
    let config = citygen::CityConfig {
        objects,
        seed,
        landmarks: 0.0,
        ..Default::default()
    };
    citygen::write_city(&config, &scene).unwrap();
    flaneur::build_from_scene(&scene, &db, opts).unwrap();
    let boxes = citygen::SceneReader::open(&scene)
        .unwrap()
        .map(|o| {
            let o = o.unwrap();
            let (min, max) = o.mesh.bounds();
            (o.id, Aabb::new(min, max).unwrap())
        })
        .collect();
    City {
        dir,
        scene,
        db,
        boxes,
    }
}

impl City {
    pub fn brute_range(&self, q: &Aabb) -> Vec<u64> {
        let mut ids: Vec<u64> = self
            .boxes
            .iter()
            .filter(|(_, b)| b.overlaps(q))
            .map(|(id, _)| *id)
            .collect();
        ids.sort_unstable();
        ids
    }

    /// range(C) − ∪ range(Hᵢ), by scanning every object.
    pub fn brute_complement(&self, c: &Aabb, history: &[Aabb]) -> Vec<u64> {
        let mut ids: Vec<u64> = self
            .boxes
            .iter()
            .filter(|(_, b)| b.overlaps(c) && history.iter().all(|h| !b.overlaps(h)))
            .map(|(id, _)| *id)
            .collect();
        ids.sort_unstable();
        ids
    }

    pub fn bounds(&self) -> Aabb {
        self.boxes.iter().fold(Aabb::EMPTY, |b, (_, o)| b.union(o))
    }
}

/// A walk through the viewcells that then stands still for two seconds at its end, so
/// that a loader that never waits has time to bring all it needs there.
pub fn walk_then_stand(db: &flaneur::Database) -> flaneur::path::CameraPath {
    let mut path = flaneur::path::cell_walk(db, 90, 1.0, 30.0, 3).unwrap();
    let last = *path.poses.last().unwrap();
    for i in 1..=60 {
        path.poses.push(flaneur::path::Pose {
            time: last.time + f64::from(i) / 30.0,
            ..last
        });
    }
    path
}

/// A closed box, its corners as vertices.
pub fn box_mesh(min: [f32; 3], max: [f32; 3]) -> flaneur::scene::Mesh {
    let positions: Vec<[f32; 3]> = (0..8)
        .map(|i| {
            [
                if i & 1 == 0 { min[0] } else { max[0] },
                if i & 2 == 0 { min[1] } else { max[1] },
                if i & 4 == 0 { min[2] } else { max[2] },
            ]
        })
        .collect();
    let indices = vec![
        0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6,
        1, 3, 5, 3, 7, 5,
    ];
    flaneur::scene::Mesh {
        normals: vec![[0.0, 1.0, 0.0]; 8],
        positions,
        indices,
    }
}

/// A small city with LODs (so never-wait walks load coarse levels first) and visibility
/// (for the PVS and VISUAL walks): 120 objects.
pub fn city_with_lods_and_visibility(seed: u64) -> City {
    city(
        120,
        seed,
        &BuildOptions {
            lod: BuildOptions::default().lod,
            ..with_visibility()
        },
    )
}

/// [`city_with_lods_and_visibility`] with format version 1's raw meshes, one chain to a
/// page or more: for tests that damage one object's LOD page (a page of packed chains
/// is several objects'), and for those that read it over HTTP and need a file larger
/// than the first round trip's two ends (format version 2's comes whole with them).
pub fn city_with_lods_and_visibility_raw(seed: u64) -> City {
    city(
        120,
        seed,
        &BuildOptions {
            lod: BuildOptions::default().lod,
            codec: flaneur::scene::MeshCodec::Raw,
            ..with_visibility()
        },
    )
}

/// The first page of object `id`'s LOD chain in the database at `db`, found by the
/// chain's documented layout: a `lod` page whose payload holds the chain's magic, its
/// version and the object's id (at the payload's start in a file of format version 1,
/// anywhere in version 2, where chains are packed several to a page).
pub fn lod_chain_page(db: &std::path::Path, id: u64) -> u64 {
    use flaneur::store::{PageKind, PAGE_HEADER_LEN};
    let page_size = flaneur::Database::open(db).unwrap().store().page_size();
    let bytes = std::fs::read(db).unwrap();
    let page = bytes
        .chunks(page_size)
        .enumerate()
        .skip(1)
        .find(|(_, p)| {
            let payload = &p[PAGE_HEADER_LEN..];
            p[0] == PageKind::Lod as u8
                && payload.windows(16).any(|w| {
                    w[..4] == flaneur::lod::CHAIN_MAGIC
                        && (w[4..8] == 1u32.to_le_bytes() || w[4..8] == 2u32.to_le_bytes())
                        && w[8..16] == id.to_le_bytes()
                })
        })
        .expect("the object's chain")
        .0;
    page as u64
}
