//! A database read by byte ranges from any HTTP server or CDN: the page source behind
//! [`Store::open_url`](super::Store::open_url), as map viewers read one PMTiles archive
//! or a Cloud-Optimized GeoTIFF. Nothing runs on the server but a plain static server
//! that honours `Range` (nginx, Apache, an object store, a CDN).
//!
//! One idea per file:
//! - `fetch.rs`: one ranged GET and what its answer must be (206 with the bytes asked
//!   for, of the version first opened: its ETag pinned and sent back as `If-Match`),
//!   retried with backoff when the connection fails; several in flight at once;
//! - `page_cache.rs`: the client's page cache, its bound capped at the file's size and the
//!   memory available, grown as pages come;
//! - `disk_cache.rs`: the optional cache on disk, one sparse file per version of a file;
//! - `request_times.rs`: how long each request took, as a histogram;
//! - `source.rs`: the page source the store reads through: cached pages, missing runs
//!   coalesced into one request each.
//!
//! Pages come back as raw bytes; the store checks each one's checksum exactly as it does
//! for a local file, so a proxy that garbles a byte is caught like a bad disk.

mod disk_cache;
mod fetch;
mod page_cache;
mod request_times;
mod source;

use std::fmt;
use std::path::PathBuf;
use std::time::Duration;

pub use request_times::RequestTimes;
pub(crate) use source::{HttpSource, CHUNK_PAGES};

/// How a database is read over HTTP.
///
/// ```
/// let opts = flaneur::store::HttpOptions { cache_bytes: 64 << 20, ..Default::default() };
/// assert_eq!(opts.retries, flaneur::store::HttpOptions::default().retries);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct HttpOptions {
    /// The client page cache's bound, in bytes: every page read (index, meshes, LODs,
    /// visibility records) is kept here, least recently used out first. Capped at the
    /// file's own size and at the memory available at the open (`MemAvailable`, where
    /// /proc/meminfo says); nothing is reserved for it up front, the cache growing with
    /// the pages it holds.
    pub cache_bytes: usize,
    /// The longest one request may take, connection included.
    pub timeout: Duration,
    /// How many times a failed request (connection refused or dropped, timeout, 5xx) is
    /// tried again, waiting twice as long each time, before the read is an error.
    pub retries: u32,
    /// The wait before the first retry.
    pub backoff: Duration,
    /// Requests in flight at once when several runs of pages are wanted together: more
    /// than a browser's six per host, since a walk asks for many page-sized runs and a
    /// link of 50 ms carries few of them a second otherwise.
    pub parallel: usize,
    /// The bytes the first round trip fetches from the start of the file: the header, its
    /// segment table, and whatever the build put behind them.
    pub prefix_bytes: usize,
    /// The bytes the first round trip fetches, beside the prefix, from the end of the
    /// file, where a build puts the R-tree's upper levels (its root last): a first
    /// query then waits for one more round trip for its leaves, not one per level.
    pub suffix_bytes: usize,
    /// A folder to keep fetched pages in, so that a second visit to the same version of
    /// the file reads them there instead of asking the server; `None` for none.
    pub cache_dir: Option<PathBuf>,
}

impl Default for HttpOptions {
    fn default() -> HttpOptions {
        HttpOptions {
            cache_bytes: 256 << 20,
            timeout: Duration::from_secs(20),
            retries: 3,
            backoff: Duration::from_millis(100),
            parallel: 16,
            prefix_bytes: 64 << 10,
            suffix_bytes: 512 << 10,
            cache_dir: None,
        }
    }
}

/// What reading a database over HTTP has cost so far.
///
/// ```
/// let s = flaneur::store::RemoteStats { page_reads: 10, pages_fetched: 4, ..Default::default() };
/// assert_eq!(s.hit_rate(), 0.6);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RemoteStats {
    /// HTTP requests sent, retries included.
    pub requests: u64,
    /// Waits for the network: a batch of requests sent together counts once.
    pub round_trips: u64,
    /// Body bytes received.
    pub bytes: u64,
    /// Requests sent again after a failure.
    pub retries: u64,
    /// Pages the store read through the client cache.
    pub page_reads: u64,
    /// Of those, pages that were not in the cache and had to be fetched.
    pub pages_fetched: u64,
    /// The client page cache's bound in effect, in bytes: [`HttpOptions::cache_bytes`]
    /// capped at the file's own size and at the memory available at the open.
    pub cache_bytes: u64,
    /// Whether the memory available at the open, being less than the bound asked for,
    /// capped the cache.
    pub cache_capped_by_memory: bool,
    /// Whether the server named no version of the file, neither an ETag nor a
    /// Last-Modified: another file put in its place while it is read then goes
    /// unnoticed until a page fails its checksum, and no cache folder is kept.
    pub unversioned: bool,
}

