//! Packed extents on real files: blobs of two kinds interleaved, runs over pages, the
//! fallback to whole extents, reads whole and by range with their pages counted, and
//! corrupt packed extents.

use super::tests::{set_len, PS};
use super::*;

fn blob(len: usize, seed: u32) -> Vec<u8> {
    (0..len)
        .map(|i| (i as u32).wrapping_mul(131).wrapping_add(seed * 7) as u8)
        .collect()
}

/// The pages a read of bytes `start..start + len` of `e` touches.
fn pages_touched(e: &Extent, start: usize, len: usize, p: usize) -> u64 {
    if len == 0 {
        return 0;
    }
    let from = e.offset as usize + start;
    ((from + len - 1) / p - from / p + 1) as u64
}

/// Reads every blob whole and by a few ranges, counting pages exactly.
fn read_back(s: &Store, blobs: &[(PageKind, Extent, Vec<u8>)]) {
    let p = s.payload_size();
    for (kind, e, b) in blobs {
        s.reset_stats();
        assert_eq!(&s.read_extent(e, *kind).unwrap(), b, "{e:?}");
        assert_eq!(s.stats().page_reads, u64::from(e.page_count), "{e:?}");
        assert_eq!(s.stats().reads_of(*kind), u64::from(e.page_count));
        let n = b.len();
        for (start, len) in [
            (0, 1),
            (n - 1, 1),
            (n / 2, n - n / 2),
            (1, n.saturating_sub(2)),
        ] {
            if start + len > n {
                continue;
            }
            s.reset_stats();
            let got = s.read_extent_range(e, *kind, start, len).unwrap();
            assert_eq!(got, &b[start..start + len], "{e:?} {start}+{len}");
            assert_eq!(
                s.stats().page_reads,
                pages_touched(e, start, len, p),
                "{e:?} {start}+{len}"
            );
        }
    }
}

#[test]
fn small_blobs_of_two_kinds_interleaved() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.db");
    let mut s = Store::create(&path, PS).unwrap();
    let p = s.payload_size();
    let mut blobs = Vec::new();
    let mut bytes = [0usize; 2];
    for i in 0..400u32 {
        // Mostly small, now and then over a page, so runs happen in both kinds.
        let (kind, k) = if i % 3 == 0 {
            (PageKind::Lod, 1)
        } else {
            (PageKind::Mesh, 0)
        };
        let len = match i % 17 {
            0 => p + 40 + i as usize,
            5 => 3 * p - 1,
            _ => 1 + (i as usize * 37) % 300,
        };
        let b = blob(len, i);
        let e = s.append_packed(kind, &b).unwrap();
        assert!(e.packed && e.offset < p as u32, "{e:?}");
        assert_eq!(
            e.page_count as usize,
            Extent::pages_spanned(e.offset as usize, len, p)
        );
        bytes[k] += len;
        blobs.push((kind, e, b));
    }
    // Every page is counted once, by its kind, and packing fills them well.
    let (mesh, lod) = (
        s.pages_written(PageKind::Mesh),
        s.pages_written(PageKind::Lod),
    );
    assert_eq!(mesh + lod + 1, s.page_count());
    assert!(mesh < bytes[0].div_ceil(p) as u64 * 3 / 2, "{mesh} pages");
    assert!(lod < bytes[1].div_ceil(p) as u64 * 3 / 2, "{lod} pages");
    assert!(mesh + lod < 400, "{mesh} + {lod} pages for 400 blobs");
    // No two blobs overlap: every byte of every page has at most one owner.
    let mut owned = vec![false; s.page_count() as usize * p];
    for (_, e, b) in &blobs {
        let at = e.first_page as usize * p + e.offset as usize;
        for o in &mut owned[at..at + b.len()] {
            assert!(!*o, "{e:?} overlaps another blob");
            *o = true;
        }
    }
    // Readable while the build goes on (the open pages rewritten in the buffer)...
    read_back(&s, &blobs);
    s.finish().unwrap();
    // ...and after reopening, on every backend.
    for backend in [Backend::Mmap, Backend::Pread { direct: false }] {
        let s = Store::open(&path, backend).unwrap();
        read_back(&s, &blobs);
    }
}

