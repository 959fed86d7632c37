//! The client's page cache: whole raw pages by page id, bounded in pages, least
//! recently used out first. One cache holds every kind of page (index nodes, meshes,
//! LOD levels, visibility records), so the bound is the client's whole memory for them.
//!
//! The bound is set once, at the open ([`bound`]): the bytes asked for, but never more
//! than the file's own pages (a cache larger than the file holds nothing more) nor more
//! than the memory available then (`MemAvailable`, where /proc/meminfo can be read).
//! Nothing is reserved for it: the cache's map grows as pages come, so a generous bound
//! costs what the pages held cost, never what the bound names (a map sized from the
//! bound took 536 MB at once for `--cache-mb 1000000` on a 25 MB file).

use std::sync::Mutex;

use lru::LruCache;

use crate::store::extent_reads::CHUNK_PAGES;

/// The fewest pages the cache holds, whatever its byte bound: two of the store's read
/// chunks, so a chunk fetched ahead is still there when it is read.
pub(crate) const MIN_PAGES: usize = 2 * CHUNK_PAGES as usize;

/// The page cache's bound in effect.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Bound {
    /// The most pages held.
    pub(crate) pages: usize,
    /// Whether the memory available, not the bound asked for nor the file's size, set it.
    pub(crate) by_memory: bool,
}

/// The bound for `asked` bytes of `page_size`-byte pages of a file of `file_len` bytes,
/// `available` bytes of memory being free (`None`: unknown, no cap for memory). At least
/// [`MIN_PAGES`] unless the file has fewer pages.
pub(crate) fn bound(
    asked: usize,
    file_len: u64,
    page_size: usize,
    available: Option<u64>,
) -> Bound {
    let page_size = page_size.max(1) as u64;
    let file_pages = file_len.div_ceil(page_size).max(1);
    let mut pages = (asked as u64 / page_size).min(file_pages);
    let mut by_memory = false;
    if let Some(free) = available {
        let fit = free / page_size;
        if pages > fit {
            pages = fit;
            by_memory = true;
        }
    }
    let pages = pages.max(MIN_PAGES as u64).min(file_pages);
    Bound {
        pages: usize::try_from(pages).unwrap_or(usize::MAX),
        by_memory,
    }
}

pub(crate) struct PageCache {
    pages: Mutex<LruCache<u64, Box<[u8]>>>,
    max_pages: usize,
}

impl PageCache {
    /// An empty cache of at most `max_pages` pages (at least one).
    pub(crate) fn new(max_pages: usize) -> PageCache {
        PageCache {
            // Unbounded to the lru crate, which would size its map from a bound; the
            // bound is kept here instead, the map growing with the pages held.
            pages: Mutex::new(LruCache::unbounded()),
            max_pages: max_pages.max(1),
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

    /// Keeps `bytes` as page `page`, the least recently used page out if the cache is full.
    pub(crate) fn insert(&self, page: u64, bytes: &[u8]) {
        let mut pages = self.lock();
        if !pages.contains(&page) && pages.len() >= self.max_pages {
            pages.pop_lru();
        }
        pages.put(page, bytes.into());
    }

    /// Pages held now.
    #[cfg(test)]
    fn len(&self) -> usize {
        self.lock().len()
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
        let cache = PageCache::new(MIN_PAGES);
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
        assert_eq!(cache.len(), MIN_PAGES);
        // A page kept again is replaced, not counted twice.
        cache.insert(0, &[2; 8]);
        assert_eq!(cache.len(), MIN_PAGES);
    }

    #[test]
    fn a_tiny_bound_still_holds_two_chunks() {
        let b = bound(1, 1 << 30, 4096, None);
        assert_eq!(b.pages, MIN_PAGES);
        let cache = PageCache::new(b.pages);
        for p in 0..MIN_PAGES as u64 {
            cache.insert(p, &[0; 4096]);
        }
        assert!((0..MIN_PAGES as u64).all(|p| cache.holds(p)));
    }

    #[test]
    fn the_bound_is_capped_at_the_file_and_at_the_memory_available() {
        let mib = 1usize << 20;
        // --cache-mb 1000000 on a 25 MB file of 4 KiB pages: the file's pages.
        let b = bound(1_000_000 * mib, 25 << 20, 4096, None);
        assert_eq!(
            b,
            Bound {
                pages: 6400,
                by_memory: false
            }
        );
        // --cache-mb 4294967296: the same; no overflow on the way.
        assert_eq!(
            bound(4_294_967_296usize.saturating_mul(mib), 25 << 20, 4096, None),
            b
        );
        assert_eq!(bound(usize::MAX, 25 << 20, 4096, Some(1 << 40)), b);
        // A file larger than memory: the memory available sets it.
        let b = bound(1 << 40, 1 << 40, 4096, Some(1 << 30));
        assert_eq!(
            b,
            Bound {
                pages: (1 << 30) / 4096,
                by_memory: true
            }
        );
        // Asked below both: as asked.
        let b = bound(64 * mib, 1 << 40, 4096, Some(1 << 30));
        assert_eq!(
            b,
            Bound {
                pages: 64 * 256,
                by_memory: false
            }
        );
        // A file of fewer pages than the floor: no more than its pages.
        assert_eq!(bound(1, 3 * 4096 + 1, 4096, None).pages, 4);
    }

    #[test]
    fn a_huge_bound_reserves_nothing_up_front() {
        // Sized from the bound, the map for 2^40 pages would abort on a 37 TB
        // allocation here; kept lazily, it holds what was put.
        let cache = PageCache::new(1 << 40);
        for p in 0..10 {
            cache.insert(p, &[p as u8; 16]);
        }
        assert_eq!(cache.len(), 10);
    }
}
