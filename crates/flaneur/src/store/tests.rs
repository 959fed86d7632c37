//! Store tests on real files in temporary directories, on every backend.

use std::fs::OpenOptions;
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

use super::header::{max_segments, MAGIC};
use super::*;

pub(super) const PS: usize = 1024;

fn blob(len: usize, seed: u8) -> Vec<u8> {
    (0..len)
        .map(|i| (i as u8).wrapping_mul(31).wrapping_add(seed))
        .collect()
}

/// The blob sizes that exercise extent edges, for a store with payload size `p`.
fn extent_sizes(p: usize) -> Vec<usize> {
    vec![0, 1, p - 1, p, p + 1, 3 * p, 3 * p + 17]
}

/// A database with one page of each data kind and extents of every edge size;
/// returns the path, the single pages and the extents with their contents.
pub(super) struct Fixture {
    _dir: tempfile::TempDir,
    pub(super) path: PathBuf,
    pages: Vec<(u64, PageKind, Vec<u8>)>,
    pub(super) extents: Vec<(Extent, Vec<u8>)>,
}

pub(super) fn build(page_size: usize) -> Fixture {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.db");
    let mut s = Store::create(&path, page_size).unwrap();
    let p = s.payload_size();
    let mut pages = Vec::new();
    let mut extents = Vec::new();
    for (i, kind) in [PageKind::RtreeNode, PageKind::Mesh, PageKind::Meta]
        .into_iter()
        .enumerate()
    {
        for len in [0, 1, p] {
            let b = blob(len, i as u8);
            let id = s.append_page(kind, &b).unwrap();
            pages.push((id, kind, b));
        }
    }
    for (i, len) in extent_sizes(p).into_iter().enumerate() {
        let b = blob(len, 100 + i as u8);
        let e = s.append_extent(PageKind::Mesh, &b).unwrap();
        assert_eq!(e.byte_len as usize, len);
        assert_eq!(e.page_count as usize, len.div_ceil(p));
        extents.push((e, b));
    }
    s.set_segment(Segment::new("rtree", 1, 2, 3)).unwrap();
    s.finish().unwrap();
    Fixture {
        _dir: dir,
        path,
        pages,
        extents,
    }
}

pub(super) fn check_all(f: &Fixture, s: &Store) {
    for (id, kind, b) in &f.pages {
        assert_eq!(&s.read_page(*id, *kind).unwrap(), b, "page {id}");
        let mut buf = vec![1, 2, 3];
        s.read_page_into(*id, *kind, &mut buf).unwrap();
        assert_eq!(&buf, b);
    }
    for (e, b) in &f.extents {
        assert_eq!(&s.read_extent(e, PageKind::Mesh).unwrap(), b, "{e:?}");
    }
    assert_eq!(
        s.header().segment("rtree"),
        Some(&Segment::new("rtree", 1, 2, 3))
    );
}

/// Opens with `backend`, or explains why O_DIRECT is unavailable here and returns None.
fn open_or_skip(path: &Path, backend: Backend) -> Option<Store> {
    match Store::open(path, backend) {
        Ok(s) => Some(s),
        Err(e)
            if backend == (Backend::Pread { direct: true })
                && e.to_string().contains("O_DIRECT") =>
        {
            eprintln!("skipping the O_DIRECT case: {e}");
            None
        }
        Err(e) => panic!("open with {backend}: {e}"),
    }
}

fn probe_direct(s: &Store, page: u64, kind: PageKind) -> bool {
    match s.read_page(page, kind) {
        Err(e) if e.to_string().contains("O_DIRECT") => {
            eprintln!("skipping the O_DIRECT case: {e}");
            false
        }
        _ => true,
    }
}

const BACKENDS: [Backend; 3] = [
    Backend::Mmap,
    Backend::Pread { direct: false },
    Backend::Pread { direct: true },
];

