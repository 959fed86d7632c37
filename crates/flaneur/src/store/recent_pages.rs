//! The last mesh and LOD pages a reader took, kept so that a page that several packed
//! extents share (format version 2 packs small extents several to a page) is read once
//! while its neighbours are wanted, not once for each of them. Off until asked for
//! (`Store::keep_recent_pages`), so that a one-off read costs what its layout costs.
//!
//! A page that comes from here is not read: it is not counted, which is the point.

use std::sync::Mutex;

use lru::LruCache;

use super::PageKind;

/// Verified payloads by page, least recently used out first.
#[derive(Default)]
pub(super) struct RecentPages {
    pages: Mutex<Option<LruCache<u64, (PageKind, Box<[u8]>)>>>,
}

fn kept(kind: PageKind) -> bool {
    matches!(kind, PageKind::Mesh | PageKind::Lod)
}

impl RecentPages {
    /// Keeps the last `count` pages from now on (0: none), forgetting what it held.
    pub(super) fn keep(&self, count: usize) {
        if let Ok(mut pages) = self.pages.lock() {
            *pages = std::num::NonZeroUsize::new(count).map(LruCache::new);
        }
    }

    /// Appends page `page`'s payload to `out` if it is kept as `kind`; its length.
    pub(super) fn append(&self, page: u64, kind: PageKind, out: &mut Vec<u8>) -> Option<usize> {
        if !kept(kind) {
            return None;
        }
        let mut pages = self.pages.lock().ok()?;
        // A page kept as another kind is read again, for the read to name the mismatch.
        let (stored, payload) = pages.as_mut()?.get(&page)?;
        (*stored == kind).then(|| {
            out.extend_from_slice(payload);
            payload.len()
        })
    }

    /// Keeps page `page`'s verified payload, of `kind`.
    pub(super) fn put(&self, page: u64, kind: PageKind, payload: &[u8]) {
        if !kept(kind) {
            return;
        }
        if let Ok(mut pages) = self.pages.lock() {
            if let Some(pages) = pages.as_mut() {
                pages.put(page, (kind, payload.into()));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::store::{PageKind, Store};

    /// Two small extents packed on one page, and the store that holds them.
    fn packed_pair(dir: &std::path::Path) -> (Store, [crate::store::Extent; 2]) {
        let path = dir.join("packed.db");
        let mut store = Store::create(&path, 4096).unwrap();
        let a = store
            .append_packed_or_whole(PageKind::Mesh, &[1; 700], true)
            .unwrap();
        let b = store
            .append_packed_or_whole(PageKind::Mesh, &[2; 900], true)
            .unwrap();
        store.finish().unwrap();
        assert_eq!(a.first_page, b.first_page, "{a:?} {b:?}");
        (Store::open(&path, Default::default()).unwrap(), [a, b])
    }

    #[test]
    fn a_shared_page_is_read_once_while_kept() {
        let dir = tempfile::tempdir().unwrap();
        let (store, [a, b]) = packed_pair(dir.path());
        let read_both = |store: &Store| {
            store.reset_stats();
            assert_eq!(store.read_extent(&a, PageKind::Mesh).unwrap(), vec![1; 700]);
            assert_eq!(store.read_extent(&b, PageKind::Mesh).unwrap(), vec![2; 900]);
            store.stats().page_reads
        };
        assert_eq!(read_both(&store), 2);
        store.keep_recent_pages(8);
        assert_eq!(read_both(&store), 1);
        // Still kept from the last round: nothing is read.
        assert_eq!(read_both(&store), 0);
        store.keep_recent_pages(0);
        assert_eq!(read_both(&store), 2);
    }

    #[test]
    fn a_kept_page_asked_for_as_another_kind_is_read_and_refused() {
        let dir = tempfile::tempdir().unwrap();
        let (store, [a, _]) = packed_pair(dir.path());
        store.keep_recent_pages(8);
        store.read_extent(&a, PageKind::Mesh).unwrap();
        let err = store
            .read_extent(&a, PageKind::Lod)
            .unwrap_err()
            .to_string();
        assert!(err.contains("kind"), "{err}");
    }
}
