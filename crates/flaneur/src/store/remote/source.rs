//! The page source a store reads a remote database through: pages from the client
//! cache, missing ones fetched. Runs of missing pages the store announces
//! ([`RawPageSource::will_read`]) go out as one request each, small gaps between them
//! bridged, several requests in flight; a page read unannounced costs one request.

use std::io;
use std::sync::atomic::{AtomicU64, Ordering};

use super::disk_cache::DiskCache;
use super::fetch::{Ends, Fetcher};
use super::page_cache::{self, Bound, PageCache};
use super::{HttpOptions, RemoteError};
use crate::store::backend::RawPageSource;
use crate::store::{RemoteStats, RequestTimes};

/// Missing runs this many pages apart or closer are fetched as one request: a few
/// pages more cost less than another request's round trip.
const BRIDGE_PAGES: u64 = 4;

/// The most bytes one request asks for.
const MAX_REQUEST_BYTES: u64 = 4 << 20;

/// A fetcher and what its first round trip brought.
pub(crate) struct Connected {
    fetcher: Fetcher,
    pub(crate) ends: Ends,
}

pub(crate) struct HttpSource {
    fetcher: Fetcher,
    page_size: usize,
    cache: PageCache,
    cache_bound: Bound,
    disk: Option<DiskCache>,
    page_reads: AtomicU64,
    pages_fetched: AtomicU64,
}

impl HttpSource {
    /// Sends the first round trip for `url`: the file's first `opts.prefix_bytes` and
    /// last `opts.suffix_bytes`. Returns the fetcher, the first bytes (the caller reads
    /// the header from them), the last with their offset, and the file's length.
    pub(crate) fn connect(url: &str, opts: &HttpOptions) -> Result<Connected, RemoteError> {
        let fetcher = Fetcher::new(url, opts);
        let ends = fetcher.open(opts.prefix_bytes as u64, opts.suffix_bytes as u64)?;
        Ok(Connected { fetcher, ends })
    }

    /// The source over a connection, its cache seeded with the whole pages it brought
    /// and bounded by `opts.cache_bytes`, the file's size and the memory available (see
    /// [`page_cache::bound`]); with `opts.cache_dir`, the cache on disk of this version
    /// of the file opened (an error when it cannot be).
    pub(crate) fn new(
        c: Connected,
        page_size: usize,
        opts: &HttpOptions,
    ) -> io::Result<HttpSource> {
        let disk = match (&opts.cache_dir, c.fetcher.version_key()) {
            (Some(dir), Some(version)) => Some(
                DiskCache::open(dir, c.fetcher.url(), &version, c.ends.len, page_size).map_err(
                    |e| {
                        io::Error::new(e.kind(), format!("the cache folder {}: {e}", dir.display()))
                    },
                )?,
            ),
            _ => None,
        };
        let cache_bound = page_cache::bound(
            opts.cache_bytes,
            c.ends.len,
            page_size,
            crate::memory::available(),
        );
        let source = HttpSource {
            fetcher: c.fetcher,
            page_size,
            cache: PageCache::new(cache_bound.pages),
            cache_bound,
            disk,
            page_reads: AtomicU64::new(0),
            pages_fetched: AtomicU64::new(0),
        };
        for (page, bytes) in c.ends.head.chunks_exact(page_size).enumerate() {
            source.keep(page as u64, bytes);
        }
        let (at, tail) = &c.ends.tail;
        if at % page_size as u64 == 0 {
            let first = at / page_size as u64;
            for (i, bytes) in tail.chunks_exact(page_size).enumerate() {
                source.keep(first + i as u64, bytes);
            }
        }
        Ok(source)
    }

    /// Keeps a fetched page, in memory and on disk.
    fn keep(&self, page: u64, bytes: &[u8]) {
        self.cache.insert(page, bytes);
        if let Some(disk) = &self.disk {
            disk.put(page, bytes);
        }
    }

