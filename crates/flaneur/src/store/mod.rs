//! The page file store: one database file of fixed-size pages.
//!
//! Layered one idea per file:
//! - `header.rs`: page 0, the file header with its segment table (layout drawn there);
//! - `page.rs`: every other page's header (kind, length, checksum) and its codec;
//! - `extent.rs`: blobs stored as runs of contiguous pages, whole or packed at a byte
//!   offset;
//! - `packed.rs`: small blobs of one kind packed into shared pages;
//! - `counters.rs`: the read counters, the papers' currency;
//! - `backend_kind.rs`: [`Backend`], the choice of how a file is read;
//! - `backend/`: where page bytes come from (`mmap`, `pread`, optionally O_DIRECT);
//! - `remote/`: a database on any HTTP server, read by byte ranges through a client
//!   page cache;
//! - `remote_stats.rs`, `request_times.rs`: what reading over HTTP has cost, and how
//!   long each request took: counted by `remote/`, handed on by `backend/`'s trait,
//!   so kept beside both;
//! - `scan.rs`: a page read whatever its kind, for an integrity check;
//! - `source.rs`: [`PageSource`], how a traversal reads node pages (from the store or
//!   through a cache over it), with the [`NodeHint`] a cache weighs them by;
//! - `append.rs`: the store's writes as a build makes them (pages, extents, overwrites),
//!   checked;
//! - `writer.rs`: buffered appends, overwrites and the commit;
//! - `replace.rs`: a new file written beside the old and renamed into its place.
//!
//! Every read goes through [`Store`], which checks the page (range, kind, length,
//! checksum), counts it, and names the page in any error. Nothing in a file can make
//! the store panic.
//!
//! Write model: a new database is written to a temporary file of its own in the target's
//! folder (`.<name>.<random>.tmp`, so two builds to one path never share one) and
//! renamed into place by [`Store::finish`]: the last rename wins, with a complete file.
//! A temporary a killed build left behind is never reused. In an open database the
//! header (page 0) is the commit point, written last, after the pages it names are on
//! disk. Pages past the header's page count are not part of the database. The store
//! never shrinks a file: a new database replaces the old by rename (readers keep the
//! file they opened) and writes to an open one append or rewrite pages in place.

mod append;
mod backend;
mod backend_kind;
mod counters;
mod dictionaries;
mod extent;
mod extent_reads;
pub(crate) mod framing;
mod header;
mod packed;
mod recent_pages;
pub(crate) mod page;
mod remote;
mod remote_stats;
mod replace;
mod request_times;
mod scan;
mod source;
mod writer;

#[cfg(test)]
mod packed_tests;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod write_safety_tests;

use std::fmt;
use std::fs::{File, OpenOptions};
use std::io;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

pub use backend_kind::Backend;
pub use counters::IoStats;
pub use dictionaries::DICTIONARIES_SEGMENT;
pub use extent::Extent;
pub(crate) use header::{valid_page_size, MAX_PAGE_SIZE, MIN_PAGE_SIZE};
pub use header::{Header, Segment, DEFAULT_PAGE_SIZE, FORMAT_VERSION, OLDEST_FORMAT_VERSION};
pub use page::{PageKind, PAGE_HEADER_LEN};
pub use remote::{is_url, HttpOptions};
pub use remote_stats::RemoteStats;
pub(crate) use replace::write_file_atomically;
use replace::{persist, temp_file};
pub use request_times::RequestTimes;
pub use source::{NodeHint, PageSource};

use backend::{MmapSource, PreadSource, RawPageSource};
use counters::Counters;
use header::HeaderError;
use remote::{HttpSource, RemoteError};
use writer::Writer;

