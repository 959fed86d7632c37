//! One ranged GET and what its answer must be.
//!
//! A database over HTTP is only as sound as each answer: the server must send 206 with
//! exactly the bytes asked for, of the same version of the file every time. The first
//! answer pins that version (its ETag, else its Last-Modified, and its length); every
//! later request carries the ETag as `If-Match`, and every answer is checked against the
//! pin, so pages of two versions are never mixed. A server that names no version (neither
//! header) is read all the same, and says so in [`RemoteStats::unversioned`]. Every
//! request asks for the identity encoding: a compressed answer's bytes are not the file's
//! at the offsets asked, so one is an error naming its encoding. A failed connection, a
//! timeout or a 5xx is tried again with a doubling wait; anything else is an error at
//! once.

use std::fmt;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Mutex, OnceLock};
use std::thread;
use std::time::{Duration, Instant};

use ureq::http::{HeaderMap, StatusCode};

use super::{HttpOptions, RemoteError};
use crate::store::{RemoteStats, RequestTimes};

/// The version of the file the first answer came from.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Version {
    etag: Option<String>,
    last_modified: Option<String>,
    len: u64,
}

/// An attempt's failure: worth another try, or final.
enum Failure {
    Retry(String),
    Final(RemoteError),
}

/// What the first round trip brought: both ends of the file.
pub(crate) struct Ends {
    /// The file's first bytes: its header and what follows.
    pub(crate) head: Vec<u8>,
    /// The file's last bytes and the offset they start at: the index's upper levels.
    pub(crate) tail: (u64, Vec<u8>),
    /// The file's length.
    pub(crate) len: u64,
}

/// One range's answer: its bytes, or why not.
type Answer = Result<Vec<u8>, RemoteError>;

/// What the counters count: see [`RemoteStats`].
#[derive(Default)]
struct Counters {
    requests: AtomicU64,
    round_trips: AtomicU64,
    bytes: AtomicU64,
    retries: AtomicU64,
}

/// Ranged GETs of one URL over one pooled agent.
pub(crate) struct Fetcher {
    agent: ureq::Agent,
    url: String,
    opts: HttpOptions,
    version: OnceLock<Version>,
    counters: Counters,
    times: Mutex<RequestTimes>,
}

impl Fetcher {
    pub(crate) fn new(url: &str, opts: &HttpOptions) -> Fetcher {
        let agent: ureq::Agent = ureq::Agent::config_builder()
            .http_status_as_error(false)
            .timeout_global(Some(opts.timeout))
            .max_idle_connections_per_host(opts.parallel.max(1))
            .build()
            .into();
        Fetcher {
            agent,
            url: url.to_string(),
            opts: opts.clone(),
            version: OnceLock::new(),
            counters: Counters::default(),
            times: Mutex::new(RequestTimes::default()),
        }
    }

    /// The version the first answer pinned, as a key for a cache of its pages: its ETag,
    /// else its Last-Modified; `None` before the open or when the server gave neither.
    pub(crate) fn version_key(&self) -> Option<String> {
        let v = self.version.get()?;
        let tag = v.etag.as_deref().or(v.last_modified.as_deref())?;
        Some(format!("{tag} {}", v.len))
    }

    /// The URL read.
    pub(crate) fn url(&self) -> &str {
        &self.url
    }

    /// The first round trip: the file's first `head` bytes and its last `tail` bytes (fewer
    /// when the file is shorter), asked for together, pinning the file's version. Returns
    /// the head, the tail with the offset it starts at, and the file's length.
    pub(crate) fn open(&self, head: u64, tail: u64) -> Result<Ends, RemoteError> {
        self.counters.round_trips.fetch_add(1, Ordering::Relaxed);
        let (first, last) = thread::scope(|s| {
            let last = (tail > 0).then(|| s.spawn(|| self.get(Span::Last(tail), true)));
            let first = self.get(Span::At(0, head.max(1) - 1), true);
            let last = last.map(|h| {
                h.join()
                    .unwrap_or_else(|_| Err(RemoteError::new("a request thread panicked")))
            });
            (first, last)
        });
        let (_, head) = first?;
        let len = self.version.get().map_or(0, |v| v.len);
        let tail = match last.transpose() {
            Ok(last) => last.unwrap_or_default(),
            // A file shorter than the suffix asked for: RFC 9110 gives the whole file, but
            // some servers (tower-http's) answer 416. Its length is known now: ask again.
            Err(_) if len > 0 && len < tail => {
                self.counters.round_trips.fetch_add(1, Ordering::Relaxed);
                self.get(Span::Last(len), false)?
            }
            Err(e) => return Err(e),
        };
        Ok(Ends { head, tail, len })
    }

