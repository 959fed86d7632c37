//! `flaneur serve`: a small static server for database files, with byte ranges, ETag and
//! `If-Match` (tower-http's `ServeFile` under axum), to try a city over HTTP without
//! setting up a web server. It is a convenience: any static server that honours `Range`
//! serves a database as well (the tests also read through nginx).

use std::net::{IpAddr, SocketAddr};
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use axum::serve::ListenerExt;
use flaneur::Database;

/// `flaneur serve`'s arguments.
#[derive(clap::Args)]
pub struct ServeArgs {
    /// The database files to serve, each at /<its file name>.
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
    /// Checks each file is a database, then serves them until the process is stopped.
    pub fn run(self) -> Result<()> {
        let mut router = axum::Router::new();
        let mut served = Vec::new();
        for db in &self.dbs {
            let opened = Database::open(db)?;
            let name = db
                .file_name()
                .and_then(|n| n.to_str())
                .with_context(|| format!("{}: no file name to serve it under", db.display()))?
                .to_string();
            if served.iter().any(|(n, _)| n == &name) {
                bail!("two databases named {name}: serve them from different folders' names");
            }
            router = router.route_service(
                &format!("/{name}"),
                tower_http::services::ServeFile::new(db),
            );
            served.push((name, opened.objects()));
        }
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
    let name = db
        .file_name()
        .and_then(|n| n.to_str())
        .with_context(|| format!("{}: no file name to serve it under", db.display()))?
        .to_string();
    let router = axum::Router::new().route_service(
        &format!("/{name}"),
        tower_http::services::ServeFile::new(db),
    );
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

/// Sends each answer's bytes at once: a reader asks for many small ranges, and Nagle's
/// algorithm against the client's delayed ACK would hold each small answer's tail back
/// for tens of milliseconds (nginx sets the same, `tcp_nodelay on`).
fn no_delay(tcp: &mut tokio::net::TcpStream) {
    let _ = tcp.set_nodelay(true);
}