/// One database file of fixed-size pages: page 0 is the [`Header`], every other page
/// carries its [`PageKind`], payload length and a checksum verified on every read.
///
/// Reads take `&self` and may run on many threads at once; every page read is counted
/// ([`Store::stats`]). Writes take `&mut self` and need a store from
/// [`Store::create`] or [`Store::open_writable`].
///
/// ```
/// use flaneur::store::{Backend, PageKind, Segment, Store};
///
/// # fn main() -> flaneur::error::Result<()> {
/// let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("city.db");
///
/// let mut store = Store::create(&path, 4096)?;
/// let node = store.append_page(PageKind::RtreeNode, b"a node")?;
/// let mesh = store.append_extent(PageKind::Mesh, &vec![7u8; 10_000])?;
/// store.set_segment(Segment::new("rtree", node, 1, 1))?;
/// store.finish()?; // only now does `path` exist
///
/// let store = Store::open(&path, Backend::Mmap)?;
/// let root = store.header().segment("rtree").unwrap().a;
/// assert_eq!(store.read_page(root, PageKind::RtreeNode)?, b"a node");
/// assert_eq!(store.read_extent(&mesh, PageKind::Mesh)?, vec![7u8; 10_000]);
/// assert_eq!(store.stats().page_reads, 1 + 3);
/// # Ok(())
/// # }
/// ```
pub struct Store {
    /// The database's path (for a created store, where `finish` puts it).
    path: PathBuf,
    header: Header,
    page_size: usize,
    backend: Backend,
    source: Box<dyn RawPageSource>,
    /// Present for created and writable stores.
    writer: Option<Writer>,
    counters: Counters,
    /// Bytes past the committed pages when opened read-only: what an interrupted
    /// writer left (or something appended); never read.
    uncommitted: u64,
    /// Each kind's open page for packed extents (at most one a kind).
    open_pages: Vec<packed::OpenPage>,
    /// Pages this handle has appended, by kind byte.
    pages_written: [u64; page::KIND_SLOTS],
    /// The last mesh and LOD pages read, when asked to keep them.
    recent: recent_pages::RecentPages,
    /// The zstd dictionaries of the geometry frames, once read (`dictionaries`).
    dictionaries: std::sync::OnceLock<Option<crate::scene::Dictionaries>>,
}

const _: fn() = || {
    fn send_sync<T: Send + Sync>() {}
    send_sync::<Store>();
};

impl fmt::Debug for Store {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Store")
            .field("path", &self.path)
            .field("page_size", &self.page_size)
            .field("page_count", &self.header.page_count())
            .field("backend", &self.backend)
            .field("writable", &self.writer.is_some())
            .finish()
    }
}

/// Takes the advisory lock that keeps a database to one writer at a time (`flock`,
/// exclusive, not waiting). Readers take none: a writer only appends and commits by
/// the header, so they never need to wait.
fn lock_for_writing(path: &Path, file: &File) -> Result<()> {
    match file.try_lock() {
        Ok(()) => Ok(()),
        Err(std::fs::TryLockError::WouldBlock) => Err(Error::Invalid(format!(
            "{}: another writer has the database open (it holds the write lock)",
            path.display()
        ))),
        Err(std::fs::TryLockError::Error(e)) => Err(Error::io(path, e)),
    }
}

/// Reads and verifies page 0 of a file `len` bytes long, through `read_at` (bytes at an
/// offset); `path` names the file in errors.
fn read_header(
    path: &Path,
    len: u64,
    read_at: impl Fn(&mut [u8], u64) -> io::Result<()>,
) -> Result<Header> {
    let not_db = |what: String| Error::NotADatabase {
        path: path.to_path_buf(),
        what,
    };
    let corrupt = |what: String| Error::CorruptPage {
        path: path.to_path_buf(),
        page: 0,
        what,
    };
    let map_header_err = |e: HeaderError| match e {
        HeaderError::NotADatabase(w) => not_db(w),
        HeaderError::Corrupt(w) => corrupt(w),
    };
    let mut prefix = vec![0u8; len.min(header::PREFIX_LEN as u64) as usize];
    read_at(&mut prefix, 0).map_err(|e| Error::io(path, e))?;
    let page_size = match Header::check_prefix(&prefix).map_err(map_header_err)? {
        Some(ps) => ps,
        None => {
            return Err(Error::Truncated {
                path: path.to_path_buf(),
                what: format!("the file is {len} bytes, too short to hold a database header"),
            })
        }
    };
    if len < page_size as u64 {
        return Err(Error::Truncated {
            path: path.to_path_buf(),
            what: format!("the file is {len} bytes, shorter than its {page_size}-byte header page"),
        });
    }
    let mut page0 = vec![0u8; page_size];
    read_at(&mut page0, 0).map_err(|e| Error::io(path, e))?;
    Header::decode(&page0).map_err(map_header_err)
}

