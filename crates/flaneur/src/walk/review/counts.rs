//! The searches a REVIEW walk ran, by where their results went.

/// Searches run along a walk, by where their results went.
#[derive(Clone, Debug, Default)]
pub(crate) struct Counts {
    pub sync: usize,
    pub adopted: usize,
    pub stale: usize,
    /// Searches the viewer queued on the loader (never-wait walks).
    pub queued: usize,
    /// Loads that failed on the network, and the last error.
    pub failed: usize,
    pub last_failure: Option<String>,
    /// Index and mesh pages read by frame 0's own query (before any prefetch started).
    pub initial_load_pages: (u64, u64),
}
