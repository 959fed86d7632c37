//! Reading extents through the store: a whole blob, a byte range of one (only the pages
//! that hold it, counted and verified), and telling a remote source which extents and
//! pages come next, so that it fetches them together.

use super::{PageKind, Store};
use crate::error::Result;
use crate::store::Extent;

/// The most pages the store announces at once when it reads a long extent.
pub(crate) const CHUNK_PAGES: u64 = 256;

impl Store {
    /// Reads the blob `ext` (pages of `kind`). Each page is counted and verified; the
    /// extent itself must be consistent, within the database: a whole extent's
    /// `byte_len` fills its pages exactly as `append_extent` writes them (all full but
    /// the last); a packed one starts inside its first page's payload, spans the pages
    /// `offset + byte_len` needs, all full but the last, which holds at least its end.
    pub fn read_extent(&self, ext: &Extent, kind: PageKind) -> Result<Vec<u8>> {
        self.read_extent_range(ext, kind, 0, ext.byte_len as usize)
    }

    /// Checks an extent's shape (offset, page count against byte length) before any
    /// page of it is read.
    fn check_extent_shape(&self, ext: &Extent) -> Result<()> {
        match ext.shape_problem(self.payload_size()) {
            Some(what) => Err(self.corrupt(ext.first_page, what)),
            None => Ok(()),
        }
    }

    /// Reads bytes `start..start + len` of the blob `ext`, reading (and counting) only
    /// the pages that hold them: a reader that needs the head of a large blob, or one
    /// record of it, pays for those pages alone. Checked as [`Store::read_extent`]; a
    /// range past the blob's end is a `CorruptPage` error naming the extent's first page
    /// (the range came from bytes that describe the blob, and those are wrong).
    pub fn read_extent_range(
        &self,
        ext: &Extent,
        kind: PageKind,
        start: usize,
        len: usize,
    ) -> Result<Vec<u8>> {
        let payload = self.payload_size();
        let byte_len = ext.byte_len as usize;
        self.check_extent_shape(ext)?;
        let end = start
            .checked_add(len)
            .filter(|&e| e <= byte_len)
            .ok_or_else(|| {
                self.corrupt(
                    ext.first_page,
                    format!(
                        "bytes {start}..{start}+{len} lie beyond an extent of {byte_len} bytes"
                    ),
                )
            })?;
        if len == 0 {
            return Ok(Vec::new());
        }
        // Check the whole range before allocating for it.
        self.check_range(ext.first_page)?;
        let last = ext.first_page.saturating_add(u64::from(ext.page_count) - 1);
        self.check_range(last)?;
        // Byte positions within the run's payloads: a packed blob starts at its offset.
        let offset = ext.offset as usize;
        let (run_start, run_end) = (offset + start, offset + end);
        let (first_index, last_index) = (run_start / payload, (run_end - 1) / payload);
        let skip = run_start - first_index * payload;
        let mut out = Vec::with_capacity(len + skip);
        let mut scratch = Vec::new();
        for i in first_index..=last_index {
            let page = ext.first_page + i as u64;
            if ((i - first_index) as u64).is_multiple_of(CHUNK_PAGES) {
                // A remote source fetches the next chunk in one request.
                let count = (last_index + 1 - i).min(CHUNK_PAGES as usize) as u64;
                self.source
                    .will_read(&[(page, count)])
                    .map_err(|e| self.read_error(page, e))?;
            }
            let got = self.read_append(page, kind, &mut scratch, &mut out)?;
            // What the page must hold: a whole extent's pages hold exactly its bytes; a
            // packed one's last page may hold other blobs after it.
            let through = (offset + byte_len - i * payload).min(payload);
            let packed_last = ext.packed && i + 1 == ext.page_count as usize;
            if got != through && !(packed_last && got > through) {
                let what = match (ext.packed, packed_last) {
                    (false, _) => format!("an extent of {byte_len} bytes"),
                    (true, _) => format!("a packed extent of {byte_len} bytes at byte {offset}"),
                };
                let at_least = if packed_last { "at least " } else { "" };
                return Err(self.corrupt(
                    page,
                    format!("page {i} of {what} holds {got} bytes, expected {at_least}{through}"),
                ));
            }
        }
        out.drain(..skip);
        out.truncate(len);
        Ok(out)
    }

    /// Announces extents about to be read, so that a remote store fetches the pages it
    /// lacks now, together: adjacent ones in one request, several requests in flight.
    /// Reads nothing on a local store. Nothing is counted until the pages are read.
    ///
    /// ```
    /// # fn main() -> flaneur::Result<()> {
    /// # let dir = tempfile::tempdir().unwrap();
    /// # let path = dir.path().join("p.db");
    /// # let mut store = flaneur::store::Store::create(&path, 4096)?;
    /// # let ext = store.append_extent(flaneur::store::PageKind::Mesh, &[1; 9000])?;
    /// # store.finish()?;
    /// let store = flaneur::store::Store::open(&path, Default::default())?;
    /// store.prefetch(&[ext])?;
    /// assert_eq!(store.stats().page_reads, 0);
    /// # Ok(()) }
    /// ```
    pub fn prefetch(&self, extents: &[Extent]) -> Result<()> {
        let count = self.page_count();
        let runs: Vec<(u64, u64)> = extents
            .iter()
            .filter(|e| e.page_count > 0 && e.first_page > 0 && e.end_page() <= count)
            .map(|e| (e.first_page, u64::from(e.page_count)))
            .collect();
        if runs.is_empty() {
            return Ok(());
        }
        let first = runs[0].0;
        self.source
            .will_read(&runs)
            .map_err(|e| self.read_error(first, e))
    }

    /// Pages about to be read, one by one (a traversal's next nodes): a remote store
    /// fetches those it lacks together. A hint: a failure shows when a page is read.
    pub(crate) fn announce(&self, pages: &[u64]) {
        let count = self.page_count();
        let runs: Vec<(u64, u64)> = pages
            .iter()
            .filter(|&&p| p > 0 && p < count)
            .map(|&p| (p, 1))
            .collect();
        if runs.len() > 1 {
            let _ = self.source.will_read(&runs);
        }
    }
}