/// Checks a file of `len` bytes against its header's page count; `writable` files may
/// hold uncommitted pages past it.
fn check_length(path: &Path, header: &Header, len: u64, writable: bool) -> Result<()> {
    let page_size = header.page_size();
    let truncated = |what: String| Error::Truncated {
        path: path.to_path_buf(),
        what,
    };
    let needed = header
        .page_count()
        .checked_mul(page_size as u64)
        .ok_or_else(|| Error::CorruptPage {
            path: path.to_path_buf(),
            page: 0,
            what: format!("page count {} is impossibly large", header.page_count()),
        })?;
    if len < needed {
        return Err(truncated(format!(
            "the header says {} pages of {page_size} bytes ({needed} bytes), the file has {len} bytes",
            header.page_count()
        )));
    }
    if !writable && !len.is_multiple_of(page_size as u64) {
        return Err(truncated(format!(
            "the file is {len} bytes, not a whole number of {page_size}-byte pages"
        )));
    }
    Ok(())
}

impl Store {
    /// Opens an existing database read-only. Many readers (threads or processes) may
    /// share one file.
    ///
    /// Errors: `NotADatabase` (empty file, bad magic, other format version, bad page
    /// size), `CorruptPage` page 0 (header checksum), `Truncated` (file shorter than
    /// its page count, or not a whole number of pages), `Io` (including a filesystem
    /// that refuses O_DIRECT for `Backend::Pread { direct: true }`).
    pub fn open(path: &Path, backend: Backend) -> Result<Store> {
        Store::open_existing(path, backend, false)
    }

    /// Opens an existing database for appending and overwriting pages (e.g. to insert
    /// objects into an index). Changes are committed by [`Store::flush`] or
    /// [`Store::finish`]; pages appended after the last commit are discarded when the
    /// store is dropped or the file is reopened. Overwrites of committed pages are
    /// written in place and are not rolled back.
    ///
    /// Takes an exclusive advisory lock on the file until the store is dropped: a
    /// second writer, in this process or another, is refused (`Invalid`, "another writer
    /// has the database open"). Readers take no lock.
    pub fn open_writable(path: &Path, backend: Backend) -> Result<Store> {
        Store::open_existing(path, backend, true)
    }

