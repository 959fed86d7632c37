//! The LOD table: where each object's LOD data lies, found by object id, and what the
//! build stored, in one extent of `lod` pages that the header's `lodtable` segment names
//! (a = first page, b = byte length, c = every `lod` page of the file, the table's own
//! included). A database without the segment has no LOD data (built with `--no-lod`, or
//! before LODs were stored) and opens as before.
//!
//! The table is a static two-level index: a head (counts, build settings, and the first
//! id of every entry page: the fence) and entry pages sorted by id. A lookup reads the
//! head once per open database (a page for about 500 entry pages) and then one entry
//! page. Every page holds whole entries, so an entry page is read alone.
//!
//! ```text
//! head, padded to whole pages (H of them) when entry pages follow:
//! offset   width  field
//! -------  -----  -----------------------------------------------------------------
//!       0      4  magic              b"FLDT"
//!       4      4  version            u32, TABLE_VERSION
//!       8      4  entry length       u32, ENTRY_LEN
//!      12      4  entries per page   u32, E = payload size / ENTRY_LEN
//!      16      8  entries            u64, n: objects with LOD data
//!      24      4  entry pages        u32, T = ceil(n / E)
//!      28      4  head pages         u32, H
//!      32      8  with levels        u64, objects with a level coarser than the full mesh
//!      40      8  levels             u64, coarse levels stored, all objects
//!      48      8  with PM            u64, objects with a progressive mesh and DAG
//!      56      8  refused            u64, objects the simplifier refused (no entry)
//!      64      4  ratio              f32, triangles of a level over the next finer's
//!      68      4  min triangles      u32, where a chain stops
//!      72      8  PM threshold       u64, triangles above which the PM and DAG are stored
//!      80     8T  fence              u64 per entry page: its first id, ascending
//!  80 + 8T     4  crc32              of the head's bytes before it
//!
//! entry page k (pages H + k): entries kE .. min(n, (k+1)E), ENTRY_LEN bytes each:
//!       0      8  object id          u64, ascending over the whole table
//!       8     16  mesh extent        the object's full mesh (level 0)
//!      24     16  chain head         its coarse levels (`chain`), empty when none: the
//!                                    chain's first bytes, up to the end of the coarsest
//!                                    level's page
//!      40     16  chain rest         the chain's other bytes (its finer levels), empty
//!                                    when the head holds them all
//!      56     16  PM extent          its progressive mesh (`pm::codec`), empty below
//!                                    the threshold
//!      72     16  DAG extent         its DAG (`dag::codec`), empty iff the PM's is
//!      88      4  triangles          u32, of the full mesh
//!      92      4  levels             u32, coarse levels in the chain (0 iff empty)
//! ```
//!
//! A chain is stored in two extents so that a build can put the heads of a batch of
//! objects side by side (`bake`): the coarsest levels of the objects of one cell, all a
//! distant view needs, are then one run of pages, one request over HTTP. The head ends
//! on a page boundary (whole pages) whenever a rest follows, so the two extents hold the
//! chain in as many pages as one would, and page `p` of the chain is page `p` of the
//! head or page `p - head pages` of the rest.
//!
//! An extent is 16 bytes as `store::Extent` encodes it. The store checks each page's
//! checksum; the table checks what a page cannot: the head's own checksum, the fence
//! against each entry page, ids ascending, extents inside the file.

use std::sync::{Arc, OnceLock};

use crate::error::{Error, Result};
use crate::store::framing::{self as bytes, f32_at, push_crc, u32_at, u64_at, CRC_LEN};
use crate::store::{Extent, PageKind, Segment, Store};

/// The header segment that names the LOD table: a = first page, b = byte length,
/// c = `lod` pages in the file.
pub const LOD_SEGMENT: &str = "lodtable";

/// The first four bytes of the table.
pub const TABLE_MAGIC: [u8; 4] = *b"FLDT";
/// The table version this build writes and reads.
pub const TABLE_VERSION: u32 = 2;

