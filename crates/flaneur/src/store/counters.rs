//! I/O counters: the one place every physical page read is counted.
//!
//! One relaxed atomic per kind is bumped per page read; totals are derived from them
//! when a snapshot is taken, so the hot path costs a single uncontended add.

use std::sync::atomic::{AtomicU64, Ordering};

use super::page::{PageKind, KIND_SLOTS};

/// A snapshot of a store's read counters. Every physical page read (`read_page`,
/// `read_page_into`, each page of `read_extent`) counts once. The header read at
/// open is not counted: a freshly opened store starts at zero.
///
/// ```
/// use flaneur::store::{IoStats, PageKind};
/// let mut later = IoStats::default();
/// later.page_reads = 5;
/// later.by_kind[PageKind::RtreeNode as usize] = 5;
/// assert_eq!(later.since(&IoStats::default()).reads_of(PageKind::RtreeNode), 5);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct IoStats {
    /// Pages read, all kinds.
    pub page_reads: u64,
    /// Bytes read: whole pages, `page_reads * page_size`.
    pub bytes_read: u64,
    /// Pages read, indexed by kind byte (`PageKind as usize`).
    pub by_kind: [u64; KIND_SLOTS],
}

impl IoStats {
    /// Pages of `kind` read.
    pub fn reads_of(&self, kind: PageKind) -> u64 {
        self.by_kind[kind as usize]
    }

    /// The reads between an earlier snapshot and this one.
    pub fn since(&self, earlier: &IoStats) -> IoStats {
        let mut by_kind = [0u64; KIND_SLOTS];
        for (d, (now, then)) in by_kind
            .iter_mut()
            .zip(self.by_kind.iter().zip(&earlier.by_kind))
        {
            *d = now.saturating_sub(*then);
        }
        IoStats {
            page_reads: self.page_reads.saturating_sub(earlier.page_reads),
            bytes_read: self.bytes_read.saturating_sub(earlier.bytes_read),
            by_kind,
        }
    }
}

/// The live counters of one store.
#[derive(Debug, Default)]
pub(crate) struct Counters {
    by_kind: [AtomicU64; KIND_SLOTS],
}

impl Counters {
    /// Counts one page of `kind` read.
    #[inline]
    pub(crate) fn record(&self, kind: PageKind) {
        self.by_kind[kind as usize].fetch_add(1, Ordering::Relaxed);
    }

    /// The counters now, for a store with `page_size`-byte pages.
    pub(crate) fn snapshot(&self, page_size: usize) -> IoStats {
        let mut s = IoStats::default();
        for (d, c) in s.by_kind.iter_mut().zip(&self.by_kind) {
            *d = c.load(Ordering::Relaxed);
        }
        s.page_reads = s.by_kind.iter().sum();
        s.bytes_read = s.page_reads * page_size as u64;
        s
    }

    /// Sets every counter to zero.
    pub(crate) fn reset(&self) {
        for c in &self.by_kind {
            c.store(0, Ordering::Relaxed);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_and_since() {
        let c = Counters::default();
        c.record(PageKind::RtreeNode);
        c.record(PageKind::RtreeNode);
        let a = c.snapshot(4096);
        c.record(PageKind::Mesh);
        let b = c.snapshot(4096);
        assert_eq!(b.page_reads, 3);
        assert_eq!(b.bytes_read, 3 * 4096);
        assert_eq!(b.reads_of(PageKind::RtreeNode), 2);
        let d = b.since(&a);
        assert_eq!((d.page_reads, d.bytes_read), (1, 4096));
        assert_eq!(d.reads_of(PageKind::Mesh), 1);
        assert_eq!(d.reads_of(PageKind::RtreeNode), 0);
        c.reset();
        assert_eq!(c.snapshot(4096), IoStats::default());
    }

    #[test]
    fn threads_share_counters() {
        let c = Counters::default();
        std::thread::scope(|s| {
            for _ in 0..4 {
                s.spawn(|| (0..1000).for_each(|_| c.record(PageKind::Meta)));
            }
        });
        assert_eq!(c.snapshot(1024).reads_of(PageKind::Meta), 4000);
    }
}
