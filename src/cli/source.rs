//! Where a command reads its database: a file, through a backend, or a URL on any HTTP
//! server, by byte ranges through a client page cache.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Result};

use flaneur::database::BuildInput;
use flaneur::store::{is_url, Backend, HttpOptions, RemoteStats};
use flaneur::Database;

/// The largest `--cache-mb` taken: 128 TiB, what a process can address with 48-bit
/// addresses (x86-64, aarch64). A larger value is no memory size but a slip (bytes given
/// for MiB); below it, the cache is capped at the file's size and the memory available.
pub const MAX_CACHE_MIB: usize = 1 << 27;

/// How a command reaches its database.
#[derive(clap::Args, Clone, Debug)]
pub struct SourceArgs {
    /// How a database file is read: mmap, pread, or direct (O_DIRECT, past the page
    /// cache). A database given as a URL (http://… or https://…) is read over HTTP.
    #[arg(long, default_value = "mmap")]
    pub backend: Backend,
    /// For a database given as a URL: the client page cache, in MiB.
    #[arg(long, default_value_t = 256, value_name = "MIB")]
    pub cache_mb: usize,
    /// For a database given as a URL: keep fetched pages in this folder, so that a
    /// second visit to the same version of the file reads them there, not over HTTP
    /// (default: none, pages kept in memory only).
    #[arg(long, value_name = "DIR")]
    pub cache_dir: Option<PathBuf>,
}

impl Default for SourceArgs {
    fn default() -> SourceArgs {
        SourceArgs {
            backend: Backend::default(),
            cache_mb: 256,
            cache_dir: None,
        }
    }
}

impl SourceArgs {
    /// Opens `db`: a URL over HTTP, else the file with the chosen backend. Prints, once,
    /// what the open of a URL warns of; a build's input given for a database is an
    /// error saying how to build one from it.
    pub fn open(&self, db: &Path) -> Result<Database> {
        let opened = match db.to_str() {
            Some(location) if is_url(location) => {
                Database::open_url_with(location, &self.http_options()?)
            }
            _ => Database::open_with(db, self.backend),
        };
        let db = opened.map_err(|e| suggest_build(e, db))?;
        for warning in db.remote_warnings() {
            eprintln!("warning: {warning}");
        }
        Ok(db)
    }

    /// The HTTP client's settings these arguments ask for; an error for a `--cache-mb`
    /// that is no memory size.
    pub fn http_options(&self) -> Result<HttpOptions> {
        if self.cache_mb > MAX_CACHE_MIB {
            bail!(
                "--cache-mb {}: {} TiB, more than a process can address; the most taken is \
                 {MAX_CACHE_MIB} MiB (128 TiB). The value is in MiB, and the cache is capped \
                 at the file's size and at the memory available anyway",
                self.cache_mb,
                self.cache_mb >> 20
            );
        }
        Ok(HttpOptions {
            cache_bytes: self.cache_mb.saturating_mul(1 << 20),
            cache_dir: self.cache_dir.clone(),
            ..HttpOptions::default()
        })
    }
}

/// `e`, with the command that builds a database when `db` is a build's input.
pub fn suggest_build(e: flaneur::Error, db: &Path) -> anyhow::Error {
    match (&e, BuildInput::of(db)) {
        (flaneur::Error::NotADatabase { .. }, Some(_)) => anyhow!(
            "{e}\nbuild a database from it first: flaneur build {} -o city.flaneur",
            db.display()
        ),
        _ => e.into(),
    }
}

/// Opens `db`, a file or a URL, with the default settings (the benches' way).
pub fn open(db: &Path) -> Result<Database> {
    SourceArgs::default().open(db)
}

/// One line on what reading over HTTP cost, for a database given as a URL.
pub fn remote_line(stats: &RemoteStats) -> String {
    format!(
        "http        {} requests in {} round trips, {:.2} MiB received, {} retried; page cache hit rate {:.1}% ({} of {} page reads fetched)",
        stats.requests,
        stats.round_trips,
        stats.bytes as f64 / (1 << 20) as f64,
        stats.retries,
        100.0 * stats.hit_rate(),
        stats.pages_fetched,
        stats.page_reads
    )
}
