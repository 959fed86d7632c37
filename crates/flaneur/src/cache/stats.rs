//! The cache's counters — counted once, in the pool (or its replay), and only reported
//! elsewhere. Shou 2002 reports the hit rate (Fig. 4.18, Fig. 5.15–5.20).

/// Hits, misses and evictions of a pool or of a replayed trace. Every completed access
/// is exactly one hit or one miss; cold misses count.
///
/// ```
/// use flaneur::cache::CacheStats;
/// let s = CacheStats { hits: 3, misses: 1, evictions: 0 };
/// assert_eq!(s.hit_rate(), 0.75);
/// assert_eq!(CacheStats::default().hit_rate(), 0.0);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct CacheStats {
    /// Accesses served from the cache.
    pub hits: u64,
    /// Accesses that read the page from the store (one physical read each).
    pub misses: u64,
    /// Resident pages dropped to make room.
    pub evictions: u64,
}

impl CacheStats {
    /// Hits + misses.
    pub fn accesses(&self) -> u64 {
        self.hits + self.misses
    }

    /// hits / accesses; 0 before any access.
    pub fn hit_rate(&self) -> f64 {
        match self.accesses() {
            0 => 0.0,
            n => self.hits as f64 / n as f64,
        }
    }

    /// The counts between an earlier snapshot and this one.
    pub fn since(&self, earlier: &CacheStats) -> CacheStats {
        CacheStats {
            hits: self.hits.saturating_sub(earlier.hits),
            misses: self.misses.saturating_sub(earlier.misses),
            evictions: self.evictions.saturating_sub(earlier.evictions),
        }
    }
}