    /// Opens a database on an HTTP server, read-only, by byte ranges: any static server
    /// that honours `Range` will do. The first round trip fetches `opts.prefix_bytes` from
    /// the start of the file (the header) and `opts.suffix_bytes` from its end (the
    /// R-tree's upper levels), two requests at once, and pins the file's version: its
    /// ETag goes back as `If-Match` on every later request, and an answer from another
    /// version is [`Error::RemoteChanged`]. Pages are checked as on disk and counted the
    /// same; [`Store::remote_stats`] says what the network cost.
    ///
    /// Errors: as [`Store::open`] for what the bytes hold, and [`Error::Remote`] for the
    /// server (unreachable after the retries, no range support, a wrong answer).
    pub fn open_url(url: &str, opts: &HttpOptions) -> Result<Store> {
        let path = PathBuf::from(url);
        let connected = HttpSource::connect(url, opts).map_err(|e| e.into_error(url))?;
        let len = connected.ends.len;
        let header = read_header(&path, len, |buf, at| {
            let at = at as usize;
            match connected.ends.head.get(at..at + buf.len()) {
                Some(bytes) => {
                    buf.copy_from_slice(bytes);
                    Ok(())
                }
                None => Err(io::Error::new(
                    io::ErrorKind::UnexpectedEof,
                    "the header lies beyond the first request's bytes",
                )),
            }
        })?;
        check_length(&path, &header, len, false)?;
        let page_size = header.page_size();
        Ok(Store {
            source: Box::new(HttpSource::new(connected, page_size, opts).map_err(|e| {
                Error::Io {
                    path: path.clone(),
                    source: e,
                }
            })?),
            path,
            header,
            page_size,
            backend: Backend::Http,
            writer: None,
            counters: Counters::default(),
            recent: Default::default(),
            dictionaries: Default::default(),
            uncommitted: 0,
            open_pages: Vec::new(),
            pages_written: [0; page::KIND_SLOTS],
        })
    }

    fn open_existing(path: &Path, backend: Backend, writable: bool) -> Result<Store> {
        let io_err = |e| Error::io(path, e);
        let file = OpenOptions::new()
            .read(true)
            .write(writable)
            .open(path)
            .map_err(io_err)?;
        if writable {
            lock_for_writing(path, &file)?;
        }
        let len = file.metadata().map_err(io_err)?.len();
        let header = read_header(path, len, |buf, at| file.read_exact_at(buf, at))?;
        let page_size = header.page_size();
        check_length(path, &header, len, writable)?;
        let needed = header.page_count() * page_size as u64;
        let mut uncommitted = len - needed;
        if writable && uncommitted > 0 {
            // Pages appended after the last commit: not part of the database. No reader
            // reads past the page count of a committed header, so none is cut short.
            file.set_len(needed).map_err(io_err)?;
            uncommitted = 0;
        }
        let source: Box<dyn RawPageSource> = match backend {
            Backend::Mmap => Box::new(
                MmapSource::new(file.try_clone().map_err(io_err)?, page_size).map_err(io_err)?,
            ),
            Backend::Pread { direct: false } => Box::new(PreadSource::buffered(
                file.try_clone().map_err(io_err)?,
                page_size,
            )),
            Backend::Pread { direct: true } => {
                Box::new(PreadSource::direct(path, page_size).map_err(io_err)?)
            }
            Backend::Http => {
                return Err(Error::Invalid(format!(
                    "{}: the http backend reads URLs (Store::open_url), not files",
                    path.display()
                )))
            }
        };
        let writer = writable.then(|| Writer::new(file, page_size, header.page_count(), None));
        Ok(Store {
            path: path.to_path_buf(),
            header,
            page_size,
            backend,
            source,
            writer,
            counters: Counters::default(),
            recent: Default::default(),
            dictionaries: Default::default(),
            uncommitted,
            open_pages: Vec::new(),
            pages_written: [0; page::KIND_SLOTS],
        })
    }

    /// Starts a new database with `page_size`-byte pages (a power of two in
    /// 1 KiB..=64 KiB; [`DEFAULT_PAGE_SIZE`] is 4096). It is written to a temporary
    /// file of its own beside `path`; nothing appears at `path` until
    /// [`Store::finish`], and dropping the store unfinished removes the temporary file. The new store reads its own pages
    /// (through `pread`).
    pub fn create(path: &Path, page_size: usize) -> Result<Store> {
        if !valid_page_size(page_size) {
            return Err(Error::Invalid(format!(
                "page size {page_size} is not a power of two in {MIN_PAGE_SIZE}..={MAX_PAGE_SIZE}"
            )));
        }
        let (file, temp) = temp_file(path)
            .map_err(|e| Error::io(path, e))?
            .into_parts();
        let reader = file.try_clone().map_err(|e| Error::io(&temp, e))?;
        let writer = Writer::new(file, page_size, 0, Some(temp));
        Ok(Store {
            path: path.to_path_buf(),
            header: Header::new(page_size),
            page_size,
            backend: Backend::Pread { direct: false },
            source: Box::new(PreadSource::buffered(reader, page_size)),
            writer: Some(writer),
            counters: Counters::default(),
            recent: Default::default(),
            dictionaries: Default::default(),
            uncommitted: 0,
            open_pages: Vec::new(),
            pages_written: [0; page::KIND_SLOTS],
        })
    }

