//! Reading the visibility table through the store, every page counted: its head (read
//! once per open database) and one cell's PVS record at a time.

use std::sync::OnceLock;

use glam::Vec3;

use super::table::{
    cell_count, decode_head, decode_record, CellPvs, TableHead, HEAD_FIXED, VISIBILITY_SEGMENT,
};
use crate::error::{Error, Result};
use crate::store::{Extent, PageKind, Store};

/// The pages of a table's start announced before its head is read.
const HEAD_PAGES_ASKED: u64 = 16;

/// The visibility table of an open database: where it lies, and its head once read.
#[derive(Debug)]
pub struct VisibilityTable {
    extent: Extent,
    head: OnceLock<TableHead>,
}

/// Turns a codec's complaint into an error naming the table's first page.
fn about(store: &Store, ext: &Extent, e: Error) -> Error {
    match e {
        Error::Invalid(what) => Error::CorruptPage {
            path: store.path().to_path_buf(),
            page: ext.first_page,
            what,
        },
        other => other,
    }
}

impl VisibilityTable {
    /// The table the header's segment names, `None` when the database has no
    /// visibility (built without `--visibility`). Reads nothing but checks that the
    /// extent lies in the file.
    pub fn open(store: &Store) -> Result<Option<VisibilityTable>> {
        let found = store.segment_extent(VISIBILITY_SEGMENT, |extent, c| {
            if c != extent.page_count as u64 {
                return Err(format!(
                    "a table of {} bytes takes {} pages, the segment says {c}",
                    extent.byte_len, extent.page_count
                ));
            }
            Ok(())
        })?;
        let Some((extent, _)) = found else {
            return Ok(None);
        };
        Ok(Some(VisibilityTable {
            extent,
            head: OnceLock::new(),
        }))
    }

    /// Where the table lies.
    pub(crate) fn extent(&self) -> Extent {
        self.extent
    }

    /// Pages the table takes.
    pub fn pages(&self) -> u64 {
        self.extent.page_count as u64
    }

    /// The pages the head most likely lies in, for a remote store to fetch in one
    /// request with whatever else is wanted then: the table's first pages, up to
    /// [`HEAD_PAGES_ASKED`] (a directory of some 3,000 cells at 4 KiB pages).
    pub(crate) fn head_pages(&self) -> impl Iterator<Item = u64> {
        let first = self.extent.first_page;
        first..first + self.pages().min(HEAD_PAGES_ASKED)
    }

    /// The head: grid, settings, stats, directory. Read the first time: its fixed part,
    /// then the directory whose length that gives, announced together beforehand so
    /// that over HTTP both come in one round trip, not two.
    pub fn head(&self, store: &Store) -> Result<&TableHead> {
        if let Some(h) = self.head.get() {
            return Ok(h);
        }
        store.announce(&self.head_pages().collect::<Vec<_>>());
        let ext = &self.extent;
        let len = ext.byte_len as usize;
        if len < HEAD_FIXED {
            return Err(about(
                store,
                ext,
                Error::Invalid(format!("a visibility table of {len} bytes has no head")),
            ));
        }
        let fixed = store.read_extent_range(ext, PageKind::Visibility, 0, HEAD_FIXED)?;
        let n = cell_count(&fixed).map_err(|e| about(store, ext, e))?;
        let head_len = TableHead::len_for(n);
        if head_len > len {
            return Err(about(
                store,
                ext,
                Error::Invalid(format!(
                    "a head of {n} cells takes {head_len} bytes, the table has {len}"
                )),
            ));
        }
        let b = store.read_extent_range(ext, PageKind::Visibility, 0, head_len)?;
        let head = decode_head(&b, ext.byte_len as u64).map_err(|e| about(store, ext, e))?;
        Ok(self.head.get_or_init(|| head))
    }

    /// The records of cells `ids` are about to be read: a remote store fetches their
    /// pages together, one round trip for a prefetching transaction's rows rather than
    /// one each. A hint, reading nothing locally; cells not walkable are passed over.
    pub fn announce(&self, store: &Store, ids: &[u32]) -> Result<()> {
        let head = self.head(store)?;
        let payload = store.payload_size() as u64;
        let mut pages = Vec::new();
        for c in ids.iter().filter_map(|&id| head.cell(id)) {
            if c.len == 0 {
                continue;
            }
            let (first, last) = (
                c.offset / payload,
                (c.offset + u64::from(c.len) - 1) / payload,
            );
            pages.extend((first..=last).map(|i| self.extent.first_page + i));
        }
        pages.sort_unstable();
        pages.dedup();
        store.announce(&pages);
        Ok(())
    }

    /// The PVS of cell `id`, `None` when the cell is not walkable or not in the grid.
    /// Reads the pages of that cell's record.
    pub fn pvs(&self, store: &Store, id: u32) -> Result<Option<CellPvs>> {
        let head = self.head(store)?;
        let Some(c) = head.cell(id) else {
            return Ok(None);
        };
        let b = store.read_extent_range(
            &self.extent,
            PageKind::Visibility,
            c.offset as usize,
            c.len as usize,
        )?;
        decode_record(&b, c.count)
            .map(Some)
            .map_err(|e| match about(store, &self.extent, e) {
                Error::CorruptPage { path, page, what } => Error::CorruptPage {
                    path,
                    page,
                    what: format!("cell {id}: {what}"),
                },
                other => other,
            })
    }

    /// The walkable cell holding `p` (by its ground square), if any.
    pub fn cell_at(&self, store: &Store, p: Vec3) -> Result<Option<u32>> {
        let head = self.head(store)?;
        Ok(head
            .grid
            .locate(p)
            .map(|(r, c)| head.grid.id(r, c))
            .filter(|&id| head.cell(id).is_some()))
    }
}
