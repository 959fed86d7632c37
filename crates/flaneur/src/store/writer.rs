//! The write side of a store: a buffer of pending appended pages, overwrites, and the
//! commit (header write + fsync).
//!
//! Appends are encoded straight into a buffer of whole pages and written with one
//! positioned write per `WRITE_BUFFER_BYTES`, so building a large database costs one
//! copy and one checksum per page and few syscalls. Pending pages are readable from
//! the buffer; nothing needs flushing before a read. The header (page 0) is the commit
//! point: pages beyond its page count are not part of the database.

use std::fs::File;
use std::io;
use std::os::unix::fs::FileExt;
use std::path::Path;

use tempfile::TempPath;

use super::header::Header;
use super::page::{self, PageKind};

/// Size of the append buffer (a multiple of every valid page size).
pub(crate) const WRITE_BUFFER_BYTES: usize = 4 << 20;

pub(crate) struct Writer {
    file: File,
    page_size: usize,
    /// Encoded pages not yet written, the first of them page `pending_first`.
    pending: Vec<u8>,
    pending_first: u64,
    /// The file's length: grown whole pages at a time (`set_len`) before pages are
    /// written past it, so that a writer killed mid-write leaves whole pages.
    file_len: u64,
    /// A created store's temporary file, removed on drop unless taken by `finish`.
    temp: Option<TempPath>,
}

impl Writer {
    /// A writer whose next appended page is `next_page`. A new file (`next_page` 0)
    /// gets a blank page 0 that the header replaces at commit.
    pub(crate) fn new(
        file: File,
        page_size: usize,
        next_page: u64,
        temp: Option<TempPath>,
    ) -> Writer {
        let mut pending = Vec::with_capacity(WRITE_BUFFER_BYTES.max(page_size));
        if next_page == 0 {
            pending.resize(page_size, 0);
        }
        Writer {
            file,
            page_size,
            pending,
            pending_first: next_page,
            file_len: next_page * page_size as u64,
            temp,
        }
    }

    /// The bytes of `page` if it is still in the buffer.
    #[inline]
    pub(crate) fn pending_page(&self, page: u64) -> Option<&[u8]> {
        let i = usize::try_from(page.checked_sub(self.pending_first)?).ok()?;
        let start = i.checked_mul(self.page_size)?;
        self.pending.get(start..start.checked_add(self.page_size)?)
    }

    /// Appends one page; the caller has checked the payload fits.
    pub(crate) fn append(&mut self, kind: PageKind, payload: &[u8]) -> io::Result<()> {
        if self.pending.len() + self.page_size > WRITE_BUFFER_BYTES.max(self.page_size) {
            self.flush_pending()?;
        }
        page::encode_into(kind, payload, self.page_size, &mut self.pending);
        Ok(())
    }

    /// Overwrites an existing page (buffered or on file).
    pub(crate) fn overwrite(
        &mut self,
        page: u64,
        kind: PageKind,
        payload: &[u8],
    ) -> io::Result<()> {
        let ps = self.page_size;
        let start = page
            .checked_sub(self.pending_first)
            .and_then(|i| usize::try_from(i).ok())
            .and_then(|i| i.checked_mul(ps));
        if let Some(dst) = start.and_then(|s| self.pending.get_mut(s..s.checked_add(ps)?)) {
            page::encode_in_place(kind, payload, dst);
            return Ok(());
        }
        let mut buf = Vec::with_capacity(self.page_size);
        page::encode_into(kind, payload, self.page_size, &mut buf);
        self.file.write_all_at(&buf, page * self.page_size as u64)
    }

    /// Writes the buffered pages to the file.
    pub(crate) fn flush_pending(&mut self) -> io::Result<()> {
        if self.pending.is_empty() {
            return Ok(());
        }
        let start = self.pending_first * self.page_size as u64;
        let end = start + self.pending.len() as u64;
        if end > self.file_len {
            self.file.set_len(end)?;
            self.file_len = end;
        }
        self.file.write_all_at(&self.pending, start)?;
        self.pending_first += (self.pending.len() / self.page_size) as u64;
        self.pending.clear();
        Ok(())
    }

    /// Writes every pending page, fsyncs, then writes the header and fsyncs: after
    /// this the file on disk is the database `header` describes, and at no moment
    /// before did the header on disk name a page not yet written.
    pub(crate) fn commit(&mut self, header: &Header) -> io::Result<()> {
        self.flush_pending()?;
        self.file.sync_data()?;
        let mut page0 = vec![0u8; self.page_size];
        header.encode(&mut page0);
        self.file.write_all_at(&page0, 0)?;
        self.file.sync_all()
    }

    /// The temporary file, now the caller's to persist (dropping it removes it).
    pub(crate) fn take_temp(&mut self) -> Option<TempPath> {
        self.temp.take()
    }

    /// The temporary file being written, if this is a created store.
    pub(crate) fn file_path(&self) -> Option<&Path> {
        self.temp.as_deref()
    }
}