#[test]
fn round_trip_every_backend() {
    for ps in [PS, 4096] {
        let f = build(ps);
        for backend in BACKENDS {
            let Some(s) = open_or_skip(&f.path, backend) else {
                continue;
            };
            if backend == (Backend::Pread { direct: true })
                && !probe_direct(&s, 1, PageKind::RtreeNode)
            {
                continue;
            }
            assert_eq!(s.page_size(), ps);
            assert_eq!(s.payload_size(), ps - PAGE_HEADER_LEN);
            assert_eq!(s.backend(), backend);
            assert!(!s.is_writable());
            check_all(&f, &s);
        }
    }
}

#[test]
fn created_store_reads_its_own_pages() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("own.db");
    let mut s = Store::create(&path, PS).unwrap();
    // Enough pages to spill the write buffer several times.
    let n = 3 * writer::WRITE_BUFFER_BYTES / PS + 5;
    for i in 0..n {
        s.append_page(PageKind::Meta, &(i as u64).to_le_bytes())
            .unwrap();
    }
    for i in [0, 1, n / 2, n - 1] {
        let got = s.read_page(i as u64 + 1, PageKind::Meta).unwrap();
        assert_eq!(got, (i as u64).to_le_bytes());
    }
    // Overwrite one page on file and one in the buffer.
    s.write_page(2, PageKind::Meta, b"on file").unwrap();
    s.write_page(n as u64, PageKind::Meta, b"buffered").unwrap();
    assert_eq!(s.read_page(2, PageKind::Meta).unwrap(), b"on file");
    assert_eq!(s.read_page(n as u64, PageKind::Meta).unwrap(), b"buffered");
    s.finish().unwrap();
    let s = Store::open(&path, Backend::Mmap).unwrap();
    assert_eq!(s.page_count(), n as u64 + 1);
    assert_eq!(s.read_page(2, PageKind::Meta).unwrap(), b"on file");
    assert_eq!(s.read_page(n as u64, PageKind::Meta).unwrap(), b"buffered");
    assert_eq!(s.read_page(3, PageKind::Meta).unwrap(), 2u64.to_le_bytes());
}

#[test]
fn counters_count_every_page_read() {
    let f = build(PS);
    for backend in [Backend::Mmap, Backend::Pread { direct: false }] {
        let s = Store::open(&f.path, backend).unwrap();
        assert_eq!(s.stats(), IoStats::default(), "open is not counted");
        let (node, _, _) = f.pages[0];
        let (mesh, _, _) = f.pages[3];
        s.read_page(node, PageKind::RtreeNode).unwrap();
        s.read_page(node, PageKind::RtreeNode).unwrap();
        let mut buf = Vec::new();
        s.read_page_into(mesh, PageKind::Mesh, &mut buf).unwrap();
        let before = s.stats();
        assert_eq!(before.page_reads, 3);
        assert_eq!(before.bytes_read, 3 * PS as u64);
        assert_eq!(before.reads_of(PageKind::RtreeNode), 2);
        assert_eq!(before.reads_of(PageKind::Mesh), 1);
        assert_eq!(before.reads_of(PageKind::Meta), 0);
        // Extents: one count per page; the empty one costs nothing.
        let total: u64 = f.extents.iter().map(|(e, _)| u64::from(e.page_count)).sum();
        for (e, _) in &f.extents {
            s.read_extent(e, PageKind::Mesh).unwrap();
        }
        // A failed read (wrong kind) is still a physical read, counted as requested.
        assert!(s.read_page(node, PageKind::Meta).is_err());
        // An out-of-range request reads nothing.
        assert!(s.read_page(s.page_count(), PageKind::Meta).is_err());
        let d = s.stats().since(&before);
        assert_eq!(d.page_reads, total + 1);
        assert_eq!(d.reads_of(PageKind::Mesh), total);
        assert_eq!(d.reads_of(PageKind::Meta), 1);
        assert_eq!(d.reads_of(PageKind::RtreeNode), 0);
        assert_eq!(d.bytes_read, (total + 1) * PS as u64);
        s.reset_stats();
        assert_eq!(s.stats(), IoStats::default());
        // Reads from many threads through &self.
        std::thread::scope(|sc| {
            for _ in 0..4 {
                sc.spawn(|| {
                    for _ in 0..50 {
                        s.read_page(node, PageKind::RtreeNode).unwrap();
                    }
                });
            }
        });
        assert_eq!(s.stats().reads_of(PageKind::RtreeNode), 200);
    }
}

