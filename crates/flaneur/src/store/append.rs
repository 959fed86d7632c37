//! The store's writes as a build makes them: pages and extents appended, a page
//! overwritten, the pages of each kind counted, each checked (a writable store, not the header's kind, a payload that
//! fits a page) before `writer.rs` buffers it.

use std::io;

use super::{Extent, PageKind, Store};
use crate::error::{Error, Result};

impl Store {
    pub(super) fn check_write(&self, kind: PageKind, payload: usize, what: &str) -> Result<()> {
        if self.writer.is_none() {
            return Err(self.read_only(what));
        }
        if kind == PageKind::Header {
            return Err(Error::Invalid(format!(
                "{}: cannot {what} of kind header: only page 0 is the header",
                self.path.display()
            )));
        }
        if payload > self.payload_size() {
            return Err(Error::Invalid(format!(
                "{}: cannot {what}: payload of {payload} bytes exceeds the {} bytes a page holds",
                self.path.display(),
                self.payload_size()
            )));
        }
        Ok(())
    }

    fn write_error(&self, e: io::Error) -> Error {
        let file = self
            .writer
            .as_ref()
            .and_then(|w| w.file_path())
            .unwrap_or(&self.path);
        Error::io(file, e)
    }

    /// Appends one page of `kind` holding `payload` and returns its page id. Errors:
    /// read-only store, kind `Header`, payload over [`Store::payload_size`].
    pub fn append_page(&mut self, kind: PageKind, payload: &[u8]) -> Result<u64> {
        self.check_write(kind, payload.len(), "append a page")?;
        let id = self.header.page_count();
        if let Some(w) = self.writer.as_mut() {
            if let Err(e) = w.append(kind, payload) {
                return Err(self.write_error(e));
            }
        }
        self.header.page_count += 1;
        self.pages_written[kind as usize] += 1;
        Ok(id)
    }

    /// Overwrites existing data page `page` with a page of `kind` holding `payload`.
    /// Errors: read-only store, page 0 or beyond the page count, kind `Header`,
    /// payload too long.
    pub fn write_page(&mut self, page: u64, kind: PageKind, payload: &[u8]) -> Result<()> {
        self.check_write(kind, payload.len(), "write a page")?;
        if page == 0 || page >= self.header.page_count() {
            return Err(Error::Invalid(format!(
                "{}: cannot overwrite page {page}: data pages are 1..{}",
                self.path.display(),
                self.header.page_count()
            )));
        }
        if let Some(w) = self.writer.as_mut() {
            if let Err(e) = w.overwrite(page, kind, payload) {
                return Err(self.write_error(e));
            }
        }
        Ok(())
    }

    /// Appends `bytes` as an extent: contiguous pages of `kind`, all full but the
    /// last. An empty blob takes no pages. Errors: as `append_page`, and blobs over
    /// 4 GiB - 1 bytes.
    pub fn append_extent(&mut self, kind: PageKind, bytes: &[u8]) -> Result<Extent> {
        self.check_write(kind, 0, "append an extent")?;
        let byte_len = u32::try_from(bytes.len()).map_err(|_| {
            Error::Invalid(format!(
                "{}: cannot append an extent of {} bytes: at most {} bytes",
                self.path.display(),
                bytes.len(),
                u32::MAX
            ))
        })?;
        let first_page = self.header.page_count();
        let payload = self.payload_size();
        let mut pages = 0u32;
        for chunk in bytes.chunks(payload) {
            if let Some(w) = self.writer.as_mut() {
                if let Err(e) = w.append(kind, chunk) {
                    return Err(self.write_error(e));
                }
            }
            // Count as we go, so a failed write leaves page_count matching the buffer.
            self.header.page_count += 1;
            self.pages_written[kind as usize] += 1;
            pages += 1;
        }
        Ok(Extent {
            first_page,
            page_count: pages,
            byte_len,
            offset: 0,
            packed: false,
        })
    }

    /// Pages of `kind` this handle has appended (`append_page`, `append_extent`,
    /// `append_packed`; overwrites not counted): what a builder records as the pages
    /// of each kind, since packed extents share pages and their page counts overlap.
    pub fn pages_written(&self, kind: PageKind) -> u64 {
        self.pages_written[kind as usize]
    }
}
