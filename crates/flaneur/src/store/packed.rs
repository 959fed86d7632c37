//! Packed extents: small blobs of one kind sharing pages, each cut at a byte offset
//! inside its first page, so that a blob much smaller than a page does not take a
//! whole one (an object's compressed mesh of a few hundred bytes would otherwise leave
//! most of its 4 KiB page padding).
//!
//! The store keeps one open page per kind: the last partially filled page that
//! `append_packed` wrote for it. A blob goes into that page when it fits there; when it
//! does not, it runs on from there into new pages only if the open page is the file's
//! last (a run's pages are contiguous); otherwise it starts a fresh page at the end and
//! the open page stays as it is, open for a later blob that fits. The open page is
//! re-encoded in place (header, payload length, checksum) each time it grows, so every
//! page is a valid page at every moment and reads during a build see it. A commit
//! closes every open page: packing never rewrites a committed page, so a crash between
//! commits leaves the committed blobs as they were. Each page stays an ordinary page
//! (`page.rs`), so a file with packed extents reads with the same page checks as any.
//!
//! The layout of a packed extent's reference is drawn in `extent.rs`.

use super::{Extent, PageKind, Store};
use crate::error::Result;

/// The page a kind's packed blobs are being added to, and its payload so far.
#[derive(Debug)]
pub(super) struct OpenPage {
    kind: PageKind,
    page: u64,
    payload: Vec<u8>,
}

impl Store {
    /// Appends `bytes` as a packed extent of `kind`: into the kind's open page when it
    /// has room, running on into the next pages when the open page is the file's last,
    /// or else from a fresh page at the end (see the module's top comment). The extent's
    /// pages are all of `kind`; every page of its run but the last is full.
    ///
    /// An empty blob takes no pages, and a blob that would span more than
    /// [`Extent::MAX_PACKED_PAGES`] pages is appended whole ([`Store::append_extent`]):
    /// both come back unpacked. Errors: as [`Store::append_extent`].
    ///
    /// ```
    /// use flaneur::store::{Backend, PageKind, Store};
    /// # fn main() -> flaneur::error::Result<()> {
    /// let dir = tempfile::tempdir().unwrap();
    /// let mut store = Store::create(&dir.path().join("p.db"), 4096)?;
    /// let a = store.append_packed(PageKind::Mesh, &[1; 1000])?;
    /// let b = store.append_packed(PageKind::Mesh, &[2; 1000])?;
    /// assert_eq!((a.first_page, b.first_page, b.offset), (1, 1, 1000));
    /// assert_eq!(store.pages_written(PageKind::Mesh), 1);
    /// assert_eq!(store.read_extent(&b, PageKind::Mesh)?, vec![2; 1000]);
    /// # Ok(()) }
    /// ```
    pub fn append_packed(&mut self, kind: PageKind, bytes: &[u8]) -> Result<Extent> {
        self.append_packed_or_whole(kind, bytes, true)
    }

    /// [`Store::append_packed`] when `packed`, else [`Store::append_extent`]: a writer
    /// whose file format decides (`scene::MeshCodec::packs`).
    pub fn append_packed_or_whole(
        &mut self,
        kind: PageKind,
        bytes: &[u8],
        packed: bool,
    ) -> Result<Extent> {
        if !packed {
            return self.append_extent(kind, bytes);
        }
        self.check_write(kind, 0, "append a packed extent")?;
        let Ok(byte_len) = u32::try_from(bytes.len()) else {
            return self.append_extent(kind, bytes);
        };
        if bytes.is_empty() {
            return self.append_extent(kind, bytes);
        }
        let payload = self.payload_size();
        let max_pages = Extent::MAX_PACKED_PAGES as usize;
        let last_page = self.header.page_count() - 1;
        if let Some(i) = self.open_pages.iter().position(|o| o.kind == kind) {
            let (page, used) = (self.open_pages[i].page, self.open_pages[i].payload.len());
            let room = payload.saturating_sub(used);
            let pages = Extent::pages_spanned(used, bytes.len(), payload);
            if room > 0 && (bytes.len() <= room || page == last_page) && pages <= max_pages {
                let mut open = self.open_pages.swap_remove(i);
                let (head, rest) = bytes.split_at(bytes.len().min(room));
                open.payload.extend_from_slice(head);
                self.write_page(page, kind, &open.payload)?;
                if open.payload.len() < payload {
                    self.open_pages.push(open);
                }
                self.append_run(kind, rest)?;
                return Ok(Extent {
                    first_page: page,
                    page_count: pages as u32,
                    byte_len,
                    offset: used as u32,
                    packed: true,
                });
            }
        }
        let pages = Extent::pages_for(bytes.len(), payload);
        if pages > max_pages {
            return self.append_extent(kind, bytes);
        }
        let first_page = self.header.page_count();
        self.append_run(kind, bytes)?;
        Ok(Extent {
            first_page,
            page_count: pages as u32,
            byte_len,
            offset: 0,
            packed: true,
        })
    }

    /// Appends `bytes` as pages of `kind`, all full but the last, which, when partly
    /// filled, becomes the kind's open page.
    fn append_run(&mut self, kind: PageKind, bytes: &[u8]) -> Result<()> {
        let payload = self.payload_size();
        for chunk in bytes.chunks(payload) {
            let page = self.append_page(kind, chunk)?;
            if chunk.len() < payload {
                self.open_pages.retain(|o| o.kind != kind);
                self.open_pages.push(OpenPage {
                    kind,
                    page,
                    payload: chunk.to_vec(),
                });
            }
        }
        Ok(())
    }

    /// Closes every open page (at a commit: committed pages are never rewritten).
    pub(super) fn close_open_pages(&mut self) {
        self.open_pages.clear();
    }
}