    /// Bytes `start..start + len` of the file, as one request (one round trip).
    pub(crate) fn range(&self, start: u64, len: u64) -> Result<Vec<u8>, RemoteError> {
        self.counters.round_trips.fetch_add(1, Ordering::Relaxed);
        self.bytes(start, len)
    }

    fn bytes(&self, start: u64, len: u64) -> Result<Vec<u8>, RemoteError> {
        Ok(self.get(Span::At(start, start + len - 1), false)?.1)
    }

    /// Several ranges at once, up to `parallel` requests in flight: one round trip when
    /// they fit, as many as the waves they need otherwise. Answers in the order asked.
    pub(crate) fn ranges(&self, ranges: &[(u64, u64)]) -> Vec<Answer> {
        let workers = self.opts.parallel.clamp(1, ranges.len().max(1));
        let waves = ranges.len().div_ceil(workers) as u64;
        self.counters
            .round_trips
            .fetch_add(waves, Ordering::Relaxed);
        if workers == 1 {
            return ranges
                .iter()
                .map(|&(start, len)| self.bytes(start, len))
                .collect();
        }
        let next = AtomicUsize::new(0);
        let mut answers: Vec<Option<Answer>> = (0..ranges.len()).map(|_| None).collect();
        let done: Vec<Vec<(usize, Answer)>> = thread::scope(|s| {
            let handles: Vec<_> = (0..workers)
                .map(|_| {
                    s.spawn(|| {
                        let mut mine = Vec::new();
                        loop {
                            let i = next.fetch_add(1, Ordering::Relaxed);
                            let Some(&(start, len)) = ranges.get(i) else {
                                break;
                            };
                            mine.push((i, self.bytes(start, len)));
                        }
                        mine
                    })
                })
                .collect();
            handles
                .into_iter()
                .map(|h| {
                    h.join().unwrap_or_else(|_| {
                        vec![(
                            usize::MAX,
                            Err(RemoteError::new("a request thread panicked")),
                        )]
                    })
                })
                .collect()
        });
        for (i, answer) in done.into_iter().flatten() {
            if let Some(slot) = answers.get_mut(i) {
                *slot = Some(answer);
            }
        }
        answers
            .into_iter()
            .map(|a| a.unwrap_or_else(|| Err(RemoteError::new("a request was never answered"))))
            .collect()
    }

    /// The counters so far (the page figures are the source's).
    pub(crate) fn stats(&self) -> RemoteStats {
        let c = &self.counters;
        RemoteStats {
            requests: c.requests.load(Ordering::Relaxed),
            round_trips: c.round_trips.load(Ordering::Relaxed),
            bytes: c.bytes.load(Ordering::Relaxed),
            retries: c.retries.load(Ordering::Relaxed),
            unversioned: self
                .version
                .get()
                .is_some_and(|v| v.etag.is_none() && v.last_modified.is_none()),
            ..RemoteStats::default()
        }
    }

    /// How long each request took so far, from sending it to its body's last byte.
    pub(crate) fn request_times(&self) -> RequestTimes {
        self.times.lock().map(|t| t.clone()).unwrap_or_default()
    }

