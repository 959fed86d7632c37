//! `Database`: one open database file — its store, its R-tree — and the queries a
//! library user runs on it. No window, no GPU, no global state.

use std::path::Path;

use crate::build::write_object;
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::rtree::{Coverlap, History, ObjectEntry, QueryResult, RTree, TreeStats};
use crate::scene::{decode_mesh, Mesh};
use crate::store::{Backend, IoStats, PageKind, Segment, Store};

const OBJECTS_SEGMENT: &str = "objects";
const BOUNDS_SEGMENT: &str = "bounds";
const KINDS_SEGMENT: &str = "pagekinds";

/// Pages written per kind, kept in the header so `info` need not scan the file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct KindCounts {
    pub rtree: u64,
    pub mesh: u64,
    pub meta: u64,
}

/// What `flaneur info` prints.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DatabaseInfo {
    pub objects: u64,
    pub triangles: u64,
    pub page_size: usize,
    pub pages: u64,
    pub file_bytes: u64,
    pub pages_by_kind: KindCounts,
    pub bounds: [f32; 6],
    pub tree: TreeStats,
    pub fanout_leaf: usize,
    pub fanout_internal: usize,
}

/// An open database.
///
/// ```no_run
/// # fn main() -> flaneur::Result<()> {
/// let db = flaneur::Database::open("city.flaneur".as_ref())?;
/// let hits = db.range(&"0,0,0,100,50,100".parse()?)?;
/// println!("{} objects, {} pages read", hits.objects.len(), hits.pages.len());
/// # Ok(()) }
/// ```
pub struct Database {
    store: Store,
    tree: RTree,
    objects: u64,
    triangles: u64,
    bounds: Aabb,
    kinds: KindCounts,
}

impl Database {
    /// Opens read-only with the default (mmap) backend.
    pub fn open(path: &Path) -> Result<Database> {
        Database::open_with(path, Backend::default())
    }

    /// Opens read-only with the given backend.
    pub fn open_with(path: &Path, backend: Backend) -> Result<Database> {
        Database::from_store(Store::open(path, backend)?)
    }

    /// Opens for [`Database::insert`].
    pub fn open_writable(path: &Path, backend: Backend) -> Result<Database> {
        Database::from_store(Store::open_writable(path, backend)?)
    }

    fn from_store(store: Store) -> Result<Database> {
        let tree = RTree::load(&store)?;
        let missing = |name: &str| Error::NotADatabase {
            path: store.path().to_path_buf(),
            what: format!("it has no '{name}' segment"),
        };
        let h = store.header();
        let objects = h
            .segment(OBJECTS_SEGMENT)
            .ok_or_else(|| missing(OBJECTS_SEGMENT))?
            .clone();
        let bounds = h
            .segment(BOUNDS_SEGMENT)
            .ok_or_else(|| missing(BOUNDS_SEGMENT))?;
        let kinds = h
            .segment(KINDS_SEGMENT)
            .ok_or_else(|| missing(KINDS_SEGMENT))?;
        let bounds = unpack_bounds(bounds);
        let kinds = KindCounts {
            rtree: kinds.a,
            mesh: kinds.b,
            meta: kinds.c,
        };
        if objects.a != tree.objects {
            return Err(Error::CorruptPage {
                path: store.path().to_path_buf(),
                page: 0,
                what: format!(
                    "header counts {} objects but the R-tree {}",
                    objects.a, tree.objects
                ),
            });
        }
        Ok(Database {
            tree,
            objects: objects.a,
            triangles: objects.b,
            bounds,
            kinds,
            store,
        })
    }

    /// BOX: every object whose box overlaps `query`.
    pub fn range(&self, query: &Aabb) -> Result<QueryResult> {
        self.tree.range(&self.store, query)
    }

    /// CSearch: the objects overlapping `cell` and none of the `history` cells.
    pub fn csearch(&self, cell: &Aabb, history: &[Aabb]) -> Result<QueryResult> {
        self.tree.csearch(&self.store, cell, history)
    }

    /// One CSearch step of a walk, filtering and extending `history`.
    pub fn csearch_step(&self, history: &mut History, cell: &Aabb) -> Result<QueryResult> {
        self.tree
            .csearch_step(&self.store, history, cell, Coverlap::default())
    }