fn corrupt_byte(path: &Path, offset: u64) {
    let f = OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)
        .unwrap();
    let mut b = [0u8; 1];
    f.read_exact_at(&mut b, offset).unwrap();
    b[0] ^= 0x20;
    f.write_all_at(&b, offset).unwrap();
}

pub(super) fn set_len(path: &Path, len: u64) {
    OpenOptions::new()
        .write(true)
        .open(path)
        .unwrap()
        .set_len(len)
        .unwrap();
}

pub(super) fn file_len(path: &Path) -> u64 {
    std::fs::metadata(path).unwrap().len()
}

#[test]
fn flipped_payload_byte_names_the_page() {
    let f = build(PS);
    let (page, kind, _) = f.pages[1]; // a one-byte payload
    corrupt_byte(&f.path, page * PS as u64 + PAGE_HEADER_LEN as u64);
    for backend in [Backend::Mmap, Backend::Pread { direct: false }] {
        let s = Store::open(&f.path, backend).unwrap();
        match s.read_page(page, kind) {
            Err(Error::CorruptPage { page: p, what, .. }) => {
                assert_eq!(p, page);
                assert!(what.contains("checksum"), "{what}");
            }
            other => panic!("expected CorruptPage, got {other:?}"),
        }
        // The neighbours are fine.
        s.read_page(page + 1, kind).unwrap();
    }
    // A flip inside an extent names the extent's page.
    let (e, _) = &f.extents[5];
    let bad = e.first_page + 1;
    corrupt_byte(&f.path, bad * PS as u64 + 500);
    let s = Store::open(&f.path, Backend::Mmap).unwrap();
    match s.read_extent(e, PageKind::Mesh) {
        Err(Error::CorruptPage { page: p, .. }) => assert_eq!(p, bad),
        other => panic!("expected CorruptPage, got {other:?}"),
    }
}

#[test]
fn flipped_header_byte_is_an_error() {
    // The page count, a segment value, and the zero tail of page 0.
    for offset in [16u64, 32 + 20, PS as u64 - 1] {
        let f = build(PS);
        corrupt_byte(&f.path, offset);
        let e = Store::open(&f.path, Backend::Mmap).unwrap_err();
        assert!(
            matches!(
                e,
                Error::CorruptPage { page: 0, .. } | Error::NotADatabase { .. }
            ),
            "offset {offset}: {e}"
        );
    }
}

#[test]
fn truncated_files() {
    let f = build(PS);
    let len = file_len(&f.path);
    for cut in [1, PS as u64] {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("cut.db");
        std::fs::copy(&f.path, &p).unwrap();
        set_len(&p, len - cut);
        for backend in [Backend::Mmap, Backend::Pread { direct: false }] {
            let e = Store::open(&p, backend).unwrap_err();
            assert!(matches!(e, Error::Truncated { .. }), "cut {cut}: {e}");
        }
        assert!(matches!(
            Store::open_writable(&p, Backend::Mmap),
            Err(Error::Truncated { .. })
        ));
    }
    // Shorter than the header page, and shorter than the header prefix.
    for keep in [PS as u64 - 1, 20] {
        set_len(&f.path, keep);
        let e = Store::open(&f.path, Backend::Mmap).unwrap_err();
        assert!(matches!(e, Error::Truncated { .. }), "{keep} bytes: {e}");
    }
}

