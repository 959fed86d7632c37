//! The one error type of the library. Every variant names what is wrong and where
//! (file, page, object), so that a user can act on it.

use std::path::PathBuf;

/// The library's result: [`Error`] unless said otherwise.
///
/// ```
/// fn objects(path: &std::path::Path) -> flaneur::Result<u64> {
///     Ok(flaneur::Database::open(path)?.objects())
/// }
/// assert!(objects("no-such.flaneur".as_ref()).is_err());
/// ```
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// What went wrong, naming the file, page or object.
///
/// ```
/// let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("not-a-database.flaneur");
/// std::fs::write(&path, vec![7u8; 8192]).unwrap();
/// match flaneur::Database::open(&path) {
///     Err(flaneur::Error::NotADatabase { path: p, what }) => {
///         assert_eq!(p, path);
///         println!("{what}"); // what was found instead of the header
///     }
///     Err(other) => panic!("{other}"),
///     Ok(_) => panic!("opened a file of sevens"),
/// }
/// ```
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },

    /// The file is not a flaneur database, or a different version of one.
    #[error("{path}: not a flaneur database: {what}")]
    NotADatabase {
        /// The file.
        path: PathBuf,
        /// What was found instead.
        what: String,
    },

    /// A page failed its checks: checksum, kind, length or content.
    #[error("{path}: page {page} is corrupt: {what}")]
    CorruptPage {
        /// The database file.
        path: PathBuf,
        /// The page, counted from 0 (the header).
        page: u64,
        /// Which check failed, and what was found.
        what: String,
    },

    /// The file is shorter than its header says.
    #[error("{path}: truncated: {what}")]
    Truncated {
        /// The file.
        path: PathBuf,
        /// What is missing.
        what: String,
    },

    /// A box that cannot be used (not finite, min above max on some axis, or text that is
    /// not a box); the message names it.
    #[error("bad box: {0}")]
    BadBox(String),

    /// A scene or model file that cannot be read (scene file, OBJ).
    #[error("{path}: {what}")]
    BadInput {
        /// The file.
        path: PathBuf,
        /// What is wrong in it, and where.
        what: String,
    },

    /// A scene's error, from the scene types and the scene file (`flaneur-scene`).
    #[error(transparent)]
    Scene(#[from] flaneur_scene::SceneError),

    /// A cubic projection's resolution (pixels per face side) out of range.
    #[error("cubic projection resolution must be 1..={max} pixels per face side, not {n}")]
    BadResolution {
        /// The resolution asked for.
        n: u32,
        /// The largest there may be.
        max: u32,
    },

    /// A viewpoint or ray origin that is not a finite point, or a ray direction that is
    /// not finite and non-zero; the message names which and its value.
    #[error("{0}")]
    BadViewpoint(String),

    /// An object's mesh that cannot be ray cast (no triangles, bad indices, NaN).
    #[error("object {id}: mesh cannot be ray cast: {what}")]
    BadMesh {
        /// The object's id.
        id: u64,
        /// What is wrong with its mesh.
        what: String,
    },

    /// A viewcell box that is not finite, or has no volume.
    #[error("viewcell {cell}: {what}")]
    BadViewcell {
        /// The viewcell's index among those given.
        cell: usize,
        /// What is wrong with its box.
        what: String,
    },

    /// A setting, argument or value that cannot be used; the message names it.
    #[error("{0}")]
    Invalid(String),

    /// A viewcell grid, position, PVS table or prefetch setting the PVS prefetcher
    /// (`prefetch::pvs`) cannot use.
    #[error("pvs prefetch: {0}")]
    Pvs(String),
    /// The GPU: no adapter, a lost device, a frame that cannot be read back or saved.
    #[error("rendering: {0}")]
    Render(String),

    /// A database read over HTTP failed: the server refused, the connection dropped (after
    /// the retries), or the answer was not the bytes asked for (no range support, a short or
    /// long body, a wrong `Content-Range`); the message names the pages.
    #[error("{url}: {what}")]
    Remote {
        /// The database's URL.
        url: String,
        /// What went wrong, and which pages were being read.
        what: String,
    },

    /// The file behind a URL changed while it was open: the server answered 412 to the
    /// `If-Match` of the version first read, or sent another version's validator. Pages of
    /// two files are never mixed; open the database again.
    #[error("{url}: the database changed on the server while it was open ({what}); open it again")]
    RemoteChanged {
        /// The database's URL.
        url: String,
        /// What showed the change.
        what: String,
    },
}

impl Error {
    /// A copy of a network failure (the server gone, the file changed under it), for
    /// the reads of a batch skipped after it: the same server would fail them too, each
    /// after its retries. `None` for any other error.
    pub(crate) fn network_copy(&self) -> Option<Error> {
        match self {
            Error::Remote { url, what } => Some(Error::Remote {
                url: url.clone(),
                what: what.clone(),
            }),
            Error::RemoteChanged { url, what } => Some(Error::RemoteChanged {
                url: url.clone(),
                what: what.clone(),
            }),
            _ => None,
        }
    }

    /// Runs `read` on each of `items` in order, each result apart, until one fails on
    /// the network: the rest are not read, and fail as it did ([`Error::network_copy`]).
    pub(crate) fn until_offline<T, R>(
        items: impl IntoIterator<Item = T>,
        mut read: impl FnMut(T) -> Result<R, Error>,
    ) -> Vec<Result<R, Error>> {
        let mut offline: Option<Error> = None;
        items
            .into_iter()
            .map(|item| {
                if let Some(e) = offline.as_ref().and_then(Error::network_copy) {
                    return Err(e);
                }
                let got = read(item);
                if let Err(e) = &got {
                    offline = e.network_copy();
                }
                got
            })
            .collect()
    }

    /// An I/O error on `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Error {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}
