//! The integrity check (`flaneur check`): the engine's `PRAGMA integrity_check`.
//!
//! Reads every page of a database and verifies its framing and checksum, then walks
//! every structure the header names and verifies what holds them together:
//! - the R-tree: each node decodes at its level, each entry's box holds its child's
//!   box, no node reached twice; its objects' count, triangles and bounds agree with the
//!   header's;
//! - every object's mesh: its extent inside the file, on mesh pages, decoding to the
//!   triangles and inside the box its leaf entry says;
//! - the LOD table: each entry's mesh is its object's, each chain's levels and each
//!   progressive mesh and DAG decode, and it counts the entries it holds;
//! - the visibility table: the directory's records inside the table, each record
//!   decoding to objects the database holds;
//! - the HDoV-tree: its head, every node, every internal LOD chain, and each scheme's
//!   V-pages for every cell;
//! - the object names: no more than the objects, each one readable;
//! - no two structures claim one page, and the pages of each kind are as many as the
//!   header counts.
//!
//! Every problem is reported with the page it was found on and what that page belongs
//! to; the check goes on past each one. Pages an insert's copy-on-write replaced
//! belong to nothing and are counted, not reported.

mod claims;
mod hdov;
mod lod;
mod objects;
mod visibility;

#[cfg(test)]
mod tests;

use std::path::Path;

use serde::Serialize;

use crate::catalog::load_meta;
use crate::error::{Error, Result};
use crate::hdov::HdovTree;
use crate::lod::stored::LodTable;
use crate::names::NameTable;
use crate::rtree::RTree;
use crate::store::DICTIONARIES_SEGMENT;
use crate::store::{Backend, HttpOptions, PageKind, Store};
use crate::visibility::VisibilityTable;

use claims::Claims;

/// One thing found wrong.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Problem {
    /// The page it was found on, where one is to blame.
    pub page: Option<u64>,
    /// What that page belongs to ("r-tree node at level 1", "mesh of object 42", …).
    pub part: String,
    /// What is wrong.
    pub what: String,
}

/// What a check found.
#[derive(Clone, Debug, Default, Serialize)]
pub struct CheckReport {
    /// Pages in the database, the header included.
    pub pages: u64,
    /// Pages read and verified (each page once for its checksum, then again as the
    /// structures are walked).
    pub page_reads: u64,
    /// Objects found in the R-tree.
    pub objects: u64,
    /// Data pages no structure claims, by kind name: the R-tree nodes an insert's
    /// copy-on-write replaced, for one.
    pub unclaimed: Vec<(String, u64)>,
    /// Bytes past the last page (see
    /// [`Store::uncommitted_bytes`](crate::store::Store::uncommitted_bytes)).
    pub uncommitted_bytes: u64,
    /// Everything found wrong, in the order found.
    pub problems: Vec<Problem>,
}

impl CheckReport {
    /// Whether the database passed: no problem found.
    pub fn ok(&self) -> bool {
        self.problems.is_empty()
    }
}

/// Checks the database file at `path`: every page and every structure.
///
/// `Err` only when the file cannot be read at all (missing, not permitted); a file
/// that is not a database, or is damaged anywhere, gives a report with its problems.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # citygen::write_city(&citygen::CityConfig { objects: 30, ..Default::default() }, &scene)?;
/// flaneur::build_from_scene(&scene, &path, &flaneur::BuildOptions::default())?;
/// let report = flaneur::check::check(&path)?;
/// assert!(report.ok(), "{:?}", report.problems);
/// assert_eq!(report.objects, 30);
/// # Ok(()) }
/// ```
pub fn check(path: &Path) -> Result<CheckReport> {
    match Store::open(path, Backend::Pread { direct: false }) {
        Ok(store) => Ok(check_store(&store)),
        Err(e @ Error::Io { .. }) => Err(e),
        Err(e) => Ok(header_unreadable(&e)),
    }
}

/// [`check`] for a database on an HTTP server, read by byte ranges with `opts`: every
/// page fetched, a chunk of them a request. `Err` when the server cannot be read at the
/// open ([`Error::Remote`], [`Error::RemoteChanged`]); what fails later is a problem of
/// the pages it kept from the check.
pub fn check_url(url: &str, opts: &HttpOptions) -> Result<CheckReport> {
    match Store::open_url(url, opts) {
        Ok(store) => Ok(check_store(&store)),
        Err(e @ (Error::Io { .. } | Error::Remote { .. } | Error::RemoteChanged { .. })) => Err(e),
        Err(e) => Ok(header_unreadable(&e)),
    }
}