#[test]
fn longer_file_not_whole_pages() {
    let f = build(PS);
    let len = file_len(&f.path);
    set_len(&f.path, len + 10);
    let e = Store::open(&f.path, Backend::Mmap).unwrap_err();
    assert!(matches!(e, Error::Truncated { .. }), "{e}");
    // A writer drops an uncommitted tail.
    Store::open_writable(&f.path, Backend::Mmap)
        .unwrap()
        .finish()
        .unwrap();
    assert_eq!(file_len(&f.path), len);
    Store::open(&f.path, Backend::Mmap).unwrap();
}

#[test]
fn wrong_magic_and_version() {
    let f = build(PS);
    corrupt_byte(&f.path, 0);
    let e = Store::open(&f.path, Backend::Mmap).unwrap_err();
    assert!(
        matches!(&e, Error::NotADatabase { what, .. } if what.contains("magic")),
        "{e}"
    );

    let f = build(PS);
    let mut page0 = vec![0u8; PS];
    let file = OpenOptions::new()
        .read(true)
        .write(true)
        .open(&f.path)
        .unwrap();
    file.read_exact_at(&mut page0, 0).unwrap();
    let mut h = Header::decode(&page0).unwrap();
    h.version = crate::store::FORMAT_VERSION + 1;
    h.encode(&mut page0);
    file.write_all_at(&page0, 0).unwrap();
    let e = Store::open(&f.path, Backend::Pread { direct: false }).unwrap_err();
    match &e {
        Error::NotADatabase { what, .. } => {
            assert!(what.contains("version 3") && what.contains("1..=2"), "{what}")
        }
        _ => panic!("{e}"),
    }
}

#[test]
fn bad_requests_are_corrupt_page_errors() {
    let f = build(PS);
    let s = Store::open(&f.path, Backend::Mmap).unwrap();
    let n = s.page_count();
    for page in [0, n, n + 1000, u64::MAX] {
        match s.read_page(page, PageKind::Mesh) {
            Err(Error::CorruptPage { page: p, .. }) => assert_eq!(p, page),
            other => panic!("page {page}: {other:?}"),
        }
    }
    let (node, _, _) = f.pages[0];
    match s.read_page(node, PageKind::Mesh) {
        Err(Error::CorruptPage { page, what, .. }) => {
            assert_eq!(page, node);
            assert!(
                what.contains("expected mesh") && what.contains("rtree-node"),
                "{what}"
            );
        }
        other => panic!("{other:?}"),
    }
    // Inconsistent extents.
    let (e, _) = f.extents[4];
    for bad in [
        Extent {
            byte_len: e.byte_len + PS as u32,
            ..e
        },
        Extent {
            page_count: e.page_count + 1,
            ..e
        },
        Extent { byte_len: 0, ..e },
        Extent {
            first_page: n - 1,
            ..e
        },
        Extent {
            first_page: u64::MAX,
            ..e
        },
        Extent { first_page: 0, ..e },
    ] {
        assert!(
            matches!(
                s.read_extent(&bad, PageKind::Mesh),
                Err(Error::CorruptPage { .. })
            ),
            "{bad:?}"
        );
    }
    // The right number of pages but the wrong split: a short page in the middle.
    let p = s.payload_size() as u32;
    let (one, _) = f.extents[1]; // a 1-byte extent, followed by a (p - 1)-byte one
    let bad = Extent {
        first_page: one.first_page,
        page_count: 2,
        byte_len: p + 1,
        ..Extent::default()
    };
    assert!(matches!(
        s.read_extent(&bad, PageKind::Mesh),
        Err(Error::CorruptPage { .. })
    ));
    // Writes to a read-only store.
    let mut s = s;
    assert!(matches!(
        s.append_page(PageKind::Meta, b"x"),
        Err(Error::Invalid(_))
    ));
    assert!(matches!(
        s.write_page(1, PageKind::Meta, b"x"),
        Err(Error::Invalid(_))
    ));
    assert!(matches!(
        s.append_extent(PageKind::Meta, b"x"),
        Err(Error::Invalid(_))
    ));
    assert!(matches!(
        s.set_segment(Segment::new("a", 0, 0, 0)),
        Err(Error::Invalid(_))
    ));
    s.flush().unwrap();
}