#[test]
fn runs_exact_fills_and_fresh_pages() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = Store::create(&dir.path().join("p.db"), PS).unwrap();
    let p = s.payload_size();
    let m = PageKind::Mesh;
    let mut blobs = Vec::new();
    fn put(
        s: &mut Store,
        blobs: &mut Vec<(PageKind, Extent, Vec<u8>)>,
        kind: PageKind,
        len: usize,
    ) -> Extent {
        let b = blob(len, blobs.len() as u32);
        let e = s.append_packed(kind, &b).unwrap();
        blobs.push((kind, e, b));
        e
    }
    let ext = |first_page, page_count, byte_len: usize, offset| Extent {
        first_page,
        page_count,
        byte_len: byte_len as u32,
        offset,
        packed: true,
    };
    assert_eq!(put(&mut s, &mut blobs, m, 100), ext(1, 1, 100, 0));
    // The open page is the file's last: a blob longer than its room runs on from it.
    assert_eq!(put(&mut s, &mut blobs, m, 3 * p), ext(1, 4, 3 * p, 100));
    assert_eq!(s.page_count(), 5);
    // Exactly the rest of the open page (page 4 holds 100 bytes): no new page.
    assert_eq!(put(&mut s, &mut blobs, m, p - 100), ext(4, 1, p - 100, 100));
    assert_eq!(s.page_count(), 5);
    // The full page is closed: the next blob starts a fresh one.
    assert_eq!(put(&mut s, &mut blobs, m, 10), ext(5, 1, 10, 0));
    // Another kind's page follows: mesh's open page (5) is no longer last, so a blob
    // too long for its room starts a fresh page, and page 5 stays open for one that fits.
    assert_eq!(put(&mut s, &mut blobs, PageKind::Lod, 20), ext(6, 1, 20, 0));
    assert_eq!(put(&mut s, &mut blobs, m, p), ext(7, 1, p, 0));
    assert_eq!(put(&mut s, &mut blobs, m, p - 10), ext(5, 1, p - 10, 10));
    assert_eq!(put(&mut s, &mut blobs, m, 30), ext(8, 1, 30, 0));
    assert_eq!(put(&mut s, &mut blobs, PageKind::Lod, 5), ext(6, 1, 5, 20));
    // A blob of exactly one page from a fresh start, and an empty blob (no pages).
    let e = s.append_packed(m, &[]).unwrap();
    assert_eq!(
        e,
        Extent {
            first_page: 9,
            ..Extent::default()
        }
    );
    assert_eq!(s.read_extent(&e, m).unwrap(), b"");
    assert_eq!(s.pages_written(m), 7);
    assert_eq!(s.pages_written(PageKind::Lod), 1);
    read_back(&s, &blobs);
    // A commit closes the open pages: packing never rewrites a committed page.
    s.flush().unwrap();
    assert_eq!(put(&mut s, &mut blobs, m, 10), ext(9, 1, 10, 0));
    read_back(&s, &blobs);
}

#[test]
fn a_writable_store_starts_with_no_open_page() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.db");
    let mut s = Store::create(&path, PS).unwrap();
    let a = s.append_packed(PageKind::Mesh, &blob(100, 1)).unwrap();
    s.append_page(PageKind::Meta, b"meta").unwrap();
    s.append_extent(PageKind::Mesh, &blob(10, 2)).unwrap();
    assert_eq!(s.pages_written(PageKind::Meta), 1);
    assert_eq!(s.pages_written(PageKind::Mesh), 2);
    s.finish().unwrap();
    let mut s = Store::open_writable(&path, Backend::Mmap).unwrap();
    assert_eq!(s.pages_written(PageKind::Mesh), 0);
    let b = s.append_packed(PageKind::Mesh, &blob(100, 3)).unwrap();
    assert_eq!((b.first_page, b.offset), (4, 0));
    s.finish().unwrap();
    let s = Store::open(&path, Backend::Mmap).unwrap();
    assert_eq!(s.read_extent(&a, PageKind::Mesh).unwrap(), blob(100, 1));
    assert_eq!(s.read_extent(&b, PageKind::Mesh).unwrap(), blob(100, 3));
}