/// The report on a file whose header cannot be read as a database's.
fn header_unreadable(e: &Error) -> CheckReport {
    let mut report = CheckReport::default();
    report.problems.push(problem_of(e, "the file header"));
    report
}

/// Every page and structure of an open store.
fn check_store(store: &Store) -> CheckReport {
    let mut c = Claims::scan(store);
    let mut report = CheckReport {
        pages: store.page_count(),
        uncommitted_bytes: store.uncommitted_bytes(),
        ..Default::default()
    };
    structures(store, &mut c, &mut report);
    report.unclaimed = c.unclaimed();
    let mut problems = c.into_problems();
    problems.append(&mut report.problems);
    report.problems = problems;
    report.page_reads = store.stats().page_reads;
    report
}

/// Walks the structures the header names; each records its own problems and goes on.
fn structures(store: &Store, c: &mut Claims, report: &mut CheckReport) {
    let header = "the file header";
    dictionaries(store, c);
    let tree = match RTree::load(store) {
        Ok(t) => Some(t),
        Err(e) => {
            c.problem(&e, header);
            None
        }
    };
    let objects = tree
        .as_ref()
        .map(|t| objects::check(store, t, c))
        .unwrap_or_default();
    report.objects = objects.len() as u64;
    match load_meta(store) {
        Ok(meta) => {
            if let Some(t) = &tree {
                objects::agree_with_header(&meta, t, &objects, c);
            }
            c.count_kind(PageKind::RtreeNode, meta.kinds.rtree);
            c.count_kind(PageKind::Mesh, meta.kinds.mesh);
            c.count_kind(PageKind::Meta, meta.kinds.meta);
        }
        Err(e) => c.problem(&e, header),
    }
    match LodTable::open(store) {
        Ok(Some(t)) => lod::check(store, &t, &objects, c),
        Ok(None) => {}
        Err(e) => c.problem(&e, header),
    }
    match VisibilityTable::open(store) {
        Ok(Some(t)) => visibility::check(store, &t, &objects, c),
        Ok(None) => {}
        Err(e) => c.problem(&e, header),
    }
    match HdovTree::open(store) {
        Ok(Some(t)) => hdov::check(store, &t, &objects, c),
        Ok(None) => {}
        Err(e) => c.problem(&e, header),
    }
    match NameTable::open(store) {
        Ok(Some(t)) => names(store, &t, report.objects, c),
        Ok(None) => {}
        Err(e) => c.problem(&e, header),
    }
    c.check_kind_counts();
}

/// The zstd dictionaries of the geometry frames, when the header names them: their
/// pages, and their bytes as the format and zstd read them.
fn dictionaries(store: &Store, c: &mut Claims) {
    let part = "the zstd dictionaries";
    match store.segment_extent(DICTIONARIES_SEGMENT, |_, _| Ok(())) {
        Ok(Some((extent, _))) => {
            if c.claim_extent(&extent, PageKind::Meta, part) {
                if let Err(e) = store.dictionaries() {
                    c.problem(&e, part);
                }
            }
        }
        Ok(None) => {}
        Err(e) => c.problem(&e, part),
    }
}

/// The names table: its pages, a name for no more objects than there are, and every
/// name readable (the first bad one reported).
fn names(store: &Store, t: &NameTable, objects: u64, c: &mut Claims) {
    let part = "the object names";
    if !c.claim_extent(&t.extent(), PageKind::Meta, part) {
        return;
    }
    if t.len() > objects {
        c.found(
            Some(t.extent().first_page),
            part,
            format!("{} names for {objects} objects", t.len()),
        );
    }
    if let Some(e) = (0..t.len()).find_map(|id| t.name(store, id).err()) {
        c.problem(&e, part);
    }
}

/// An error as a problem of `part`: the page it names, else none.
fn problem_of(e: &Error, part: &str) -> Problem {
    match e {
        Error::CorruptPage { page, what, .. } => Problem {
            page: Some(*page),
            part: part.to_string(),
            what: what.clone(),
        },
        Error::NotADatabase { what, .. } => Problem {
            page: Some(0),
            part: part.to_string(),
            what: format!("not a flaneur database: {what}"),
        },
        Error::Truncated { what, .. } => Problem {
            page: None,
            part: part.to_string(),
            what: format!("truncated: {what}"),
        },
        other => Problem {
            page: None,
            part: part.to_string(),
            what: other.to_string(),
        },
    }
}
