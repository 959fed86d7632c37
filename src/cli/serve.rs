//! `flaneur serve`: a small static server for database files, or for a folder of them
//! (a published city: its databases beside their other files), with byte ranges, ETag and
//! `If-Match` (tower-http's `ServeDir` under axum), to try a city over HTTP without
//! setting up a web server. It is a convenience: any static server that honours `Range`
//! serves a database as well (the tests also read through nginx).
//!
//! Every request is confined to what the server was told to serve. The folders are opened
//! once, at the start, and every request opens its file relative to them, a component at
//! a time, without following a symbolic link (`openat` with `O_NOFOLLOW`), and serves it
//! only if it is a regular file: a link put in a served file's place after the start, or
//! a served folder renamed and a link put in its place, serves nothing outside. A file
//! replaced by another (a new build renamed over it) is served anew, its ETag changed.

use std::collections::HashMap;
use std::ffi::{CString, OsStr, OsString};
use std::fs::File;
use std::future::Future;
use std::io;
use std::net::{IpAddr, SocketAddr};
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd, RawFd};
use std::os::unix::ffi::OsStrExt;
use std::path::{Component, Path, PathBuf};
use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context as TaskContext, Poll};

use anyhow::{bail, Context, Result};

use axum::serve::ListenerExt;
use flaneur::Database;
use tower_http::services::fs::{Backend, ServeDir};

/// `flaneur serve`'s arguments.
#[derive(clap::Args)]
pub struct ServeArgs {
    /// The database files to serve, each at /<its file name>; or one folder, whose regular
    /// files (subfolders included; no links, no hidden names) are served at their paths
    /// below it.
    #[arg(required = true)]
    dbs: Vec<PathBuf>,
    /// The port to listen on; 0 picks a free one (printed).
    #[arg(long, default_value_t = 8080)]
    port: u16,
    /// The address to listen on: loopback by default, 0.0.0.0 for every interface.
    #[arg(long, default_value = "127.0.0.1")]
    bind: IpAddr,
}

impl ServeArgs {
    /// Checks each file is a database (or opens the one folder given), then serves until
    /// the process is stopped.
    pub fn run(self) -> Result<()> {
        let (root, served, folder) = match &self.dbs[..] {
            [dir] if dir.is_dir() => {
                let (root, served) = Root::folder(dir)?;
                (root, served, Some(dir.clone()))
            }
            dbs => {
                if let Some(dir) = dbs.iter().find(|p| p.is_dir()) {
                    bail!(
                        "{}: a folder among files; serve one folder, or database files, \
                         not both",
                        dir.display()
                    );
                }
                let (root, served) = Root::files(dbs)?;
                (root, served, None)
            }
        };
        let router = router(root);
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .enable_all()
            .build()
            .context("starting the server's runtime")?;
        runtime.block_on(async move {
            let listener = tokio::net::TcpListener::bind(SocketAddr::new(self.bind, self.port))
                .await
                .with_context(|| format!("listening on {}:{}", self.bind, self.port))?;
            let at = listener.local_addr()?;
            println!("byte ranges, ETag and If-Match; stop with Ctrl-C");
            if let Some(dir) = folder {
                println!(
                    "folder      {}: its regular files at http://{at}/<path in it> (no \
                     symbolic link followed, no hidden file)",
                    dir.display()
                );
            }
            for (name, objects) in &served {
                println!("serving http://{at}/{name} ({objects} objects)");
            }
            axum::serve(listener.tap_io(no_delay), router)
                .await
                .context("serving the databases")
        })
    }
}

/// Serves `db` on a free loopback port from a thread of its own, for as long as the
/// process runs (`flaneur bench http`'s origin server): its address and the name it is
/// served under.
pub fn spawn(db: &Path) -> Result<(SocketAddr, String)> {
    let (root, _) = Root::files(&[db.to_path_buf()])?;
    let name = served_name(db)?;
    let router = router(root);
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("starting the server's runtime")?;
    let listener = runtime
        .block_on(tokio::net::TcpListener::bind(("127.0.0.1", 0)))
        .context("listening on loopback")?;
    let at = listener.local_addr()?;
    std::thread::Builder::new()
        .name("serve".into())
        .spawn(move || {
            runtime.block_on(async move { axum::serve(listener.tap_io(no_delay), router).await })
        })
        .context("starting the server's thread")?;
    Ok((at, name))
}

/// Every path answered from `root`: files, with byte ranges, ETag and `If-Match`; a
/// folder's path, or anything outside `root`, 404.
fn router(root: Root) -> axum::Router {
    let files = ServeDir::with_backend("", Confined(Arc::new(root)))
        .append_index_html_on_directories(false)
        .redirect_to_trailing_slash(false);
    axum::Router::new().fallback_service(files)
}