const MAGIC_OFFSET: usize = 0;
const VERSION_OFFSET: usize = MAGIC_OFFSET + TABLE_MAGIC.len();
const ENTRY_LEN_OFFSET: usize = VERSION_OFFSET + 4;
const PER_PAGE_OFFSET: usize = ENTRY_LEN_OFFSET + 4;
const ENTRIES_OFFSET: usize = PER_PAGE_OFFSET + 4;
const ENTRY_PAGES_OFFSET: usize = ENTRIES_OFFSET + 8;
const HEAD_PAGES_OFFSET: usize = ENTRY_PAGES_OFFSET + 4;
const WITH_LEVELS_OFFSET: usize = HEAD_PAGES_OFFSET + 4;
const LEVELS_OFFSET: usize = WITH_LEVELS_OFFSET + 8;
const WITH_PM_OFFSET: usize = LEVELS_OFFSET + 8;
const REFUSED_OFFSET: usize = WITH_PM_OFFSET + 8;
const RATIO_OFFSET: usize = REFUSED_OFFSET + 8;
const MIN_TRIANGLES_OFFSET: usize = RATIO_OFFSET + 4;
const PM_THRESHOLD_OFFSET: usize = MIN_TRIANGLES_OFFSET + 4;
const FENCE_OFFSET: usize = PM_THRESHOLD_OFFSET + 8;

const ID_AT: usize = 0;
const MESH_AT: usize = ID_AT + 8;
const CHAIN_AT: usize = MESH_AT + Extent::ENCODED_LEN;
const CHAIN_REST_AT: usize = CHAIN_AT + Extent::ENCODED_LEN;
const PM_AT: usize = CHAIN_REST_AT + Extent::ENCODED_LEN;
const DAG_AT: usize = PM_AT + Extent::ENCODED_LEN;
const TRIANGLES_AT: usize = DAG_AT + Extent::ENCODED_LEN;
const LEVELS_AT: usize = TRIANGLES_AT + 4;
/// Bytes per table entry.
pub const ENTRY_LEN: usize = LEVELS_AT + 4;

/// Where one object's LOD data lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LodEntry {
    pub id: u64,
    /// The object's full mesh: level 0.
    pub mesh: Extent,
    /// Its coarse levels (`chain`): the chain's head, its first bytes up to the end of
    /// its coarsest level's page; empty when no level is coarser than the full mesh.
    pub chain: Extent,
    /// The rest of its chain (its finer levels); empty when the head holds it all.
    pub chain_rest: Extent,
    /// Its progressive mesh; empty when the object is not above the PM threshold.
    pub pm: Extent,
    /// Its DAG; empty exactly when `pm` is.
    pub dag: Extent,
    /// Triangles of the full mesh.
    pub triangles: u32,
    /// Coarse levels in the chain.
    pub levels: u32,
}

/// What a build stored as LOD data, kept in the table's head.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct LodStats {
    /// Objects with LOD data: every object the simplifier accepted.
    pub objects: u64,
    /// Objects with at least one level coarser than their full mesh (the others are at
    /// or below `min_triangles` already).
    pub with_levels: u64,
    /// Coarse levels stored, all objects together (level 0 is the object's mesh).
    pub levels: u64,
    /// Objects with a stored progressive mesh and DAG.
    pub with_pm: u64,
    /// Objects the simplifier refused: they have no LOD data.
    pub refused: u64,
    /// Pages of kind `lod` in the file: chains, progressive meshes, DAGs and the table.
    pub pages: u64,
    /// Triangles of each level over the next finer one's.
    pub ratio: f32,
    /// A chain stops at this many triangles.
    pub min_triangles: u32,
    /// Objects above this many triangles have their progressive mesh and DAG stored.
    pub pm_threshold: u64,
}

fn corrupt(what: String) -> Error {
    Error::Invalid(format!("LOD table: {what}"))
}

fn extent_at(b: &[u8], at: usize) -> Extent {
    let mut w = [0u8; Extent::ENCODED_LEN];
    w.copy_from_slice(&b[at..at + Extent::ENCODED_LEN]);
    Extent::from_le_bytes(&w)
}