    /// Commits and closes. A created store: writes all pages and the header, fsyncs
    /// and renames the temporary file to `path`. A writable store: writes the header
    /// and fsyncs. A read-only store: nothing to do.
    pub fn finish(mut self) -> Result<()> {
        let Some(mut w) = self.writer.take() else {
            return Ok(());
        };
        let file_path = w.file_path().unwrap_or(&self.path).to_path_buf();
        w.commit(&self.header)
            .map_err(|e| Error::io(&file_path, e))?;
        if let Some(temp) = w.take_temp() {
            persist(temp, &self.path)?;
        }
        Ok(())
    }

    /// Commits without closing: writes pending pages and the header, fsyncs. For a
    /// created store the file is still the temporary one. A read-only store: nothing to do.
    /// Closes the open pages of packed extents: later packed blobs start fresh pages.
    pub fn flush(&mut self) -> Result<()> {
        self.close_open_pages();
        let Some(w) = self.writer.as_mut() else {
            return Ok(());
        };
        let file_path = w.file_path().unwrap_or(&self.path).to_path_buf();
        w.commit(&self.header)
            .map_err(|e| Error::io(&file_path, e))?;
        self.source.refresh().map_err(|e| Error::io(&file_path, e))
    }

    /// The database's path (for a created store, where `finish` will put it).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Bytes per page.
    pub fn page_size(&self) -> usize {
        self.page_size
    }

    /// Payload bytes per page: `page_size - PAGE_HEADER_LEN`.
    pub fn payload_size(&self) -> usize {
        self.page_size - PAGE_HEADER_LEN
    }

    /// Pages in the database, header included; the next appended page gets this id.
    pub fn page_count(&self) -> u64 {
        self.header.page_count()
    }

    /// The file header (as it will be written at the next commit, for a writer).
    pub fn header(&self) -> &Header {
        &self.header
    }

    /// The extent that segment `name` names as (a = first page, b = byte length), with
    /// the segment's third value for the caller to check; `None` without the segment.
    /// A `CorruptPage` (page 0) naming the segment when the extent is empty, starts at
    /// the header, or does not lie inside the file; `check` adds the caller's own
    /// conditions on the extent and c (`Err` with what is wrong).
    pub fn segment_extent(
        &self,
        name: &str,
        check: impl Fn(&Extent, u64) -> std::result::Result<(), String>,
    ) -> Result<Option<(Extent, u64)>> {
        let Some(seg) = self.header.segment(name) else {
            return Ok(None);
        };
        let bad = |what: String| Error::CorruptPage {
            path: self.path.clone(),
            page: 0,
            what: format!("segment {name:?}: {what}"),
        };
        let byte_len = u32::try_from(seg.b).map_err(|_| bad(format!("length {}", seg.b)))?;
        let extent = Extent {
            first_page: seg.a,
            page_count: Extent::pages_for(byte_len as usize, self.payload_size()) as u32,
            byte_len,
            offset: 0,
            packed: false,
        };
        if extent.page_count == 0 || extent.first_page == 0 || extent.end_page() > self.page_count()
        {
            return Err(bad(format!(
                "{byte_len} bytes at page {} do not lie in a file of {} pages",
                seg.a,
                self.page_count()
            )));
        }
        check(&extent, seg.c).map_err(bad)?;
        Ok(Some((extent, seg.c)))
    }

