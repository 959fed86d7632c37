//! Reads a never-wait loader asked for and the network failed, each asked for again (ours):
//! how many, and the last one's words. The PVS and VISUAL lanes count them as their
//! loaders tell of them while the walk runs, and once more as it ends, for what a loader
//! was still reading then, so that a headless walk can end in failure.

use crate::error::Error;

/// Loads that failed on the network.
#[derive(Debug, Default)]
pub(crate) struct LoadFailures {
    pub count: usize,
    /// The last failure's words.
    pub last: Option<String>,
}

impl LoadFailures {
    /// A read failed for `why`.
    pub fn note(&mut self, why: String) {
        self.count += 1;
        self.last = Some(why);
    }

    /// A loader stopped on `e` as the walk ended: counted where the network failed;
    /// any other stop is handed back for the caller to name.
    pub fn note_stop(&mut self, e: Error) -> Option<Error> {
        match e {
            Error::Remote { .. } | Error::RemoteChanged { .. } => {
                self.note(e.to_string());
                None
            }
            e => Some(e),
        }
    }
}