    /// One range, tried again after failures that may pass; its bytes and where they start.
    fn get(&self, span: Span, first: bool) -> Result<(u64, Vec<u8>), RemoteError> {
        let mut wait = self.opts.backoff;
        let mut attempt = 0;
        loop {
            let started = Instant::now();
            let answer = self.attempt(span, first);
            if let Ok(mut t) = self.times.lock() {
                t.record(started.elapsed());
            }
            match answer {
                Ok(bytes) => return Ok(bytes),
                Err(Failure::Final(e)) => return Err(e),
                Err(Failure::Retry(why)) if attempt >= self.opts.retries => {
                    return Err(RemoteError::new(format!(
                        "{span}: {} attempts failed, the last: {why}",
                        attempt + 1
                    )))
                }
                Err(Failure::Retry(_)) => {
                    attempt += 1;
                    self.counters.retries.fetch_add(1, Ordering::Relaxed);
                    thread::sleep(wait);
                    wait = wait.saturating_mul(2).min(Duration::from_secs(5));
                }
            }
        }
    }

    fn attempt(&self, span: Span, first: bool) -> Result<(u64, Vec<u8>), Failure> {
        // The pages are read at their offsets in the file itself: a compressed body has
        // other offsets and another length.
        let mut request = self
            .agent
            .get(&self.url)
            .header("Range", span.header())
            .header("Accept-Encoding", "identity");
        if let Some(etag) = self.version.get().and_then(|v| v.etag.as_deref()) {
            request = request.header("If-Match", etag);
        }
        self.counters.requests.fetch_add(1, Ordering::Relaxed);
        let mut response = request.call().map_err(|e| transport(&e))?;
        let status = response.status();
        let headers = response.headers().clone();
        let fail = |what: String| Err(Failure::Final(RemoteError::new(what)));
        match status {
            StatusCode::PARTIAL_CONTENT => {}
            StatusCode::OK => {
                return fail(format!(
                    "the server answered 200 with the whole file to a request for {span}: \
                     it does not serve byte ranges, which a database over HTTP needs \
                     (nginx, Apache, object stores and CDNs do)"
                ))
            }
            StatusCode::PRECONDITION_FAILED => {
                return Err(Failure::Final(RemoteError::changed(format!(
                    "412 Precondition Failed to If-Match {}",
                    self.version
                        .get()
                        .and_then(|v| v.etag.as_deref())
                        .unwrap_or("?")
                ))))
            }
            StatusCode::RANGE_NOT_SATISFIABLE => {
                let what = format!(
                    "416 Range Not Satisfiable for {span}{}",
                    header(&headers, "content-range")
                        .map(|r| format!(" (the server says {r})"))
                        .unwrap_or_default()
                );
                return Err(Failure::Final(if first {
                    RemoteError::new(format!("{what}: the file is empty"))
                } else {
                    RemoteError::changed(what)
                }));
            }
            s if s.is_server_error() || s == StatusCode::TOO_MANY_REQUESTS => {
                return Err(Failure::Retry(format!("HTTP {s}")))
            }
            s => return fail(format!("HTTP {s} to a request for {span}")),
        }
        if let Some(coding) = header(&headers, "content-encoding")
            .map(str::trim)
            .filter(|c| !c.is_empty() && !c.eq_ignore_ascii_case("identity"))
        {
            return fail(format!(
                "the server sent {span} compressed (Content-Encoding: {coding}) though the \
                 request asked for none: a database is read by byte ranges of the file as it \
                 is stored, so the server must not compress it (turn its compression off for \
                 this file)"
            ));
        }
        let (got_start, got_end, total) = header(&headers, "content-range")
            .and_then(parse_content_range)
            .ok_or_else(|| {
                Failure::Final(RemoteError::new(format!(
                    "a 206 answer to {span} without a usable Content-Range ({:?})",
                    header(&headers, "content-range")
                )))
            })?;
        self.check_version(&headers, total)?;
        // The first round trip may ask past the end of a short file; every other asks
        // within it.
        let (start, end) = match span {
            Span::At(a, b) if first => (a, b.min(total.saturating_sub(1))),
            Span::At(a, b) => (a, b),
            Span::Last(n) => (total.saturating_sub(n), total - 1),
        };
        if got_start != start || got_end != end {
            return fail(format!(
                "asked for bytes {start}-{end}, the server sent {got_start}-{got_end}/{total}"
            ));
        }
        let expect = end - start + 1;
        let body = response
            .body_mut()
            .with_config()
            .limit(expect)
            .read_to_vec()
            .map_err(|e| match e {
                ureq::Error::BodyExceedsLimit(_) => Failure::Final(RemoteError::new(format!(
                    "bytes {start}-{end}: the server sent more than the {expect} bytes asked for"
                ))),
                other => transport(&other),
            })?;
        self.counters
            .bytes
            .fetch_add(body.len() as u64, Ordering::Relaxed);
        if body.len() as u64 != expect {
            return fail(format!(
                "bytes {start}-{end}: the server sent {} bytes, not {expect}",
                body.len()
            ));
        }
        Ok((start, body))
    }