/// Bytes of a head with `entry_pages` fence entries, checksum included.
fn head_len(entry_pages: u64) -> u64 {
    (FENCE_OFFSET + CRC_LEN) as u64 + 8 * entry_pages
}

/// The shape of a table of `n` entries in pages of `payload` bytes: (entries per page,
/// entry pages, head pages).
fn shape(n: u64, payload: usize) -> (u64, u64, u64) {
    let per_page = (payload / ENTRY_LEN).max(1) as u64;
    let entry_pages = n.div_ceil(per_page);
    let head_pages = head_len(entry_pages).div_ceil(payload.max(1) as u64);
    (per_page, entry_pages, head_pages)
}

impl LodEntry {
    fn encode(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.id.to_le_bytes());
        for e in [self.mesh, self.chain, self.chain_rest, self.pm, self.dag] {
            out.extend_from_slice(&e.to_le_bytes());
        }
        out.extend_from_slice(&self.triangles.to_le_bytes());
        out.extend_from_slice(&self.levels.to_le_bytes());
    }

    fn decode(b: &[u8]) -> LodEntry {
        LodEntry {
            id: u64_at(b, ID_AT),
            mesh: extent_at(b, MESH_AT),
            chain: extent_at(b, CHAIN_AT),
            chain_rest: extent_at(b, CHAIN_REST_AT),
            pm: extent_at(b, PM_AT),
            dag: extent_at(b, DAG_AT),
            triangles: u32_at(b, TRIANGLES_AT),
            levels: u32_at(b, LEVELS_AT),
        }
    }

    /// What is wrong with an entry read from a store of `pages` pages with `payload`
    /// bytes per page, if anything.
    pub(crate) fn problem(&self, pages: u64, payload: usize) -> Option<String> {
        let extents = [
            ("mesh", self.mesh),
            ("chain", self.chain),
            ("chain rest", self.chain_rest),
            ("PM", self.pm),
            ("DAG", self.dag),
        ];
        for (name, e) in extents {
            let fits = e.shape_problem(payload).is_none()
                && (e.page_count == 0 || (e.first_page >= 1 && e.end_page() <= pages));
            if !fits {
                return Some(format!("its {name} extent {e:?} is not inside the file"));
            }
        }
        if self.mesh.is_empty() || self.triangles == 0 {
            return Some("it has no full mesh".into());
        }
        if self.chain.is_empty() != (self.levels == 0) {
            return Some(format!(
                "{} levels in a chain of {} bytes",
                self.levels, self.chain.byte_len
            ));
        }
        let whole_pages = self.chain.byte_len as usize == self.chain.page_count as usize * payload;
        if !self.chain_rest.is_empty() && (self.chain.is_empty() || !whole_pages) {
            return Some(format!(
                "the rest of a chain follows a head of {} bytes, not of whole pages",
                self.chain.byte_len
            ));
        }
        if self.pm.is_empty() != self.dag.is_empty() {
            return Some("a progressive mesh without its DAG, or a DAG without one".into());
        }
        None
    }
}