#[test]
fn a_blob_over_the_packed_page_count_is_stored_whole() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = Store::create(&dir.path().join("p.db"), PS).unwrap();
    let p = s.payload_size();
    let most = Extent::MAX_PACKED_PAGES as usize;
    s.append_packed(PageKind::Mesh, &[1; 10]).unwrap();
    // From the open page it would span one page too many; from a fresh one it fits.
    let e = s.append_packed(PageKind::Mesh, &vec![2; most * p]).unwrap();
    assert_eq!((e.first_page, e.offset, e.packed), (2, 0, true));
    assert_eq!(e.page_count as usize, most);
    let big = blob(most * p + 1, 9);
    let before = s.page_count();
    let e = s.append_packed(PageKind::Mesh, &big).unwrap();
    assert_eq!(
        e,
        Extent {
            first_page: before,
            page_count: most as u32 + 1,
            byte_len: big.len() as u32,
            offset: 0,
            packed: false
        }
    );
    assert_eq!(
        s.read_extent_range(&e, PageKind::Mesh, big.len() - 5, 5)
            .unwrap(),
        &big[big.len() - 5..]
    );
    // The whole extent left the open page (page 1, 10 bytes) as it was.
    let e = s.append_packed(PageKind::Mesh, &[3; 5]).unwrap();
    assert_eq!((e.first_page, e.offset), (1, 10));
}

#[test]
fn corrupt_packed_extents_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.db");
    let mut s = Store::create(&path, PS).unwrap();
    let p = s.payload_size();
    let m = PageKind::Mesh;
    s.append_packed(m, &blob(300, 1)).unwrap();
    let e = s.append_packed(m, &blob(2 * p, 2)).unwrap(); // pages 1..=3, offset 300
    assert_eq!((e.first_page, e.page_count, e.offset), (1, 3, 300));
    s.finish().unwrap();
    let corrupt = |s: &Store, bad: &Extent, says: &str| {
        let err = s.read_extent(bad, m).unwrap_err();
        assert!(
            matches!(&err, Error::CorruptPage { what, .. } if what.contains(says)),
            "{bad:?}: {err}"
        );
    };
    let s = Store::open(&path, Backend::Mmap).unwrap();
    assert_eq!(s.read_extent(&e, m).unwrap(), blob(2 * p, 2));
    corrupt(
        &s,
        &Extent {
            offset: p as u32,
            ..e
        },
        "past the",
    );
    corrupt(
        &s,
        &Extent {
            offset: Extent::MAX_PACKED_OFFSET,
            ..e
        },
        "past the",
    );
    corrupt(&s, &Extent { page_count: 4, ..e }, "needs 3 pages");
    corrupt(&s, &Extent { page_count: 2, ..e }, "needs 3 pages");
    corrupt(
        &s,
        &Extent {
            byte_len: 0,
            page_count: 0,
            ..e
        },
        "0 bytes",
    );
    corrupt(&s, &Extent { first_page: 0, ..e }, "page 0");
    corrupt(&s, &Extent { first_page: 2, ..e }, "beyond the end");
    // A whole extent with an offset cannot come from a file; one built in memory is
    // still refused.
    corrupt(
        &s,
        &Extent {
            packed: false,
            page_count: 3,
            ..e
        },
        "starts at byte 300",
    );
    // The blob's last page holds less than its end: 300 + 2p bytes end 300 bytes into
    // page 3, which the later 300-byte shift of the offset makes short.
    corrupt(&s, &Extent { offset: 700, ..e }, "expected at least");
    drop(s);
    // A last page cut short on disk (its payload length rewritten, checksum resealed).
    let mut w = Store::open_writable(&path, Backend::Mmap).unwrap();
    w.write_page(3, m, &blob(200, 5)).unwrap();
    w.finish().unwrap();
    let s = Store::open(&path, Backend::Mmap).unwrap();
    corrupt(&s, &e, "expected at least 300");
    // A middle page cut short.
    drop(s);
    let mut w = Store::open_writable(&path, Backend::Mmap).unwrap();
    w.write_page(2, m, &blob(p - 1, 5)).unwrap();
    w.finish().unwrap();
    let s = Store::open(&path, Backend::Pread { direct: false }).unwrap();
    let err = s.read_extent_range(&e, m, p, 10).unwrap_err();
    assert!(
        matches!(&err, Error::CorruptPage { page: 2, what, .. } if what.contains(&format!("expected {p}"))),
        "{err}"
    );
    // A truncated file: the run's last page is gone.
    drop(s);
    set_len(&path, 3 * PS as u64);
    assert!(Store::open(&path, Backend::Mmap).is_err());
}