#[test]
fn empty_and_random_files_are_not_databases() {
    let dir = tempfile::tempdir().unwrap();
    let empty = dir.path().join("empty");
    std::fs::write(&empty, b"").unwrap();
    let e = Store::open(&empty, Backend::Mmap).unwrap_err();
    assert!(matches!(e, Error::NotADatabase { .. }), "{e}");

    let text = dir.path().join("text");
    std::fs::write(&text, "just some text, not a database\n".repeat(200)).unwrap();
    let e = Store::open(&text, Backend::Pread { direct: false }).unwrap_err();
    assert!(matches!(e, Error::NotADatabase { .. }), "{e}");

    let random = dir.path().join("random");
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    let bytes: Vec<u8> = (0..3 * 4096)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u8
        })
        .collect();
    std::fs::write(&random, &bytes).unwrap();
    let e = Store::open(&random, Backend::Mmap).unwrap_err();
    assert!(matches!(e, Error::NotADatabase { .. }), "{e}");

    // The right magic followed by garbage: never a panic.
    let mut b = bytes.clone();
    b[..8].copy_from_slice(&MAGIC);
    std::fs::write(&random, &b).unwrap();
    assert!(Store::open(&random, Backend::Mmap).is_err());

    let missing = dir.path().join("missing");
    assert!(matches!(
        Store::open(&missing, Backend::Mmap),
        Err(Error::Io { .. })
    ));
}

#[test]
fn created_store_appears_only_at_finish() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("new.db");
    {
        let mut s = Store::create(&path, PS).unwrap();
        s.append_extent(PageKind::Mesh, &blob(5 * PS, 1)).unwrap();
        s.flush().unwrap();
        assert!(!path.exists());
    }
    assert!(!path.exists(), "dropped unfinished: no file");
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "temp file removed"
    );

    let mut s = Store::create(&path, PS).unwrap();
    s.append_page(PageKind::Meta, b"hello").unwrap();
    assert!(!path.exists());
    s.finish().unwrap();
    assert!(path.exists());
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "only the database"
    );
    let s = Store::open(&path, Backend::Mmap).unwrap();
    assert_eq!(s.read_page(1, PageKind::Meta).unwrap(), b"hello");

    // finish replaces an existing database.
    let mut s = Store::create(&path, 2048).unwrap();
    s.append_page(PageKind::Meta, b"second").unwrap();
    s.finish().unwrap();
    let s = Store::open(&path, Backend::Mmap).unwrap();
    assert_eq!((s.page_size(), s.page_count()), (2048, 2));

    assert!(matches!(Store::create(&path, 1000), Err(Error::Invalid(_))));
    assert!(matches!(Store::create(&path, 512), Err(Error::Invalid(_))));
    assert!(matches!(
        Store::create(&path, 128 * 1024),
        Err(Error::Invalid(_))
    ));
}

#[test]
fn write_checks() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = Store::create(&dir.path().join("w.db"), PS).unwrap();
    let p = s.payload_size();
    assert!(matches!(
        s.append_page(PageKind::Meta, &vec![0; p + 1]),
        Err(Error::Invalid(_))
    ));
    assert!(matches!(
        s.append_page(PageKind::Header, b""),
        Err(Error::Invalid(_))
    ));
    let id = s.append_page(PageKind::Meta, &vec![0; p]).unwrap();
    assert_eq!(id, 1);
    assert!(matches!(
        s.write_page(0, PageKind::Meta, b""),
        Err(Error::Invalid(_))
    ));
    assert!(matches!(
        s.write_page(2, PageKind::Meta, b""),
        Err(Error::Invalid(_))
    ));
    assert!(matches!(
        s.write_page(1, PageKind::Meta, &vec![0; p + 1]),
        Err(Error::Invalid(_))
    ));
    let e = s.append_extent(PageKind::Mesh, b"").unwrap();
    assert_eq!(
        e,
        Extent {
            first_page: 2,
            page_count: 0,
            byte_len: 0,
            ..Extent::default()
        }
    );
    assert_eq!(s.read_extent(&e, PageKind::Mesh).unwrap(), b"");
    assert_eq!(s.page_count(), 2);
}

