//! The store's writes under concurrency and interruption: builds to one path that
//! never share a temporary, stale temporaries, the one-writer lock, the tail an
//! interrupted writer leaves, and a file shrunk under a `pread` reader.

use std::os::unix::fs::PermissionsExt;

use super::tests::{build, check_all, file_len, set_len, PS};
use super::*;

fn mode(path: &Path) -> u32 {
    std::fs::metadata(path).unwrap().permissions().mode() & 0o777
}

#[test]
fn two_stores_created_for_one_path_never_share_a_temporary() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("city.db");
    let mut first = Store::create(&path, PS).unwrap();
    let mut second = Store::create(&path, PS).unwrap();
    first.append_page(PageKind::Meta, b"first").unwrap();
    second.append_page(PageKind::Meta, b"second").unwrap();
    first.finish().unwrap();
    // The second keeps writing after the first has published its file.
    for _ in 0..(writer::WRITE_BUFFER_BYTES / PS + 2) {
        second.append_page(PageKind::Mesh, b"more").unwrap();
    }
    let published = std::fs::read(&path).unwrap();
    let s = Store::open(&path, Backend::Mmap).unwrap();
    assert_eq!(
        s.page_count(),
        2,
        "the first's file, untouched by the second"
    );
    assert_eq!(s.read_page(1, PageKind::Meta).unwrap(), b"first");
    drop(s);
    assert_eq!(std::fs::read(&path).unwrap(), published);

    second.finish().unwrap();
    let s = Store::open(&path, Backend::Pread { direct: false }).unwrap();
    assert_eq!(s.read_page(1, PageKind::Meta).unwrap(), b"second");
    assert_eq!(
        s.page_count(),
        2 + (writer::WRITE_BUFFER_BYTES / PS + 2) as u64,
        "the last rename wins, with the whole file"
    );
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn a_stale_temporary_is_ignored_with_its_mode() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("city.db");
    // What a build killed under the old naming left: read-only, garbage.
    let stale = dir.path().join("city.db.tmp");
    std::fs::write(&stale, b"half a database").unwrap();
    std::fs::set_permissions(&stale, std::fs::Permissions::from_mode(0o444)).unwrap();
    let plain = dir.path().join("plain");
    std::fs::File::create(&plain).unwrap();

    let mut s = Store::create(&path, PS).unwrap();
    s.append_page(PageKind::Meta, b"new").unwrap();
    s.finish().unwrap();
    assert_eq!(
        mode(&path),
        mode(&plain),
        "a new database gets File::create's mode"
    );
    assert_eq!(std::fs::read(&stale).unwrap(), b"half a database");
    assert_eq!(mode(&stale), 0o444);
    Store::open_writable(&path, Backend::Mmap).unwrap();
}

#[test]
fn a_database_has_one_writer_at_a_time() {
    let f = build(PS);
    let first = Store::open_writable(&f.path, Backend::Mmap).unwrap();
    let e = Store::open_writable(&f.path, Backend::Pread { direct: false }).unwrap_err();
    assert!(
        e.to_string()
            .contains("another writer has the database open"),
        "{e}"
    );
    // Readers do not wait for the writer.
    check_all(&f, &Store::open(&f.path, Backend::Mmap).unwrap());
    drop(first);
    Store::open_writable(&f.path, Backend::Mmap).unwrap();
}

#[test]
fn a_tail_past_the_committed_pages_is_counted_and_cut_by_the_next_writer() {
    let f = build(PS);
    let len = file_len(&f.path);
    // A whole zero page appended, as an interrupted writer leaves after growing the file.
    set_len(&f.path, len + PS as u64);
    for backend in [Backend::Mmap, Backend::Pread { direct: false }] {
        let s = Store::open(&f.path, backend).unwrap();
        assert_eq!(s.uncommitted_bytes(), PS as u64);
        check_all(&f, &s);
        let beyond = s.page_count();
        assert!(s.read_page(beyond, PageKind::Meta).is_err());
    }
    drop(Store::open_writable(&f.path, Backend::Mmap).unwrap());
    assert_eq!(file_len(&f.path), len);
    assert_eq!(
        Store::open(&f.path, Backend::Mmap)
            .unwrap()
            .uncommitted_bytes(),
        0
    );
}

#[test]
fn a_writer_grows_its_file_by_whole_pages() {
    let f = build(PS);
    let mut s = Store::open_writable(&f.path, Backend::Mmap).unwrap();
    for _ in 0..(writer::WRITE_BUFFER_BYTES / PS + 5) {
        s.append_page(PageKind::Mesh, b"x").unwrap();
        assert_eq!(file_len(&f.path) % PS as u64, 0);
    }
}

#[test]
fn a_file_shrunk_under_a_pread_reader_is_an_error_naming_the_page() {
    let f = build(PS);
    let s = Store::open(&f.path, Backend::Pread { direct: false }).unwrap();
    let (e, b) = f.extents.last().unwrap();
    set_len(&f.path, e.first_page * PS as u64);
    let err = s.read_extent(e, PageKind::Mesh).unwrap_err();
    assert!(
        matches!(&err, Error::Truncated { what, .. }
            if what.contains(&format!("page {}", e.first_page))),
        "{err}"
    );
    assert!(!b.is_empty());
}