/// Encodes the table of `entries` (ascending by id, no id twice) for pages of
/// `payload` bytes. An `Error::Invalid` when the ids are not strictly ascending.
pub(crate) fn encode_table(
    entries: &[LodEntry],
    stats: &LodStats,
    payload: usize,
) -> Result<Vec<u8>> {
    if let Some(w) = entries.windows(2).find(|w| w[0].id >= w[1].id) {
        return Err(Error::Invalid(format!(
            "LOD table: object id {} follows {}: ids must be unique, as LOD data is found \
             by id",
            w[1].id, w[0].id
        )));
    }
    let n = entries.len() as u64;
    let (per_page, entry_pages, head_pages) = shape(n, payload);
    let mut b = Vec::new();
    b.extend_from_slice(&TABLE_MAGIC);
    for v in [TABLE_VERSION, ENTRY_LEN as u32, per_page as u32] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b.extend_from_slice(&n.to_le_bytes());
    b.extend_from_slice(&(entry_pages as u32).to_le_bytes());
    b.extend_from_slice(&(head_pages as u32).to_le_bytes());
    for v in [
        stats.with_levels,
        stats.levels,
        stats.with_pm,
        stats.refused,
    ] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b.extend_from_slice(&stats.ratio.to_le_bytes());
    b.extend_from_slice(&stats.min_triangles.to_le_bytes());
    b.extend_from_slice(&stats.pm_threshold.to_le_bytes());
    for page in entries.chunks(per_page as usize) {
        b.extend_from_slice(&page[0].id.to_le_bytes());
    }
    push_crc(&mut b);
    if n > 0 {
        b.resize(head_pages as usize * payload, 0);
        for page in entries.chunks(per_page as usize) {
            let start = b.len();
            for e in page {
                e.encode(&mut b);
            }
            if page.len() as u64 == per_page {
                b.resize(start + payload, 0);
            }
        }
        // The last page holds only its entries: the extent ends where they do.
        let last = n - (entry_pages - 1) * per_page;
        b.truncate(
            ((head_pages + entry_pages - 1) * payload as u64 + last * ENTRY_LEN as u64) as usize,
        );
    }
    Ok(b)
}

/// The decoded head of a table.
#[derive(Debug)]
pub(crate) struct Head {
    stats: LodStats,
    entries: u64,
    per_page: u64,
    head_pages: u64,
    fence: Vec<u64>,
}

/// An open database's LOD table: where it lies, and its head once read.
#[derive(Debug)]
pub(crate) struct LodTable {
    extent: Extent,
    pages: u64,
    head: OnceLock<Arc<Head>>,
}

impl LodTable {
    /// The table the store's header names, if any. Reads nothing: the head is read at
    /// the first lookup. A `CorruptPage` (page 0) when the segment names an extent that
    /// is not inside the file.
    pub(crate) fn open(store: &Store) -> Result<Option<LodTable>> {
        let pages_in_file = store.page_count();
        let found = store.segment_extent(LOD_SEGMENT, |extent, c| {
            if c < extent.page_count as u64 || c >= pages_in_file {
                return Err(format!(
                    "a table of {} bytes at page {} with {c} LOD pages, in a file of \
                     {pages_in_file} pages",
                    extent.byte_len, extent.first_page
                ));
            }
            Ok(())
        })?;
        let Some((extent, c)) = found else {
            return Ok(None);
        };
        Ok(Some(LodTable {
            extent,
            pages: c,
            head: OnceLock::new(),
        }))
    }

    /// Records the table in the store's header (persisted at the store's finish).
    pub(crate) fn save(store: &mut Store, table: &Extent, lod_pages: u64) -> Result<()> {
        store.set_segment(Segment::new(
            LOD_SEGMENT,
            table.first_page,
            table.byte_len as u64,
            lod_pages,
        ))
    }

    /// Pages of kind `lod` in the file (from the header; reads nothing).
    pub(crate) fn pages(&self) -> u64 {
        self.pages
    }

    /// Where the table lies.
    pub(crate) fn extent(&self) -> Extent {
        self.extent
    }

    /// Entries in the table: objects with LOD data (reads the head the first time).
    pub(crate) fn entry_count(&self, store: &Store) -> Result<u64> {
        Ok(self.head(store)?.entries)
    }

    /// The first page of the table, where its head starts.
    pub(crate) fn first_page(&self) -> u64 {
        self.extent.first_page
    }

    /// What the build stored (reads the head the first time).
    pub(crate) fn stats(&self, store: &Store) -> Result<LodStats> {
        Ok(self.head(store)?.stats)
    }

    /// The page that holds object `id`'s entry, if the table covers its id (it may still
    /// have none there): what [`LodTable::find`] will read, to ask for many at once.
    /// Reads the head the first time.
    pub(crate) fn entry_page(&self, store: &Store, id: u64) -> Result<Option<u64>> {
        let head = self.head(store)?;
        let k = head.fence.partition_point(|&first| first <= id);
        Ok((k > 0).then(|| self.extent.first_page + head.head_pages + k as u64 - 1))
    }