    /// CSearch with an explicit descent rule; same result, different pages.
    pub fn csearch_with(
        &self,
        cell: &Aabb,
        history: &[Aabb],
        rule: Coverlap,
    ) -> Result<QueryResult> {
        self.tree.csearch_with(&self.store, cell, history, rule)
    }

    /// Reads an object's mesh (counted like every read).
    pub fn mesh(&self, object: &ObjectEntry) -> Result<Mesh> {
        let bytes = self.store.read_extent(&object.mesh, PageKind::Mesh)?;
        decode_mesh(&bytes).map_err(|what| Error::CorruptPage {
            path: self.store.path().to_path_buf(),
            page: object.mesh.first_page,
            what: format!("mesh of object {}: {what}", object.id),
        })
    }

    /// Adds an object to an open database (opened with [`Database::open_writable`]):
    /// its mesh is appended and the R-tree grows by insertion. Durable when this
    /// returns. Not crash-atomic: changed nodes are rewritten in place, so a crash in
    /// the middle of an insert can leave the index inconsistent — every read checks
    /// its page, so that shows as an error naming the page, never as a wrong answer.
    pub fn insert(&mut self, id: u64, mesh: &Mesh) -> Result<ObjectEntry> {
        let entry = write_object(&mut self.store, id, crate::scene::KIND_IMPORTED, mesh)?;
        let before = self.store.page_count();
        self.tree.insert(&mut self.store, entry)?;
        self.kinds.mesh += entry.mesh.page_count as u64;
        self.kinds.rtree += self.store.page_count() - before;
        self.objects += 1;
        self.triangles += entry.triangles as u64;
        self.bounds = self.bounds.union(&entry.bounds);
        save_meta(
            &mut self.store,
            self.objects,
            self.triangles,
            &self.bounds,
            &self.kinds,
        )?;
        self.store.flush()?;
        Ok(entry)
    }

    pub fn objects(&self) -> u64 {
        self.objects
    }

    pub fn triangles(&self) -> u64 {
        self.triangles
    }

    /// Pages written per kind (from the header; reads nothing).
    pub fn pages_by_kind(&self) -> KindCounts {
        self.kinds
    }

    /// The box around every object.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    pub fn tree(&self) -> &RTree {
        &self.tree
    }

    pub fn store(&self) -> &Store {
        &self.store
    }

    /// Physical page reads so far.
    pub fn io(&self) -> IoStats {
        self.store.stats()
    }

    pub fn reset_io(&self) {
        self.store.reset_stats()
    }

    /// Objects, triangles, pages by kind, tree shape (walks the whole tree).
    pub fn info(&self) -> Result<DatabaseInfo> {
        let tree = self.tree.stats(&self.store)?;
        let (b, page_size) = (self.bounds, self.store.page_size());
        Ok(DatabaseInfo {
            objects: self.objects,
            triangles: self.triangles,
            page_size,
            pages: self.store.page_count(),
            file_bytes: self.store.page_count() * page_size as u64,
            pages_by_kind: self.kinds,
            bounds: [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z],
            tree,
            fanout_leaf: self.tree.fanout.leaf,
            fanout_internal: self.tree.fanout.internal,
        })
    }
}

pub(crate) fn save_meta(
    store: &mut Store,
    objects: u64,
    triangles: u64,
    bounds: &Aabb,
    kinds: &KindCounts,
) -> Result<()> {
    store.set_segment(Segment {
        name: OBJECTS_SEGMENT.into(),
        a: objects,
        b: triangles,
        c: 0,
    })?;
    let [a, b, c] = pack_bounds(bounds);
    store.set_segment(Segment {
        name: BOUNDS_SEGMENT.into(),
        a,
        b,
        c,
    })?;
    store.set_segment(Segment {
        name: KINDS_SEGMENT.into(),
        a: kinds.rtree,
        b: kinds.mesh,
        c: kinds.meta,
    })
}

fn pack_bounds(b: &Aabb) -> [u64; 3] {
    let bytes = b.to_le_bytes();
    [0, 1, 2].map(|i| u64::from_le_bytes(bytes[i * 8..i * 8 + 8].try_into().unwrap()))
}

fn unpack_bounds(seg: &Segment) -> Aabb {
    let mut bytes = [0u8; 24];
    for (i, v) in [seg.a, seg.b, seg.c].into_iter().enumerate() {
        bytes[i * 8..i * 8 + 8].copy_from_slice(&v.to_le_bytes());
    }
    Aabb::from_le_bytes(&bytes)
}
