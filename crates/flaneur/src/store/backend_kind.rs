//! The choice of how a store reads a file's pages, as the CLI's `--backend` names it.

use std::fmt;
use std::str::FromStr;

use crate::error::{Error, Result};

/// How a store reads pages.
///
/// ```
/// use flaneur::store::Backend;
/// assert_eq!("mmap".parse::<Backend>().unwrap(), Backend::Mmap);
/// assert_eq!("direct".parse::<Backend>().unwrap(), Backend::Pread { direct: true });
/// assert_eq!(Backend::Pread { direct: false }.to_string(), "pread");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Backend {
    /// The whole file memory-mapped; pages are copied out of the map. The fast default.
    #[default]
    Mmap,
    /// One positioned read per page; with `direct`, the file is opened with O_DIRECT
    /// so reads bypass the page cache (cold-cache experiments; not every filesystem
    /// allows it).
    Pread {
        /// Open the file with O_DIRECT.
        direct: bool,
    },
    /// Byte ranges from an HTTP server, through a client page cache: what a store opened
    /// with [`Store::open_url`](super::Store::open_url) reads with. Not a backend for a file.
    Http,
}

impl Backend {
    /// The name `FromStr` accepts: `"mmap"`, `"pread"` or `"direct"`.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Mmap => "mmap",
            Backend::Pread { direct: false } => "pread",
            Backend::Pread { direct: true } => "direct",
            Backend::Http => "http",
        }
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Backend {
    type Err = Error;

    fn from_str(s: &str) -> Result<Backend> {
        match s {
            "mmap" => Ok(Backend::Mmap),
            "pread" => Ok(Backend::Pread { direct: false }),
            "direct" => Ok(Backend::Pread { direct: true }),
            "http" => Err(Error::Invalid(
                "the http backend is chosen by giving a URL (http://… or https://…) instead of a path"
                    .to_string(),
            )),
            other => Err(Error::Invalid(format!(
                "unknown storage backend {other:?} (expected mmap, pread or direct)"
            ))),
        }
    }
}