/// Sends each answer's bytes at once: a reader asks for many small ranges, and Nagle's
/// algorithm against the client's delayed ACK would hold each small answer's tail back
/// for tens of milliseconds (nginx sets the same, `tcp_nodelay on`).
fn no_delay(tcp: &mut tokio::net::TcpStream) {
    let _ = tcp.set_nodelay(true);
}

/// The name `db` is served under: its file name.
fn served_name(db: &Path) -> Result<String> {
    Ok(db
        .file_name()
        .and_then(|n| n.to_str())
        .with_context(|| format!("{}: no file name to serve it under", db.display()))?
        .to_string())
}

/// What the server may open: the folders it was told of, held open since the start.
enum Root {
    /// One folder: every regular file below it, but hidden ones (a name starting with
    /// a dot: `.git`, an editor's temporary).
    Folder(OwnedFd),
    /// Files named on the command line: by the name each is served under, its folder
    /// and its name there (a link given at the start resolved then, once).
    Files(HashMap<OsString, (OwnedFd, OsString)>),
}

impl Root {
    /// The folder `dir`; with the databases at its top, which are listed (name, objects)
    /// when they open; a `.flaneur` file that does not open is a warning, still served.
    fn folder(dir: &Path) -> Result<(Root, Vec<(String, u64)>)> {
        let real = dir
            .canonicalize()
            .with_context(|| format!("{}: cannot serve this folder", dir.display()))?;
        let fd = open_dir(&real).with_context(|| format!("{}: cannot open", dir.display()))?;
        let mut served = Vec::new();
        let mut entries: Vec<_> = std::fs::read_dir(&real)
            .with_context(|| format!("{}: cannot list", dir.display()))?
            .filter_map(|e| e.ok())
            .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
            .map(|e| e.path())
            .filter(|p| p.extension() == Some(OsStr::new("flaneur")))
            .collect();
        entries.sort();
        for path in entries {
            let Ok(name) = served_name(&path) else {
                continue;
            };
            if name.starts_with('.') {
                continue;
            }
            match Database::open(&path) {
                Ok(db) => served.push((name, db.objects())),
                Err(e) => eprintln!("warning: {e} (served as a file all the same)"),
            }
        }
        Ok((Root::Folder(fd), served))
    }

    /// The database files `dbs`, each checked to be one, each served under its name.
    fn files(dbs: &[PathBuf]) -> Result<(Root, Vec<(String, u64)>)> {
        let mut files = HashMap::new();
        let mut served = Vec::new();
        for db in dbs {
            let opened = Database::open(db)?;
            let name = served_name(db)?;
            if files.contains_key(OsStr::new(&name)) {
                bail!("two databases named {name}: serve them from different folders' names");
            }
            let real = db
                .canonicalize()
                .with_context(|| format!("{}: cannot serve this file", db.display()))?;
            let (Some(parent), Some(file)) = (real.parent(), real.file_name()) else {
                bail!("{}: no folder and name to serve it from", db.display());
            };
            let fd =
                open_dir(parent).with_context(|| format!("{}: cannot open", parent.display()))?;
            files.insert(OsString::from(&name), (fd, file.to_os_string()));
            served.push((name, opened.objects()));
        }
        Ok((Root::Files(files), served))
    }

    /// The regular file at `path` (as `ServeDir` joins it to the base ".": "./a/b"),
    /// opened below the root without following a link; `NotFound` for anything else.
    fn open(&self, path: &Path) -> io::Result<File> {
        let mut names = Vec::new();
        for c in path.components() {
            match c {
                Component::CurDir if names.is_empty() => {}
                Component::Normal(n) => names.push(n),
                _ => return Err(not_found("a path outside the served files")),
            }
        }
        let file = match self {
            Root::Files(files) => {
                let [name] = names[..] else {
                    return Err(not_found("not a served file"));
                };
                let (dir, real) = files.get(name).ok_or_else(|| not_found("not served"))?;
                open_below(dir.as_raw_fd(), &[real.as_os_str()])?
            }
            Root::Folder(dir) => {
                if names.is_empty() || names.iter().any(|n| n.as_bytes().starts_with(b".")) {
                    return Err(not_found("not a served file"));
                }
                open_below(dir.as_raw_fd(), &names)?
            }
        };
        if !file.metadata()?.is_file() {
            return Err(not_found("not a regular file"));
        }
        Ok(file)
    }
}