    /// How this store reads pages (a created store reads with `pread`).
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// Bytes in the file past its committed pages, for a store opened read-only: what
    /// a writer interrupted before its commit leaves, or bytes appended by something
    /// else. They are never read; the next writer to open the file cuts them off.
    pub fn uncommitted_bytes(&self) -> u64 {
        self.uncommitted
    }

    /// Whether this store accepts writes.
    pub fn is_writable(&self) -> bool {
        self.writer.is_some()
    }

    /// Inserts `seg` into the header's segment table, or replaces the segment of the
    /// same name. Persisted at the next `flush`/`finish`. Errors: read-only store,
    /// name empty, over 15 bytes or not ascii, table full.
    pub fn set_segment(&mut self, seg: Segment) -> Result<()> {
        if self.writer.is_none() {
            return Err(self.read_only("set a segment"));
        }
        let path = &self.path;
        self.header
            .set_segment(seg)
            .map_err(|why| Error::Invalid(format!("{}: {why}", path.display())))
    }

    fn read_only(&self, what: &str) -> Error {
        Error::Invalid(format!(
            "{}: cannot {what}: the store is open read-only",
            self.path.display()
        ))
    }

    fn corrupt(&self, page: u64, what: String) -> Error {
        Error::CorruptPage {
            path: self.path.clone(),
            page,
            what,
        }
    }

    fn read_error(&self, page: u64, e: io::Error) -> Error {
        let e = match e.downcast::<RemoteError>() {
            Ok(remote) => return remote.into_error(&self.path.to_string_lossy()),
            Err(e) => e,
        };
        if e.kind() == io::ErrorKind::UnexpectedEof {
            Error::Truncated {
                path: self.path.clone(),
                what: format!("page {page} lies beyond the end of the file"),
            }
        } else {
            Error::io(&self.path, e)
        }
    }

    /// Checks that `page` is a data page of this database.
    #[inline]
    fn check_range(&self, page: u64) -> Result<()> {
        if page == 0 {
            return Err(self.corrupt(0, "page 0 is the file header, not a data page".to_string()));
        }
        let count = self.header.page_count();
        if page >= count {
            return Err(self.corrupt(
                page,
                format!("page {page} is beyond the end of the database ({count} pages)"),
            ));
        }
        Ok(())
    }

    /// The bytes of `page` where they are in memory (write buffer or map).
    #[inline]
    fn in_memory(&self, page: u64) -> Option<&[u8]> {
        match &self.writer {
            Some(w) => w
                .pending_page(page)
                .or_else(|| self.source.page_bytes(page)),
            None => self.source.page_bytes(page),
        }
    }

