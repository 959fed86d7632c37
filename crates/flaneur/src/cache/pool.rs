//! The buffer pool: an index cache of verified page payloads over the store — the
//! "index cache" of Shou 2002 §4.2.4 and §4.4 (1 MB of 4 KiB nodes in the thesis's
//! runs), and the node cache of §5.7.
//!
//! The pool holds `budget / page_size` frames, charged a whole page each however short
//! the payload, so the resident bytes never exceed the budget. A miss reads the page
//! through [`Store::read_page_into`] (one counted physical read), then asks the policy
//! for victims until a frame is free, and admits the page. A hit copies the cached
//! payload out. Departures from the thesis:
//! - room is made before the new page is admitted, so the page just loaded is never
//!   its own victim; when the policy has nothing evictable (DPLRU pins the root) the
//!   page is served without being cached;
//! - the store is read outside the pool's lock, so a prefetch thread and the walk
//!   can share one pool; a failed read changes nothing (no count, no entry). Two
//!   threads missing the same page at once both read it and both count a miss.
//!
//! The bookkeeping (`Frames`, `frames.rs`) is shared with
//! [`Trace::replay`](super::Trace::replay), which runs it without bytes, so a replay of
//! a recorded single-threaded access sequence reproduces the live pool's counts exactly.

use std::path::Path;
use std::sync::{Mutex, MutexGuard, PoisonError};

use super::frames::Frames;
use super::policy::{Hint, Policy};
use super::stats::CacheStats;
use super::trace::{Access, Trace, TracedLookahead};
use super::Lookahead;
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::store::{NodeHint, PageKind, PageSource, Store};

/// One cached page: its verified payload and the kind it was verified as.
struct Frame {
    kind: PageKind,
    bytes: Vec<u8>,
}

struct Inner {
    frames: Frames<Frame>,
    trace: Option<Trace>,
}

impl Inner {
    fn record(&mut self, page: u64, hint: &Hint) {
        if let Some(t) = &mut self.trace {
            t.accesses.push(Access {
                page,
                hint: *hint,
                query: self.frames.query(),
                search: self.frames.searches(),
            });
        }
    }
}

/// An index cache over a [`Store`], with a replacement [`Policy`]. Methods take
/// `&self`; one pool may serve several threads.
///
/// ```
/// use flaneur::cache::{BufferPool, Hint, Lru};
/// use flaneur::store::{Backend, PageKind, Store};
/// # fn main() -> flaneur::Result<()> {
/// let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("pages.db");
/// let mut store = Store::create(&path, 1024)?;
/// let pages: Vec<u64> = (0..4).map(|i| store.append_page(PageKind::RtreeNode, &[i; 10])).collect::<Result<_, _>>()?;
/// store.finish()?;
/// let store = Store::open(&path, Backend::Mmap)?;
///
/// let pool = BufferPool::new(&store, 2 * 1024, Box::new(Lru::default()))?; // two pages
/// let mut buf = Vec::new();
/// for p in [pages[0], pages[1], pages[0], pages[2], pages[1]] {
///     pool.get(p, PageKind::RtreeNode, &Hint::UNKNOWN, &mut buf)?;
/// }
/// assert_eq!(buf, [1; 10]);
/// let s = pool.stats();
/// assert_eq!((s.hits, s.misses, s.evictions), (1, 4, 2));
/// assert_eq!(store.stats().page_reads, s.misses);
/// assert!(pool.resident_bytes() <= pool.budget_bytes());
/// # Ok(()) }
/// ```
pub struct BufferPool<'s> {
    store: &'s Store,
    budget: usize,
    capacity: usize,
    inner: Mutex<Inner>,
}

impl std::fmt::Debug for BufferPool<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BufferPool")
            .field("store", &self.store.path())
            .field("budget", &self.budget)
            .field("capacity", &self.capacity)
            .field("policy", &self.policy_name())
            .field("stats", &self.stats())
            .finish()
    }
}