/// Opens the folder `dir`, following links (what the command line names is trusted at
/// the start).
fn open_dir(dir: &Path) -> io::Result<OwnedFd> {
    let path = CString::new(dir.as_os_str().as_bytes())?;
    // SAFETY: a NUL-terminated path; the descriptor returned, if any, is ours alone.
    let fd = unsafe {
        libc::open(
            path.as_ptr(),
            libc::O_RDONLY | libc::O_DIRECTORY | libc::O_CLOEXEC,
        )
    };
    owned(fd)
}

/// Opens `names` below the folder `dir`: each but the last a folder, the last a file,
/// none of them a symbolic link.
fn open_below(dir: RawFd, names: &[&OsStr]) -> io::Result<File> {
    let mut held: Option<OwnedFd> = None;
    for (i, name) in names.iter().enumerate() {
        let at = held.as_ref().map_or(dir, |fd| fd.as_raw_fd());
        let last = i + 1 == names.len();
        // Non-blocking, so that a FIFO in the folder cannot hold the open; a regular
        // file's reads do not heed the flag.
        let flags = libc::O_RDONLY
            | libc::O_NOFOLLOW
            | libc::O_CLOEXEC
            | if last {
                libc::O_NONBLOCK | libc::O_NOCTTY
            } else {
                libc::O_DIRECTORY
            };
        let c = CString::new(name.as_bytes()).map_err(|_| not_found("a NUL in the name"))?;
        // SAFETY: `at` is an open folder we hold; a NUL-terminated name; the descriptor
        // returned, if any, is ours alone.
        let fd = unsafe { libc::openat(at, c.as_ptr(), flags) };
        // A link (ELOOP), a file where a folder was expected (ENOTDIR): not served.
        held = Some(owned(fd).map_err(|e| not_found(&e.to_string()))?);
    }
    held.map(File::from)
        .ok_or_else(|| not_found("an empty path"))
}

fn owned(fd: RawFd) -> io::Result<OwnedFd> {
    if fd < 0 {
        return Err(io::Error::last_os_error());
    }
    // SAFETY: a descriptor just returned by open or openat, owned by no one else.
    Ok(unsafe { OwnedFd::from_raw_fd(fd) })
}

fn not_found(why: &str) -> io::Error {
    io::Error::new(io::ErrorKind::NotFound, why.to_string())
}

/// tower-http's file system backend, every open confined to a [`Root`].
#[derive(Clone)]
struct Confined(Arc<Root>);

type Boxed<T> = Pin<Box<dyn Future<Output = io::Result<T>> + Send>>;

impl Confined {
    /// The regular file at `path`, opened on the blocking pool (as tokio's own file
    /// opens are).
    fn open_file(&self, path: PathBuf) -> Boxed<File> {
        let root = self.0.clone();
        Box::pin(async move {
            tokio::task::spawn_blocking(move || root.open(&path))
                .await
                .map_err(io::Error::other)?
        })
    }
}

impl Backend for Confined {
    type File = ConfinedFile;
    type Metadata = std::fs::Metadata;
    type OpenFuture = Boxed<ConfinedFile>;
    type MetadataFuture = Boxed<std::fs::Metadata>;

    fn open(&self, path: PathBuf) -> Self::OpenFuture {
        let file = self.open_file(path);
        Box::pin(async move { Ok(ConfinedFile(tokio::fs::File::from_std(file.await?))) })
    }

    fn metadata(&self, path: PathBuf) -> Self::MetadataFuture {
        let file = self.open_file(path);
        Box::pin(async move { file.await?.metadata() })
    }
}

/// A file [`Confined`] opened, read and sought by tokio.
struct ConfinedFile(tokio::fs::File);

impl tokio::io::AsyncRead for ConfinedFile {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut TaskContext<'_>,
        buf: &mut tokio::io::ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        Pin::new(&mut self.0).poll_read(cx, buf)
    }
}

impl tokio::io::AsyncSeek for ConfinedFile {
    fn start_seek(mut self: Pin<&mut Self>, position: io::SeekFrom) -> io::Result<()> {
        Pin::new(&mut self.0).start_seek(position)
    }

    fn poll_complete(mut self: Pin<&mut Self>, cx: &mut TaskContext<'_>) -> Poll<io::Result<u64>> {
        Pin::new(&mut self.0).poll_complete(cx)
    }
}

impl tower_http::services::fs::File for ConfinedFile {
    type Metadata = std::fs::Metadata;
    type MetadataFuture<'a> =
        Pin<Box<dyn Future<Output = io::Result<std::fs::Metadata>> + Send + 'a>>;

    fn metadata(&self) -> Self::MetadataFuture<'_> {
        Box::pin(self.0.metadata())
    }
}