    #[inline]
    fn verify<'a>(&self, page: u64, bytes: &'a [u8], kind: PageKind) -> Result<&'a [u8]> {
        page::decode(bytes, kind).map_err(|what| self.corrupt(page, what))
    }

    /// Reads, counts and verifies `page`, appending its payload to `out`; returns the
    /// payload length. `scratch` holds the page when it has to be copied in.
    fn read_append(
        &self,
        page: u64,
        kind: PageKind,
        scratch: &mut Vec<u8>,
        out: &mut Vec<u8>,
    ) -> Result<usize> {
        self.check_range(page)?;
        if let Some(len) = self.recent.append(page, kind, out) {
            return Ok(len);
        }
        self.counters.record(kind);
        let payload = match self.in_memory(page) {
            Some(bytes) => self.verify(page, bytes, kind)?,
            None => {
                scratch.resize(self.page_size, 0);
                self.source
                    .read(page, scratch)
                    .map_err(|e| self.read_error(page, e))?;
                self.verify(page, scratch, kind)?
            }
        };
        self.recent.put(page, kind, payload);
        out.extend_from_slice(payload);
        Ok(payload.len())
    }

    /// Reads data page `page`, which must be of `kind`, and returns its payload.
    /// Counted. Errors (`CorruptPage` naming the page): page 0 or beyond the page
    /// count, blank page, wrong kind (expected and found are named), bad payload
    /// length, checksum mismatch.
    pub fn read_page(&self, page: u64, kind: PageKind) -> Result<Vec<u8>> {
        let mut buf = Vec::new();
        self.read_page_into(page, kind, &mut buf)?;
        Ok(buf)
    }

    /// [`Store::read_page`] into a reused buffer (the hot path): `buf` is replaced by
    /// the payload. On error its contents are unspecified.
    pub fn read_page_into(&self, page: u64, kind: PageKind, buf: &mut Vec<u8>) -> Result<()> {
        self.check_range(page)?;
        self.counters.record(kind);
        buf.clear();
        if let Some(bytes) = self.in_memory(page) {
            buf.extend_from_slice(self.verify(page, bytes, kind)?);
            return Ok(());
        }
        buf.resize(self.page_size, 0);
        self.source
            .read(page, buf)
            .map_err(|e| self.read_error(page, e))?;
        let len = self.verify(page, buf, kind)?.len();
        buf.copy_within(PAGE_HEADER_LEN..PAGE_HEADER_LEN + len, 0);
        buf.truncate(len);
        Ok(())
    }

    /// Page `page`'s payload into `buf` if a remote store holds it without a round trip,
    /// checked but not counted: a traversal looking ahead for what to fetch together.
    /// `false` on a local store, and for a page that fails its checks (the read proper
    /// will name it).
    pub(crate) fn peek_page_into(&self, page: u64, kind: PageKind, buf: &mut Vec<u8>) -> bool {
        if self.backend != Backend::Http || self.check_range(page).is_err() {
            return false;
        }
        buf.clear();
        buf.resize(self.page_size, 0);
        if !self.source.cached(page, buf) {
            return false;
        }
        let Ok(len) = self.verify(page, buf, kind).map(<[u8]>::len) else {
            return false;
        };
        buf.copy_within(PAGE_HEADER_LEN..PAGE_HEADER_LEN + len, 0);
        buf.truncate(len);
        true
    }

    /// From now on, keeps the last `pages` mesh and LOD pages read (0: none, the
    /// default), so that a page several packed extents share is read once while they are
    /// wanted (format version 2 packs small extents several to a page). A kept page is
    /// not read again, so not counted. A store being written keeps none: its pages may
    /// still change.
    ///
    /// ```
    /// # fn main() -> flaneur::Result<()> {
    /// # let dir = tempfile::tempdir().unwrap();
    /// # let path = dir.path().join("p.db");
    /// use flaneur::store::{PageKind, Store};
    /// let mut store = Store::create(&path, 4096)?;
    /// let ext = store.append_extent(PageKind::Mesh, &[1; 9000])?;
    /// store.finish()?;
    /// let store = Store::open(&path, Default::default())?;
    /// store.keep_recent_pages(64);
    /// store.read_extent(&ext, PageKind::Mesh)?;
    /// store.read_extent(&ext, PageKind::Mesh)?;
    /// assert_eq!(store.stats().page_reads, 3);
    /// # Ok(()) }
    /// ```
    pub fn keep_recent_pages(&self, pages: usize) {
        self.recent.keep(if self.is_writable() { 0 } else { pages });
    }

    /// What reading over HTTP has cost so far; `None` for a local file.
    pub fn remote_stats(&self) -> Option<RemoteStats> {
        self.source.remote_stats()
    }

    /// How long each request over HTTP took so far; `None` for a local file.
    pub fn remote_request_times(&self) -> Option<RequestTimes> {
        self.source.request_times()
    }

    /// A snapshot of the read counters.
    pub fn stats(&self) -> IoStats {
        self.counters.snapshot(self.page_size)
    }

    /// Sets the read counters to zero.
    pub fn reset_stats(&self) {
        self.counters.reset()
    }
}
