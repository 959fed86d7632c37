//! The client's page cache: whole raw pages by page id, bounded in bytes, least
//! recently used out first. One cache holds every kind of page (index nodes, meshes,
//! LOD levels, visibility records), so the bound is the client's whole memory for them.

use std::num::NonZeroUsize;
use std::sync::Mutex;

use lru::LruCache;

/// The fewest pages the cache holds, whatever its byte bound: two of the store's read
/// chunks, so a chunk fetched ahead is still there when it is read.
pub(crate) const MIN_PAGES: usize = 2 * super::source::CHUNK_PAGES as usize;

pub(crate) struct PageCache {
    pages: Mutex<LruCache<u64, Box<[u8]>>>,
}

impl PageCache {
    /// A cache of at most `bytes` bytes of `page_size`-byte pages (at least [`MIN_PAGES`]).
    pub(crate) fn new(bytes: usize, page_size: usize) -> PageCache {
        let pages = (bytes / page_size.max(1)).max(MIN_PAGES);
        PageCache {
            pages: Mutex::new(LruCache::new(
                NonZeroUsize::new(pages).unwrap_or(NonZeroUsize::MIN),
            )),
        }
    }

    /// Copies page `page` into `buf` if it is held.
    pub(crate) fn copy_out(&self, page: u64, buf: &mut [u8]) -> bool {
        let mut pages = self.lock();
        match pages.get(&page) {
            Some(bytes) if bytes.len() == buf.len() => {
                buf.copy_from_slice(bytes);
                true
            }
            _ => false,
        }
    }

    /// Whether page `page` is held (without touching its recency).
    pub(crate) fn holds(&self, page: u64) -> bool {
        self.lock().contains(&page)
    }

    /// Keeps `bytes` as page `page`.
    pub(crate) fn insert(&self, page: u64, bytes: &[u8]) {
        self.lock().put(page, bytes.into());
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, LruCache<u64, Box<[u8]>>> {
        // A panic elsewhere while holding the lock leaves whole pages behind: still usable.
        self.pages.lock().unwrap_or_else(|p| p.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holds_at_most_its_bound_and_evicts_the_least_recent() {
        let cache = PageCache::new(MIN_PAGES * 8, 8);
        for p in 0..MIN_PAGES as u64 {
            cache.insert(p, &[p as u8; 8]);
        }
        let mut buf = [0u8; 8];
        assert!(cache.copy_out(0, &mut buf));
        assert_eq!(buf, [0; 8]);
        cache.insert(MIN_PAGES as u64, &[1; 8]);
        assert!(cache.holds(0), "page 0 was used last of the old ones");
        assert!(!cache.holds(1), "page 1 was the least recently used");
        assert!(!cache.copy_out(1, &mut buf));
    }

    #[test]
    fn a_tiny_bound_still_holds_two_chunks() {
        let cache = PageCache::new(1, 4096);
        for p in 0..MIN_PAGES as u64 {
            cache.insert(p, &[0; 4096]);
        }
        assert!((0..MIN_PAGES as u64).all(|p| cache.holds(p)));
    }
}