impl RemoteStats {
    /// What was spent since `earlier`, a snapshot of the same reader.
    pub fn since(&self, earlier: &RemoteStats) -> RemoteStats {
        RemoteStats {
            requests: self.requests.saturating_sub(earlier.requests),
            round_trips: self.round_trips.saturating_sub(earlier.round_trips),
            bytes: self.bytes.saturating_sub(earlier.bytes),
            retries: self.retries.saturating_sub(earlier.retries),
            page_reads: self.page_reads.saturating_sub(earlier.page_reads),
            pages_fetched: self.pages_fetched.saturating_sub(earlier.pages_fetched),
            ..*self
        }
    }

    /// What a reader of `url` should be told once, at the open: a server that names no
    /// version of the file, a cache capped by the memory available. The library never
    /// prints: the command line does.
    ///
    /// ```
    /// let s = flaneur::store::RemoteStats { unversioned: true, ..Default::default() };
    /// let w = s.warnings("http://example.org/c.flaneur");
    /// assert!(w.len() == 1 && w[0].contains("http://example.org/c.flaneur"));
    /// ```
    pub fn warnings(&self, url: &str) -> Vec<String> {
        let mut out = Vec::new();
        if self.unversioned {
            out.push(format!(
                "{url}: the server sends neither an ETag nor a Last-Modified, so a new \
                 version of the file put there while it is read goes unnoticed until a page \
                 fails its checksum (and no cache folder is kept); a well-kept static server \
                 sends both"
            ));
        }
        if self.cache_capped_by_memory {
            out.push(format!(
                "{url}: the page cache is capped at the memory available, {} MiB",
                self.cache_bytes >> 20
            ));
        }
        out
    }

    /// The share of page reads the client cache answered without a request (1 with no reads).
    pub fn hit_rate(&self) -> f64 {
        if self.page_reads == 0 {
            return 1.0;
        }
        1.0 - self.pages_fetched.min(self.page_reads) as f64 / self.page_reads as f64
    }
}

/// Why a read over HTTP failed, carried inside an `io::Error` through the page source so
/// the store can name it as [`Error::Remote`](crate::Error::Remote) or
/// [`Error::RemoteChanged`](crate::Error::RemoteChanged).
#[derive(Debug)]
pub(crate) struct RemoteError {
    pub(crate) what: String,
    /// The file on the server is not the one first opened.
    pub(crate) changed: bool,
}

impl RemoteError {
    pub(crate) fn new(what: impl Into<String>) -> RemoteError {
        RemoteError {
            what: what.into(),
            changed: false,
        }
    }

    pub(crate) fn changed(what: impl Into<String>) -> RemoteError {
        RemoteError {
            what: what.into(),
            changed: true,
        }
    }

    /// The library's error for this failure on `url`.
    pub(crate) fn into_error(self, url: &str) -> crate::Error {
        let url = url.to_string();
        if self.changed {
            crate::Error::RemoteChanged {
                url,
                what: self.what,
            }
        } else {
            crate::Error::Remote {
                url,
                what: self.what,
            }
        }
    }
}

impl fmt::Display for RemoteError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.what)
    }
}

impl std::error::Error for RemoteError {}

/// Whether `location` names a database on an HTTP server rather than a file.
///
/// ```
/// assert!(flaneur::store::is_url("https://example.org/city.flaneur"));
/// assert!(!flaneur::store::is_url("city.flaneur"));
/// ```
pub fn is_url(location: &str) -> bool {
    let lower = location.get(..8).unwrap_or(location).to_ascii_lowercase();
    lower.starts_with("http://") || lower.starts_with("https://")
}