    /// The entry of object `id`, if it has LOD data: the head (once) and one entry page.
    pub(crate) fn find(&self, store: &Store, id: u64) -> Result<Option<LodEntry>> {
        let head = self.head(store)?;
        // The last entry page whose first id is at most `id`.
        let k = head.fence.partition_point(|&first| first <= id);
        if k == 0 {
            return Ok(None);
        }
        let k = k - 1;
        let payload = store.payload_size();
        let (start, len) = head.entry_page_place(k, payload);
        let page = self.read(store, start, len)?;
        let page_no = self.extent.first_page + head.head_pages + k as u64;
        let bad = |what: String| Error::CorruptPage {
            path: store.path().to_path_buf(),
            page: page_no,
            what: format!("LOD table entry page {k}: {what}"),
        };
        let entries = head.entry_page(k, &page).map_err(bad)?;
        let Ok(i) = entries.binary_search_by_key(&id, |e| e.id) else {
            return Ok(None);
        };
        let e = entries[i];
        if let Some(why) = e.problem(store.page_count(), payload) {
            return Err(bad(format!("object {id}: {why}")));
        }
        Ok(Some(e))
    }

    fn read(&self, store: &Store, start: usize, len: usize) -> Result<Vec<u8>> {
        store
            .read_extent_range(&self.extent, PageKind::Lod, start, len)
            .map_err(|e| match e {
                Error::CorruptPage { path, page, what } => Error::CorruptPage {
                    path,
                    page,
                    what: format!("LOD table: {what}"),
                },
                other => other,
            })
    }

    fn head(&self, store: &Store) -> Result<&Head> {
        if let Some(h) = self.head.get() {
            return Ok(h);
        }
        let head = self.read_head(store).map_err(|e| match e {
            Error::Invalid(what) => Error::CorruptPage {
                path: store.path().to_path_buf(),
                page: self.extent.first_page,
                what,
            },
            other => other,
        })?;
        // Another thread may have read it too; either copy is the same.
        let _ = self.head.set(Arc::new(head));
        Ok(self.head.get().expect("just set"))
    }

    fn read_head(&self, store: &Store) -> Result<Head> {
        let payload = store.payload_size();
        let total = self.extent.byte_len as usize;
        let first = self.read(store, 0, total.min(payload))?;
        decode_head(first, total, payload, self.pages, |start, len| {
            self.read(store, start, len)
        })
    }
}

impl Head {
    /// Entry pages in the table (the fence's length).
    pub(crate) fn entry_pages(&self) -> usize {
        self.fence.len()
    }

    /// Where entry page `k` (below [`Head::entry_pages`]) lies in the table, in pages
    /// of `payload` bytes: (start, length) in bytes.
    pub(crate) fn entry_page_place(&self, k: usize, payload: usize) -> (usize, usize) {
        let count = (self.entries - k as u64 * self.per_page).min(self.per_page) as usize;
        let start = (self.head_pages + k as u64) as usize * payload;
        (start, count * ENTRY_LEN)
    }

    /// The entries of entry page `k` (`page`, its bytes), checked against the fence: the
    /// first id is the fence's, the ids ascend and stay below the next page's first.
    pub(crate) fn entry_page(
        &self,
        k: usize,
        page: &[u8],
    ) -> std::result::Result<Vec<LodEntry>, String> {
        let entries: Vec<LodEntry> = page.chunks_exact(ENTRY_LEN).map(LodEntry::decode).collect();
        let (Some(first), Some(last)) = (entries.first(), entries.last()) else {
            return Err("it holds no entry".into());
        };
        if Some(&first.id) != self.fence.get(k) {
            return Err(format!(
                "it starts at object {}, the fence says {:?}",
                first.id,
                self.fence.get(k)
            ));
        }
        if entries.windows(2).any(|w| w[0].id >= w[1].id)
            || self.fence.get(k + 1).is_some_and(|&next| last.id >= next)
        {
            return Err("its object ids are not ascending".into());
        }
        Ok(entries)
    }
}