    /// Whether page `page` is held without a request: in memory, or on disk (then it is
    /// brought into memory).
    fn holds(&self, page: u64, buf: &mut [u8]) -> bool {
        if self.cache.holds(page) {
            return true;
        }
        match &self.disk {
            Some(disk) if disk.get(page, buf) => {
                self.cache.insert(page, buf);
                true
            }
            _ => false,
        }
    }

    /// Fetches `runs` of pages (first, count) in one wave of requests and keeps them.
    fn fetch_runs(&self, runs: &[(u64, u64)]) -> io::Result<()> {
        let ps = self.page_size as u64;
        let ranges: Vec<(u64, u64)> = runs.iter().map(|&(p, n)| (p * ps, n * ps)).collect();
        let answers = self.fetcher.ranges(&ranges);
        for (&(first, count), answer) in runs.iter().zip(answers) {
            let bytes = answer.map_err(|e| pages_error(e, first, count))?;
            for (i, page) in bytes.chunks_exact(self.page_size).enumerate() {
                self.keep(first + i as u64, page);
            }
        }
        Ok(())
    }
}

/// `e`, saying which pages were being read.
fn pages_error(e: RemoteError, first: u64, count: u64) -> io::Error {
    let what = if count == 1 {
        format!("page {first}: {}", e.what)
    } else {
        format!("pages {first}..{}: {}", first + count, e.what)
    };
    io::Error::other(RemoteError { what, ..e })
}

impl RawPageSource for HttpSource {
    fn read(&self, page: u64, buf: &mut [u8]) -> io::Result<()> {
        self.page_reads.fetch_add(1, Ordering::Relaxed);
        if self.cache.copy_out(page, buf) {
            return Ok(());
        }
        if let Some(disk) = &self.disk {
            if disk.get(page, buf) {
                self.cache.insert(page, buf);
                return Ok(());
            }
        }
        self.pages_fetched.fetch_add(1, Ordering::Relaxed);
        let ps = self.page_size as u64;
        let bytes = self
            .fetcher
            .range(page * ps, ps)
            .map_err(|e| pages_error(e, page, 1))?;
        buf.copy_from_slice(&bytes);
        self.keep(page, &bytes);
        Ok(())
    }

    fn will_read(&self, runs: &[(u64, u64)]) -> io::Result<()> {
        // The missing pages, as runs with short gaps bridged and long runs split.
        let max_pages = (MAX_REQUEST_BYTES / self.page_size as u64).max(1);
        let mut buf = vec![0u8; self.page_size];
        let mut missing: Vec<u64> = runs
            .iter()
            .flat_map(|&(first, count)| first..first.saturating_add(count))
            .filter(|&p| !self.holds(p, &mut buf))
            .collect();
        missing.sort_unstable();
        missing.dedup();
        if missing.is_empty() {
            return Ok(());
        }
        self.pages_fetched
            .fetch_add(missing.len() as u64, Ordering::Relaxed);
        let mut requests: Vec<(u64, u64)> = Vec::new();
        for p in missing {
            match requests.last_mut() {
                Some((first, count))
                    if p < *first + *count + BRIDGE_PAGES && p - *first < max_pages =>
                {
                    *count = p - *first + 1
                }
                _ => requests.push((p, 1)),
            }
        }
        self.fetch_runs(&requests)
    }

    fn cached(&self, page: u64, buf: &mut [u8]) -> bool {
        self.cache.copy_out(page, buf)
    }

    fn request_times(&self) -> Option<RequestTimes> {
        Some(self.fetcher.request_times())
    }

    fn remote_stats(&self) -> Option<RemoteStats> {
        Some(RemoteStats {
            page_reads: self.page_reads.load(Ordering::Relaxed),
            pages_fetched: self.pages_fetched.load(Ordering::Relaxed),
            cache_bytes: (self.cache_bound.pages as u64).saturating_mul(self.page_size as u64),
            cache_capped_by_memory: self.cache_bound.by_memory,
            ..self.fetcher.stats()
        })
    }
}
