// The one error type of the crate. Every failure a user can act on names the file, and
// for a damaged scene file the object index, so that "which file, where, what was
// expected" is in the message rather than in a debugger session.

use std::path::PathBuf;

/// Everything that can go wrong writing, reading or configuring a scene.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The operating system refused a read, write, open or create.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file involved.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The file does not start like a scene file (wrong magic, unknown version).
    #[error("{} is not a flaneur scene file: {what}", .path.display())]
    NotAScene {
        /// The file involved.
        path: PathBuf,
        /// What was found instead.
        what: String,
    },
    /// A record (or the trailer after the last record) fails its checks.
    #[error("{}: object {object} is corrupt: {what}", .path.display())]
    Corrupt {
        /// The file involved.
        path: PathBuf,
        /// The 0-based index of the record in the file (the trailer counts as the
        /// index after the last record).
        object: u64,
        /// Which check failed.
        what: String,
    },
    /// The file ends before its trailer; `what` names the object at which it ends.
    #[error("{} is cut short: {what}", .path.display())]
    Truncated {
        /// The file involved.
        path: PathBuf,
        /// Where it ends.
        what: String,
    },
    /// A generator's configuration (citygen's `CityConfig`) or an argument is out of range.
    #[error("invalid configuration: {0}")]
    Config(String),
}

impl SceneError {
    /// Wraps an I/O error with the file it concerns.
    pub fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        SceneError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}