/// Rewrites the checksum of the head of the table `b` (pages of `payload` bytes) where
/// its count of entries puts it, when `b` holds that much: damaged bytes that pass the
/// checksum, so that a fuzz target reaches the checks after it.
pub(crate) fn reseal_head(b: &mut [u8], payload: usize) {
    if b.len() < FENCE_OFFSET + CRC_LEN {
        return;
    }
    let entry_pages = u64_at(b, ENTRIES_OFFSET).div_ceil((payload / ENTRY_LEN).max(1) as u64);
    let len = entry_pages
        .checked_mul(8)
        .and_then(|fence| fence.checked_add((FENCE_OFFSET + CRC_LEN) as u64));
    if let Some(head) = len.and_then(|l| b.get_mut(..usize::try_from(l).ok()?)) {
        bytes::reseal(head);
    }
}

/// Decodes the head of a table of `total` bytes in pages of `payload` bytes (`pages` of
/// them of kind `lod` in the file) from its `first` bytes (its first page, or all of a
/// shorter table), asking `more(start, len)` for the rest of the head where it is longer:
/// the shape against the count of entries, the length, the checksum, the fence, the
/// counts. An `Error::Invalid` saying what is wrong, whatever the bytes.
pub(crate) fn decode_head(
    mut b: Vec<u8>,
    total: usize,
    payload: usize,
    pages: u64,
    more: impl FnOnce(usize, usize) -> Result<Vec<u8>>,
) -> Result<Head> {
    if b.len() < FENCE_OFFSET + CRC_LEN {
        return Err(corrupt(format!(
            "truncated: {} bytes, the head alone takes {}",
            b.len(),
            FENCE_OFFSET + CRC_LEN
        )));
    }
    bytes::magic_and_version(&b, "a LOD table", TABLE_MAGIC, TABLE_VERSION).map_err(|w| {
        // Version 1 kept each chain in one extent; a build of this version splits it.
        let rebuild = if w.starts_with("version") {
            ": the database was built by another version of flaneur; build it again"
        } else {
            ""
        };
        corrupt(format!("{w}{rebuild}"))
    })?;
    let entries = u64_at(&b, ENTRIES_OFFSET);
    let (per_page, entry_pages, head_pages) = shape(entries, payload);
    let stored = (
        u32_at(&b, ENTRY_LEN_OFFSET) as u64,
        u32_at(&b, PER_PAGE_OFFSET) as u64,
        u32_at(&b, ENTRY_PAGES_OFFSET) as u64,
        u32_at(&b, HEAD_PAGES_OFFSET) as u64,
    );
    if stored != (ENTRY_LEN as u64, per_page, entry_pages, head_pages) {
        return Err(corrupt(format!(
            "its shape (entry length, per page, entry pages, head pages) {stored:?} is not \
             that of {entries} entries in {payload}-byte pages"
        )));
    }
    let expect_len = if entries == 0 {
        head_len(0)
    } else {
        (head_pages + entry_pages - 1) * payload as u64
            + (entries - (entry_pages - 1) * per_page) * ENTRY_LEN as u64
    };
    if expect_len != total as u64 {
        return Err(corrupt(format!(
            "{total} bytes, a table of {entries} entries takes {expect_len}"
        )));
    }
    let len = head_len(entry_pages) as usize;
    if len > b.len() {
        b.extend(more(b.len(), len - b.len())?);
    }
    bytes::checksum(&b, len - CRC_LEN).map_err(|w| corrupt(format!("head {w}")))?;
    let fence: Vec<u64> = (0..entry_pages as usize)
        .map(|k| u64_at(&b, FENCE_OFFSET + 8 * k))
        .collect();
    if fence.windows(2).any(|w| w[0] >= w[1]) {
        return Err(corrupt("the fence's ids are not ascending".into()));
    }
    let stats = LodStats {
        objects: entries,
        with_levels: u64_at(&b, WITH_LEVELS_OFFSET),
        levels: u64_at(&b, LEVELS_OFFSET),
        with_pm: u64_at(&b, WITH_PM_OFFSET),
        refused: u64_at(&b, REFUSED_OFFSET),
        pages,
        ratio: f32_at(&b, RATIO_OFFSET),
        min_triangles: u32_at(&b, MIN_TRIANGLES_OFFSET),
        pm_threshold: u64_at(&b, PM_THRESHOLD_OFFSET),
    };
    if stats.with_levels > entries || stats.with_pm > entries || stats.levels < stats.with_levels {
        return Err(corrupt(format!(
            "counts {stats:?} do not fit {entries} objects"
        )));
    }
    Ok(Head {
        stats,
        entries,
        per_page,
        head_pages,
        fence,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(id: u64, first: u64) -> LodEntry {
        let ext = |page: u64, len: u32| Extent {
            first_page: page,
            page_count: len.div_ceil(1012),
            byte_len: len,
            ..Extent::default()
        };
        LodEntry {
            id,
            mesh: ext(first, 3000),
            chain: ext(first + 3, 1012),
            chain_rest: ext(first + 4, 500),
            pm: if id.is_multiple_of(7) {
                ext(first + 5, 2000)
            } else {
                Extent::default()
            },
            dag: if id.is_multiple_of(7) {
                ext(first + 7, 100)
            } else {
                Extent::default()
            },
            triangles: 500,
            levels: 3,
        }
    }

    /// A store holding `entries` (ids `ids`) and their table; returns it reopened.
    fn store_with(ids: &[u64]) -> (tempfile::TempDir, Store, Vec<LodEntry>) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.db");
        let mut s = Store::create(&path, 1024).unwrap();
        let mut entries = Vec::new();
        for &id in ids {
            let first = s.page_count();
            for _ in 0..8 {
                s.append_page(PageKind::Mesh, b"x").unwrap();
            }
            entries.push(entry(id, first));
        }
        let stats = LodStats {
            objects: ids.len() as u64,
            with_levels: ids.len() as u64,
            levels: 3 * ids.len() as u64,
            with_pm: ids.iter().filter(|&&i| i % 7 == 0).count() as u64,
            refused: 2,
            pages: 0,
            ratio: 0.5,
            min_triangles: 100,
            pm_threshold: 20_000,
        };
        let bytes = encode_table(&entries, &stats, s.payload_size()).unwrap();
        let table = s.append_extent(PageKind::Lod, &bytes).unwrap();
        LodTable::save(&mut s, &table, table.page_count as u64).unwrap();
        s.finish().unwrap();
        let s = Store::open(&path, crate::store::Backend::Mmap).unwrap();
        (dir, s, entries)
    }

    #[test]
    fn finds_every_id_and_no_other() {
        for n in [0usize, 1, 12, 13, 100, 700] {
            let ids: Vec<u64> = (0..n as u64).map(|i| 3 * i + 5).collect();
            let (_dir, s, entries) = store_with(&ids);
            let t = LodTable::open(&s).unwrap().unwrap();
            let stats = t.stats(&s).unwrap();
            assert_eq!(
                (stats.objects, stats.refused, stats.ratio),
                (n as u64, 2, 0.5)
            );
            for e in &entries {
                assert_eq!(t.find(&s, e.id).unwrap(), Some(*e));
            }
            for id in [0, 4, 6, 3 * n as u64 + 5, u64::MAX] {
                assert_eq!(t.find(&s, id).unwrap(), None, "{id}");
            }
            // The head is read once; a lookup then reads one entry page.
            if n > 0 {
                s.reset_stats();
                t.find(&s, entries[n / 2].id).unwrap();
                assert_eq!(s.stats().reads_of(PageKind::Lod), 1);
            }
        }
    }

    #[test]
    fn refuses_ids_out_of_order() {
        let e = [entry(5, 1), entry(5, 9)];
        assert!(encode_table(&e, &LodStats::default(), 1012)
            .unwrap_err()
            .to_string()
            .contains("unique"));
    }

    #[test]
    fn a_table_of_another_version_asks_for_a_rebuild() {
        let (dir, s, _) = store_with(&[1, 2, 3]);
        let table_page = LodTable::open(&s).unwrap().unwrap().first_page();
        let mut head = s.read_page(table_page, PageKind::Lod).unwrap();
        drop(s);
        // A version-1 table, as builds before the split chains wrote: intact pages.
        head[VERSION_OFFSET..VERSION_OFFSET + 4].copy_from_slice(&1u32.to_le_bytes());
        let path = dir.path().join("t.db");
        let mut w = Store::open_writable(&path, crate::store::Backend::Mmap).unwrap();
        w.write_page(table_page, PageKind::Lod, &head).unwrap();
        w.finish().unwrap();
        let s = Store::open(&path, crate::store::Backend::Mmap).unwrap();
        let t = LodTable::open(&s).unwrap().unwrap();
        let e = t.find(&s, 2).unwrap_err().to_string();
        assert!(
            e.contains("version 1, this build reads version 2") && e.contains("build it again"),
            "{e}"
        );
    }

    #[test]
    fn damaged_tables_are_named_errors() {
        let ids: Vec<u64> = (0..100).collect();
        let (dir, s, entries) = store_with(&ids);
        let payload = s.payload_size();
        let per_page = payload / ENTRY_LEN;
        let t = LodTable::open(&s).unwrap().unwrap();
        let table_page = t.first_page();
        drop(s);
        let path = dir.path().join("t.db");
        // An entry page that passes its page checksum but holds the wrong entries, as a
        // misdirected write could leave it: the fence catches it.
        let mut w = Store::open_writable(&path, crate::store::Backend::Mmap).unwrap();
        let mut moved = Vec::new();
        for e in &entries[2 * per_page..3 * per_page] {
            e.encode(&mut moved);
        }
        moved.resize(payload, 0);
        w.write_page(table_page + 2, PageKind::Lod, &moved).unwrap();
        w.finish().unwrap();
        let s = Store::open(&path, crate::store::Backend::Mmap).unwrap();
        let t = LodTable::open(&s).unwrap().unwrap();
        let e = t.find(&s, per_page as u64).unwrap_err().to_string();
        assert!(
            e.contains(&format!("page {}", table_page + 2)) && e.contains("fence"),
            "{e}"
        );
        assert!(t.find(&s, 0).is_ok(), "the other pages still read");
        drop(s);
        // A rotted head: the store's page checksum names the page.
        let f = std::fs::OpenOptions::new().write(true).open(&path).unwrap();
        use std::os::unix::fs::FileExt;
        f.write_all_at(&[0xff], table_page * 1024 + 20).unwrap();
        let s = Store::open(&path, crate::store::Backend::Mmap).unwrap();
        let t = LodTable::open(&s).unwrap().unwrap();
        let e = t.find(&s, 3).unwrap_err().to_string();
        assert!(
            e.contains(&format!("page {table_page}")) && e.contains("LOD table"),
            "{e}"
        );
        // Entries that point outside the file.
        let mut e = entries[3];
        e.chain.first_page = s.page_count();
        assert!(e
            .problem(s.page_count(), payload)
            .unwrap()
            .contains("chain"));
        let mut e = entries[3];
        e.levels = 0;
        assert!(e.problem(s.page_count(), payload).is_some());
        let mut e = entries[7];
        e.dag = Extent::default();
        assert!(e.problem(s.page_count(), payload).unwrap().contains("DAG"));
        // A chain's rest behind a head that ends inside a page: the chain's pages would
        // not be numbered through.
        let mut e = entries[3];
        e.chain.byte_len -= 1;
        assert!(e
            .problem(s.page_count(), payload)
            .unwrap()
            .contains("whole pages"));
    }
}
