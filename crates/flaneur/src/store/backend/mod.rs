//! Where page bytes come from: a small trait with two implementations, `mmap` (the
//! fast default) and `pread` (explicit reads, optionally O_DIRECT for cold-cache
//! experiments); the HTTP source is `store::remote`'s. Backends only move bytes; checking
//! and counting is the store's job.

mod mmap;
mod pread;

use std::io;

pub(crate) use mmap::MmapSource;
pub(crate) use pread::PreadSource;

/// A source of whole pages of one database file, as raw bytes: unchecked and
/// uncounted, unlike the verified payloads a [`PageSource`](crate::store::PageSource)
/// hands a traversal.
pub(crate) trait RawPageSource: Send + Sync {
    /// Reads page `page` whole (`buf.len()` = page size) into `buf`.
    fn read(&self, page: u64, buf: &mut [u8]) -> io::Result<()>;

    /// The bytes of page `page` without copying, where the backend has them in memory.
    fn page_bytes(&self, _page: u64) -> Option<&[u8]> {
        None
    }

    /// The file may have grown through writes: make its new pages reachable.
    fn refresh(&mut self) -> io::Result<()> {
        Ok(())
    }

    /// Runs of pages (first, count) about to be read: a source whose every read costs a
    /// round trip fetches them together now. Local sources have nothing to do.
    fn will_read(&self, _runs: &[(u64, u64)]) -> io::Result<()> {
        Ok(())
    }

    /// Copies page `page` into `buf` if this source holds it without a round trip (a
    /// remote source's cache); local sources say no, their reads being cheap anyway.
    fn cached(&self, _page: u64, _buf: &mut [u8]) -> bool {
        false
    }

    /// What reading over the network has cost, for a remote source.
    fn remote_stats(&self) -> Option<crate::store::RemoteStats> {
        None
    }

    /// How long each request took, for a remote source.
    fn request_times(&self) -> Option<crate::store::RequestTimes> {
        None
    }
}