    /// Pins the first answer's version (the first round trip's two answers race for it),
    /// and checks every answer against it.
    fn check_version(&self, headers: &HeaderMap, total: u64) -> Result<(), Failure> {
        let seen = Version {
            etag: header(headers, "etag").map(str::to_string),
            last_modified: header(headers, "last-modified").map(str::to_string),
            len: total,
        };
        let pinned = self.version.get_or_init(|| seen.clone());
        let changed = |what: String| Err(Failure::Final(RemoteError::changed(what)));
        if pinned.len != seen.len {
            return changed(format!("it was {} bytes, now {}", pinned.len, seen.len));
        }
        if let (Some(a), Some(b)) = (&pinned.etag, &seen.etag) {
            if a != b {
                return changed(format!("ETag {a} became {b}"));
            }
        } else if let (Some(a), Some(b)) = (&pinned.last_modified, &seen.last_modified) {
            if a != b {
                return changed(format!("Last-Modified {a} became {b}"));
            }
        }
        Ok(())
    }
}

/// Which bytes a request asks for.
#[derive(Clone, Copy, Debug)]
enum Span {
    /// Bytes `.0..=.1`.
    At(u64, u64),
    /// The file's last `.0` bytes (all of it, when shorter).
    Last(u64),
}

impl Span {
    fn header(self) -> String {
        match self {
            Span::At(a, b) => format!("bytes={a}-{b}"),
            Span::Last(n) => format!("bytes=-{n}"),
        }
    }
}

impl fmt::Display for Span {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Span::At(a, b) => write!(f, "bytes {a}-{b}"),
            Span::Last(n) => write!(f, "the last {n} bytes"),
        }
    }
}

fn header<'a>(headers: &'a HeaderMap, name: &str) -> Option<&'a str> {
    headers.get(name).and_then(|v| v.to_str().ok())
}

/// A transport failure: a dropped or refused connection or a timeout may pass; a bad URL
/// will not.
fn transport(e: &ureq::Error) -> Failure {
    match e {
        ureq::Error::Io(_)
        | ureq::Error::Timeout(_)
        | ureq::Error::ConnectionFailed
        | ureq::Error::Protocol(_)
        | ureq::Error::BodyStalled => Failure::Retry(e.to_string()),
        other => Failure::Final(RemoteError::new(other.to_string())),
    }
}

/// `bytes START-END/TOTAL` → (start, end, total).
fn parse_content_range(value: &str) -> Option<(u64, u64, u64)> {
    let rest = value.trim().strip_prefix("bytes")?.trim_start();
    let (span, total) = rest.split_once('/')?;
    let (a, b) = span.split_once('-')?;
    let (a, b, total) = (
        a.trim().parse().ok()?,
        b.trim().parse().ok()?,
        total.trim().parse().ok()?,
    );
    (a <= b && b < total).then_some((a, b, total))
}

#[cfg(test)]
mod tests {
    use super::parse_content_range;

    #[test]
    fn content_range_is_read_strictly() {
        assert_eq!(parse_content_range("bytes 0-99/1000"), Some((0, 99, 1000)));
        assert_eq!(parse_content_range("bytes 10-10/11"), Some((10, 10, 11)));
        assert_eq!(parse_content_range("bytes 5-4/10"), None);
        assert_eq!(parse_content_range("bytes 0-10/10"), None);
        assert_eq!(parse_content_range("bytes */1000"), None);
        assert_eq!(parse_content_range("bytes 0-9/*"), None);
        assert_eq!(parse_content_range("items 0-9/10"), None);
    }
}