#[test]
fn open_writable_append_overwrite_segment() {
    for backend in [Backend::Mmap, Backend::Pread { direct: false }] {
        let f = build(PS);
        let before = Store::open(&f.path, Backend::Mmap).unwrap().page_count();
        let mut s = Store::open_writable(&f.path, backend).unwrap();
        assert!(s.is_writable());
        let (node, _, _) = f.pages[0];
        s.write_page(node, PageKind::RtreeNode, b"rewritten")
            .unwrap();
        let a = s.append_page(PageKind::RtreeNode, b"appended").unwrap();
        assert_eq!(a, before);
        let big = blob(10 * PS, 9);
        let e = s.append_extent(PageKind::Mesh, &big).unwrap();
        s.set_segment(Segment::new("rtree", a, 3, 4)).unwrap();
        s.set_segment(Segment::new("meshes", e.first_page, 0, 0))
            .unwrap();
        // Read back before any commit: pending pages and overwritten pages.
        assert_eq!(
            s.read_page(node, PageKind::RtreeNode).unwrap(),
            b"rewritten"
        );
        assert_eq!(s.read_page(a, PageKind::RtreeNode).unwrap(), b"appended");
        assert_eq!(s.read_extent(&e, PageKind::Mesh).unwrap(), big);
        s.flush().unwrap();
        // And after: the pages now lie beyond the original mapping (remapped).
        assert_eq!(s.read_page(a, PageKind::RtreeNode).unwrap(), b"appended");
        assert_eq!(s.read_extent(&e, PageKind::Mesh).unwrap(), big);
        // Overwrite a committed page after flush; seen without reopening.
        s.write_page(a, PageKind::RtreeNode, b"again").unwrap();
        assert_eq!(s.read_page(a, PageKind::RtreeNode).unwrap(), b"again");
        // Appended after the flush, then the store is finished.
        let late = s.append_page(PageKind::Meta, b"late").unwrap();
        s.finish().unwrap();

        let r = Store::open(&f.path, Backend::Mmap).unwrap();
        assert_eq!(r.page_count(), late + 1);
        assert_eq!(
            r.read_page(node, PageKind::RtreeNode).unwrap(),
            b"rewritten"
        );
        assert_eq!(r.read_page(a, PageKind::RtreeNode).unwrap(), b"again");
        assert_eq!(r.read_page(late, PageKind::Meta).unwrap(), b"late");
        assert_eq!(r.read_extent(&e, PageKind::Mesh).unwrap(), big);
        assert_eq!(
            r.header().segment("rtree"),
            Some(&Segment::new("rtree", a, 3, 4))
        );
        assert_eq!(r.header().segment("meshes").unwrap().a, e.first_page);
        // Untouched pages are intact.
        let (mesh, kind, b) = &f.pages[4];
        assert_eq!(&r.read_page(*mesh, *kind).unwrap(), b);
    }
}

