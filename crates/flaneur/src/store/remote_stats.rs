//! What reading a database over HTTP has cost: counted by `remote`, reported through the
//! backends' trait (`backend`), which local sources answer with none. It lies beside both,
//! not in `remote`, so that the trait can name it without reaching into the source that
//! implements it.

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
    /// The client page cache's bound in effect, in bytes:
    /// [`HttpOptions::cache_bytes`](super::HttpOptions::cache_bytes) capped at the file's
    /// own size and at the memory available at the open.
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