impl<'s> BufferPool<'s> {
    /// A pool of `budget_bytes / page_size` pages over `store`; a budget smaller than
    /// one page is an error.
    pub fn new(
        store: &'s Store,
        budget_bytes: usize,
        policy: Box<dyn Policy>,
    ) -> Result<BufferPool<'s>> {
        let page_size = store.page_size();
        let capacity = budget_bytes / page_size;
        if capacity == 0 {
            return Err(Error::Invalid(format!(
                "cache budget of {budget_bytes} bytes is smaller than one {page_size}-byte page of {}",
                store.path().display()
            )));
        }
        let inner = Inner {
            frames: Frames::new(policy, capacity),
            trace: None,
        };
        Ok(BufferPool {
            store,
            budget: budget_bytes,
            capacity,
            inner: Mutex::new(inner),
        })
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        // A panic elsewhere cannot leave the frames half-changed: every change is
        // made under the lock by code that does not panic.
        self.inner.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Reads `page` of `kind` into `buf`: from the cache on a hit, from the store
    /// (verified, counted) on a miss, which is then cached.
    pub fn get(&self, page: u64, kind: PageKind, hint: &Hint, buf: &mut Vec<u8>) -> Result<()> {
        {
            let mut g = self.lock();
            match g.frames.peek(page) {
                Some(f) if f.kind == kind => {
                    buf.clear();
                    buf.extend_from_slice(&f.bytes);
                    g.frames.hit(page, hint);
                    g.record(page, hint);
                    return Ok(());
                }
                // Cached as another kind: the store reports the mismatch.
                Some(_) => {
                    drop(g);
                    return self.store.read_page_into(page, kind, buf);
                }
                None => {}
            }
        }
        self.store.read_page_into(page, kind, buf)?;
        let mut g = self.lock();
        g.frames.install(page, hint, |spare| {
            let mut f = spare.unwrap_or(Frame {
                kind,
                bytes: Vec::new(),
            });
            f.kind = kind;
            f.bytes.clear();
            f.bytes.extend_from_slice(buf);
            f
        });
        g.record(page, hint);
        Ok(())
    }

    /// The counts since the pool was made or last reset.
    pub fn stats(&self) -> CacheStats {
        self.lock().frames.stats()
    }

    /// Sets the counts of [`BufferPool::stats`] back to zero.
    pub fn reset_stats(&self) {
        self.lock().frames.reset_stats();
    }

    /// Drops every cached page (the counts stay).
    pub fn clear(&self) {
        self.lock().frames.clear();
    }

    /// Gives the policy the walk's prediction of its next searches (see
    /// [`Policy::look_ahead`](crate::cache::Policy::look_ahead)); a trace records it
    /// where it came among the accesses, so that a replay gives it at the same point.
    pub fn look_ahead(&self, ahead: &Lookahead) {
        let mut g = self.lock();
        g.frames.look_ahead(ahead);
        let search = g.frames.searches();
        if let Some(t) = &mut g.trace {
            t.lookaheads.push(TracedLookahead {
                at: t.accesses.len(),
                search,
                ahead: ahead.clone(),
            });
        }
    }

    /// Starts (discarding any earlier record) or stops recording accesses and
    /// lookaheads.
    pub fn set_trace(&self, on: bool) {
        self.lock().trace = on.then(Trace::default);
    }

    /// The accesses and lookaheads recorded since the trace was turned on or last
    /// taken; recording goes on if it was on.
    pub fn take_trace(&self) -> Trace {
        let mut g = self.lock();
        g.trace.as_mut().map(std::mem::take).unwrap_or_default()
    }

    /// The byte budget the pool was made with.
    pub fn budget_bytes(&self) -> usize {
        self.budget
    }

    /// Pages the pool can hold.
    pub fn capacity_pages(&self) -> usize {
        self.capacity
    }

    /// Cached pages × page size: never more than the budget.
    pub fn resident_bytes(&self) -> usize {
        self.lock().frames.len() * self.store.page_size()
    }