#[test]
fn mmap_writer_reads_flushed_pages_beyond_its_mapping() {
    // Spill the write buffer without an explicit flush: pages written to the file
    // after the map was made are read through pread until the next remap.
    let f = build(PS);
    let mut s = Store::open_writable(&f.path, Backend::Mmap).unwrap();
    let n = writer::WRITE_BUFFER_BYTES / PS + 10;
    let first = s.page_count();
    for i in 0..n {
        s.append_page(PageKind::Meta, &(i as u32).to_le_bytes())
            .unwrap();
    }
    for i in [0, n / 2, n - 1] {
        assert_eq!(
            s.read_page(first + i as u64, PageKind::Meta).unwrap(),
            (i as u32).to_le_bytes()
        );
    }
}

#[test]
fn uncommitted_appends_are_dropped() {
    let f = build(PS);
    let before = file_len(&f.path);
    {
        let mut s = Store::open_writable(&f.path, Backend::Mmap).unwrap();
        for _ in 0..(writer::WRITE_BUFFER_BYTES / PS + 3) {
            s.append_page(PageKind::Meta, b"lost").unwrap();
        }
    }
    // The header still says the old count; the file may carry a tail.
    let s = Store::open_writable(&f.path, Backend::Pread { direct: false }).unwrap();
    assert_eq!(s.page_count() * PS as u64, before);
    drop(s);
    assert_eq!(file_len(&f.path), before);
    let s = Store::open(&f.path, Backend::Mmap).unwrap();
    check_all(&f, &s);
}

#[test]
fn segment_table_limits() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("seg.db");
    let mut s = Store::create(&path, PS).unwrap();
    let e = s
        .set_segment(Segment::new("a-name-too-long!", 0, 0, 0))
        .unwrap_err();
    assert!(
        matches!(&e, Error::Invalid(w) if w.contains("at most 15")),
        "{e}"
    );
    let max = s.header().max_segments();
    assert_eq!(max, max_segments(PS));
    for i in 0..max {
        s.set_segment(Segment::new(format!("seg{i}"), i as u64, 0, 0))
            .unwrap();
    }
    // Replacing still works when full; adding does not.
    s.set_segment(Segment::new("seg0", 99, 0, 0)).unwrap();
    let e = s.set_segment(Segment::new("extra", 0, 0, 0)).unwrap_err();
    assert!(matches!(&e, Error::Invalid(w) if w.contains("full")), "{e}");
    s.finish().unwrap();
    let s = Store::open(&path, Backend::Mmap).unwrap();
    assert_eq!(s.header().segments().len(), max);
    assert_eq!(s.header().segment("seg0").unwrap().a, 99);
    assert_eq!(
        s.header().segment(&format!("seg{}", max - 1)).unwrap().a,
        max as u64 - 1
    );
}

#[test]
fn backend_names() {
    for b in BACKENDS {
        assert_eq!(b.to_string().parse::<Backend>().unwrap(), b);
    }
    assert!("fast".parse::<Backend>().is_err());
    assert_eq!(Backend::default(), Backend::Mmap);
}

/// Sequential append throughput and warm mmap read latency. Run in release:
/// `cargo test --release --lib store::tests::throughput -- --ignored --nocapture`
/// (the file goes to the temporary directory; set TMPDIR to measure another disk).
#[test]
#[ignore]
fn throughput() {
    use std::time::Instant;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("big.db");
    let total = 200 << 20;
    let chunk = blob(64 * 1024 + 123, 5);
    let mut s = Store::create(&path, DEFAULT_PAGE_SIZE).unwrap();
    let t = Instant::now();
    let mut written = 0usize;
    let mut extents = Vec::new();
    while written < total {
        extents.push(s.append_extent(PageKind::Mesh, &chunk).unwrap());
        written += chunk.len();
    }
    let appended = t.elapsed();
    s.finish().unwrap();
    let all = t.elapsed();
    let mb = written as f64 / 1e6;
    eprintln!(
        "append {mb:.0} MB: {:.0} MB/s without fsync, {:.0} MB/s including finish (fsync + rename)",
        mb / appended.as_secs_f64(),
        mb / all.as_secs_f64()
    );

    let s = Store::open(&path, Backend::Mmap).unwrap();
    let n = s.page_count();
    let mut buf = Vec::new();
    for p in 1..n {
        s.read_page_into(p, PageKind::Mesh, &mut buf).unwrap(); // warm
    }
    let t = Instant::now();
    let rounds = 3;
    let mut x = 12345u64;
    for _ in 0..rounds * (n - 1) {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let p = 1 + (x >> 33) % (n - 1);
        s.read_page_into(p, PageKind::Mesh, &mut buf).unwrap();
    }
    let per = t.elapsed().as_nanos() as f64 / (rounds * (n - 1)) as f64;
    eprintln!("read_page_into, mmap warm, random full 4 KiB pages: {per:.0} ns/page");
    let t = Instant::now();
    let mut bytes = 0;
    for e in &extents {
        bytes += s.read_extent(e, PageKind::Mesh).unwrap().len();
    }
    eprintln!(
        "read_extent, mmap warm: {:.0} MB/s",
        bytes as f64 / 1e6 / t.elapsed().as_secs_f64()
    );
}

