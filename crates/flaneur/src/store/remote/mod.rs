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
//! - `source.rs`: the page source the store reads through: cached pages, missing runs
//!   coalesced into one request each.
//!
//! Pages come back as raw bytes; the store checks each one's checksum exactly as it does
//! for a local file, so a proxy that garbles a byte is caught like a bad disk.

mod disk_cache;
mod fetch;
mod page_cache;
mod source;

use std::fmt;
use std::path::PathBuf;
use std::time::Duration;

pub(crate) use source::HttpSource;

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