    /// The replacement policy's name, as [`Policy::name`](crate::cache::Policy::name) gives it.
    pub fn policy_name(&self) -> String {
        self.lock().frames.policy_name()
    }

    /// The store the pool reads missed pages from.
    pub fn store(&self) -> &'s Store {
        self.store
    }
}

impl PageSource for BufferPool<'_> {
    fn read_node(&self, page: u64, hint: &NodeHint, buf: &mut Vec<u8>) -> Result<()> {
        self.get(page, PageKind::RtreeNode, &Hint::node(hint), buf)
    }

    fn path(&self) -> &Path {
        self.store.path()
    }

    fn will_read(&self, pages: &[u64]) {
        self.store.announce(pages);
    }

    fn peek_node(&self, page: u64, buf: &mut Vec<u8>) -> bool {
        self.store.peek_page_into(page, PageKind::RtreeNode, buf)
    }

    /// DIST is measured against the latest search begun (with two threads searching
    /// at once, the last to begin).
    fn begin_search(&self, query: &Aabb) {
        self.lock().frames.begin_search(query);
    }

    fn end_search(&self) {
        self.lock().frames.end_search();
    }
}

const _: fn() = || {
    fn send_sync<T: Send + Sync>() {}
    send_sync::<BufferPool<'static>>();
};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cache::{DpLru, Lru};
    use crate::store::Backend;

    const PAGE: usize = 1024;

    /// A store of `n` node pages, page i holding `[i as u8; 100]`.
    fn store(n: u64) -> (tempfile::TempDir, std::path::PathBuf, Vec<u64>) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("pages.db");
        let mut s = Store::create(&path, PAGE).unwrap();
        let pages = (0..n)
            .map(|i| s.append_page(PageKind::RtreeNode, &[i as u8; 100]).unwrap())
            .collect();
        s.finish().unwrap();
        (dir, path, pages)
    }

    #[test]
    fn a_budget_below_one_page_is_an_error() {
        let (_d, path, _) = store(1);
        let s = Store::open(&path, Backend::Mmap).unwrap();
        let e = BufferPool::new(&s, PAGE - 1, Box::new(Lru::default())).unwrap_err();
        assert!(matches!(e, Error::Invalid(_)), "{e}");
        assert_eq!(
            BufferPool::new(&s, 3 * PAGE + 5, Box::new(Lru::default()))
                .unwrap()
                .capacity_pages(),
            3
        );
    }

    #[test]
    fn hits_misses_and_the_budget() {
        let (_d, path, pages) = store(50);
        let s = Store::open(&path, Backend::Pread { direct: false }).unwrap();
        let pool = BufferPool::new(&s, 8 * PAGE, Box::new(Lru::default())).unwrap();
        let mut buf = Vec::new();
        for round in 0..3 {
            for (i, p) in pages.iter().enumerate().take(8 + round * 10) {
                pool.get(*p, PageKind::RtreeNode, &Hint::UNKNOWN, &mut buf)
                    .unwrap();
                assert_eq!(buf, [i as u8; 100]);
                assert!(pool.resident_bytes() <= pool.budget_bytes());
            }
        }
        let st = pool.stats();
        assert_eq!(st.misses, s.stats().page_reads);
        assert_eq!(st.accesses(), 8 + 18 + 28);
        assert_eq!(st.hits, 8, "the second round hits the first 8 pages only");
        pool.clear();
        assert_eq!(pool.resident_bytes(), 0);
        pool.reset_stats();
        pool.get(pages[0], PageKind::RtreeNode, &Hint::UNKNOWN, &mut buf)
            .unwrap();
        assert_eq!(
            pool.stats(),
            CacheStats {
                hits: 0,
                misses: 1,
                evictions: 0
            }
        );
    }

    #[test]
    fn a_failed_read_leaves_the_pool_as_it_was() {
        let (_d, path, pages) = store(4);
        // Corrupt page 2's payload on disk.
        {
            use std::os::unix::fs::FileExt;
            let f = std::fs::OpenOptions::new().write(true).open(&path).unwrap();
            f.write_all_at(&[0xAB; 8], pages[2] * PAGE as u64 + 40)
                .unwrap();
        }
        let s = Store::open(&path, Backend::Mmap).unwrap();
        let pool = BufferPool::new(&s, 2 * PAGE, Box::new(DpLru::default())).unwrap();
        pool.set_trace(true);
        let mut buf = Vec::new();
        let leaf = Hint {
            level: 0,
            height: 2,
            ..Hint::UNKNOWN
        };
        pool.get(pages[0], PageKind::RtreeNode, &leaf, &mut buf)
            .unwrap();
        let before = pool.stats();
        let e = pool
            .get(pages[2], PageKind::RtreeNode, &leaf, &mut buf)
            .unwrap_err();
        assert!(
            matches!(e, Error::CorruptPage { page, .. } if page == pages[2]),
            "{e}"
        );
        assert!(
            pool.get(999, PageKind::RtreeNode, &leaf, &mut buf).is_err(),
            "out of range"
        );
        // Cached as a node, asked for as a mesh: the store's kind check answers.
        assert!(pool.get(pages[0], PageKind::Mesh, &leaf, &mut buf).is_err());
        assert_eq!(pool.stats(), before);
        assert_eq!(pool.resident_bytes(), PAGE);
        assert_eq!(
            pool.take_trace().len(),
            1,
            "failed accesses are not recorded"
        );
        pool.get(pages[0], PageKind::RtreeNode, &leaf, &mut buf)
            .unwrap();
        assert_eq!(buf, [0; 100]);
        assert_eq!(pool.stats().hits, 1);
    }

    #[test]
    fn dplru_keeps_the_root_and_serves_the_rest_uncached_when_full() {
        let (_d, path, pages) = store(6);
        let s = Store::open(&path, Backend::Mmap).unwrap();
        let pool = BufferPool::new(&s, PAGE, Box::new(DpLru::default())).unwrap();
        let root = Hint {
            level: 1,
            height: 2,
            ..Hint::UNKNOWN
        };
        let leaf = Hint {
            level: 0,
            height: 2,
            ..Hint::UNKNOWN
        };
        let mut buf = Vec::new();
        for p in &pages[1..] {
            pool.get(pages[0], PageKind::RtreeNode, &root, &mut buf)
                .unwrap();
            pool.get(*p, PageKind::RtreeNode, &leaf, &mut buf).unwrap();
            assert_eq!(buf, [(*p - pages[0]) as u8; 100]);
            pool.end_search();
        }
        let st = pool.stats();
        assert_eq!((st.hits, st.misses, st.evictions), (4, 6, 0));
        assert_eq!(pool.resident_bytes(), PAGE);
    }

    #[test]
    fn two_threads_share_one_pool() {
        let (_d, path, pages) = store(64);
        let s = Store::open(&path, Backend::Mmap).unwrap();
        let pool = BufferPool::new(&s, 16 * PAGE, Box::new(DpLru::default())).unwrap();
        std::thread::scope(|sc| {
            for t in 0..2u64 {
                let (pool, pages) = (&pool, &pages);
                sc.spawn(move || {
                    let mut buf = Vec::new();
                    for i in 0..2000u64 {
                        let k = ((i * 7 + t * 13) % 24) as usize;
                        pool.get(pages[k], PageKind::RtreeNode, &Hint::UNKNOWN, &mut buf)
                            .unwrap();
                        assert_eq!(buf, [k as u8; 100]);
                        assert!(pool.resident_bytes() <= pool.budget_bytes());
                    }
                });
            }
        });
        let st = pool.stats();
        assert_eq!(st.accesses(), 4000);
        assert_eq!(st.misses, s.stats().page_reads);
    }
}
