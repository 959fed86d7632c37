//! The bodies of the engine's fuzz targets (`fuzz/`, README "Fuzzing"): one function per
//! target, taking any bytes, that hands them to a decoder of untrusted file bytes (a
//! piece of a database file, a scene file, an OBJ file, or a whole database) and must
//! return, whatever they are: no panic, abort, hang or allocation the bytes' length
//! does not bound. Every error the decoders return is a right answer.
//!
//! The fuzz targets are one line each, calling these, and the corpora's replay
//! (`tests/fuzz_decoders_corpus.rs`) calls the same functions, so the two cannot drift.
//! Where a format carries checksums, a target decodes the bytes as they are and again
//! with the checksums rewritten to match (`reseal`), so that mutated bytes reach the
//! checks behind the checksum, not only the checksum.
//!
//! Hidden from the documentation: not part of the engine's API, and free to change.

mod corpus;
mod files;
mod index;
mod lod;
mod seeds;
mod store;
mod visibility;

use std::cell::RefCell;
use std::path::PathBuf;
use std::sync::OnceLock;

use crate::scene::{Dictionaries, MeshCodec};

pub use corpus::{corpus_dir, corpus_inputs};
pub use files::{database, gltf, obj, osm_pbf, scene_file};
pub use index::{hdov, mesh_codec, rtree_node};
pub use lod::{lod_chain, lod_pm_dag, lod_table};
pub use seeds::{cut_seeds, Seed};
pub use store::{db_header, db_page};
pub use visibility::visibility_table;

/// A target's body.
pub type Target = fn(&[u8]);

/// Every target: its name (its corpus is `fuzz/corpus/<name>/`) and its body.
pub const TARGETS: [(&str, Target); 14] = [
    ("db_header", db_header),
    ("db_page", db_page),
    ("rtree_node", rtree_node),
    ("mesh_codec", mesh_codec),
    ("lod_chain", lod_chain),
    ("lod_pm_dag", lod_pm_dag),
    ("lod_table", lod_table),
    ("visibility_table", visibility_table),
    ("hdov", hdov),
    ("scene_file", scene_file),
    ("obj", obj),
    ("gltf", gltf),
    ("osm_pbf", osm_pbf),
    ("database", database),
];

/// The most objects, cells or found things a target reads of one input: enough to
/// reach every kind of record, few enough that an input runs in milliseconds.
const MAX_ITEMS: usize = 16;

thread_local! {
    /// This thread's scratch directory for the targets that decode a file, removed
    /// when the thread ends (a fuzzer's process exits without ending its thread; its
    /// directory, empty, stays in the system's temporary directory).
    static SCRATCH: RefCell<Option<tempfile::TempDir>> = const { RefCell::new(None) };
}

/// Writes `data` to a file named `name` in this thread's scratch directory, runs `f` on
/// its path and removes the file. A scratch file that cannot be written is no finding:
/// `f` is not run.
fn with_file(name: &str, data: &[u8], f: impl FnOnce(&std::path::Path)) {
    let path: Option<PathBuf> = SCRATCH.with(|s| {
        let mut s = s.borrow_mut();
        if s.is_none() {
            *s = tempfile::Builder::new()
                .prefix("flaneur-fuzz")
                .tempdir()
                .ok();
        }
        s.as_ref().map(|d| d.path().join(name))
    });
    let Some(path) = path else { return };
    if std::fs::write(&path, data).is_ok() {
        f(&path);
    }
    let _ = std::fs::remove_file(&path);
}

/// `b` with the crc32 of its last four bytes rewritten to match the bytes before them.
fn resealed_tail(b: &[u8]) -> Vec<u8> {
    let mut b = b.to_vec();
    crate::store::framing::reseal(&mut b);
    b
}

/// The zstd dictionaries `mesh_codec` decodes with, and its seeds were compressed with:
/// a database's are trained on its own city, which a fuzz input does not carry. Both
/// are trained on the bunny's meshoptimizer buffers at 48 levels of detail, the same in
/// every build.
pub(crate) fn dictionaries() -> &'static Dictionaries {
    static DICTIONARIES: OnceLock<Dictionaries> = OnceLock::new();
    DICTIONARIES.get_or_init(|| {
        let pm = crate::lod::ProgressiveMesh::build(&crate::scene::bunny()).expect("the bunny");
        let samples: Vec<Vec<u8>> = (1..=48)
            .map(|k| {
                let mesh = pm.mesh_at_triangles(k * 40).expect("a level of the bunny");
                MeshCodec::Meshopt { zstd: None }
                    .to_bytes(&mesh)
                    .expect("the bunny encodes")
            })
            .collect();
        let trained = Dictionaries::train(&samples, &samples, crate::scene::DEFAULT_ZSTD_LEVEL);
        assert!(
            !trained.is_empty(),
            "the bunny's buffers train a dictionary"
        );
        trained
    })
}