#[test]
fn extent_ranges_read_only_their_pages() {
    let f = build(PS);
    let s = Store::open(&f.path, Backend::Mmap).unwrap();
    let p = s.payload_size();
    for (e, b) in &f.extents {
        let n = b.len();
        let mut ranges = vec![(0, n), (0, 0), (n, 0)];
        for start in [0, 1, p - 1, p, p + 1, 2 * p + 5] {
            for len in [1, 2, p - 1, p, p + 1, 2 * p] {
                if start + len <= n {
                    ranges.push((start, len));
                }
            }
        }
        for (start, len) in ranges {
            s.reset_stats();
            let got = s.read_extent_range(e, PageKind::Mesh, start, len).unwrap();
            assert_eq!(got, &b[start..start + len], "{e:?} {start}+{len}");
            let pages = if len == 0 {
                0
            } else {
                (start + len - 1) / p - start / p + 1
            };
            assert_eq!(s.stats().page_reads, pages as u64, "{e:?} {start}+{len}");
        }
        for (start, len) in [(n, 1), (0, n + 1), (usize::MAX, 2)] {
            let err = s
                .read_extent_range(e, PageKind::Mesh, start, len)
                .unwrap_err();
            assert!(
                matches!(&err, Error::CorruptPage { what, .. } if what.contains("beyond")),
                "{err}"
            );
        }
    }
}

#[test]
fn segment_extents_are_checked_against_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("seg.db");
    let mut s = Store::create(&path, PS).unwrap();
    let ext = s.append_extent(PageKind::Meta, &blob(3 * PS, 7)).unwrap();
    let pages = ext.page_count as u64;
    let len = ext.byte_len as u64;
    for (name, a, b) in [
        ("blob", ext.first_page, len),
        ("far", ext.first_page, len * 10),
        ("header", 0, 10),
        ("empty", ext.first_page, 0),
    ] {
        s.set_segment(Segment::new(name, a, b, pages)).unwrap();
    }
    s.finish().unwrap();
    let s = Store::open(&path, Backend::Mmap).unwrap();
    let ok = |_: &Extent, _: u64| Ok(());
    let (found, c) = s.segment_extent("blob", ok).unwrap().unwrap();
    assert_eq!((found, c), (ext, pages));
    assert!(s.segment_extent("none", ok).unwrap().is_none());
    for name in ["far", "header", "empty"] {
        match s.segment_extent(name, ok) {
            Err(Error::CorruptPage { page: 0, what, .. }) => assert!(what.contains(name), "{what}"),
            other => panic!("{name}: {other:?}"),
        }
    }
    let refuse = |_: &Extent, c: u64| Err(format!("c is {c}"));
    let e = s.segment_extent("blob", refuse).unwrap_err().to_string();
    assert!(
        e.contains("\"blob\"") && e.contains(&format!("c is {pages}")),
        "{e}"
    );
}
