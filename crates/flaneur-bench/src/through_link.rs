//! What the network experiments share: a database opened by URL through a link of its
//! own, of set round trip and bandwidth, and the checks of their settings.

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use crate::link::{Link, LinkSpec};
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::store::{HttpOptions, RemoteStats};

/// Opens `name`, served at `origin`, through a new link `rtt_ms` and `mbit` away, with
/// a client page cache of `cache_bytes`. The link carries the database's requests for
/// as long as it is held; `what` names the experiment in an error.
pub fn open_through(
    what: &str,
    origin: SocketAddr,
    name: &str,
    (rtt_ms, mbit): (u32, f64),
    cache_bytes: usize,
) -> Result<(Link, Database)> {
    let link = Link::start(
        origin,
        LinkSpec {
            rtt: Duration::from_millis(u64::from(rtt_ms)),
            mbit: Some(mbit),
        },
    )
    .map_err(|e| Error::Invalid(format!("{what}: starting the link: {e}")))?;
    let url = format!("http://{}/{name}", link.addr());
    let db = Database::open_url_with(
        &url,
        &HttpOptions {
            cache_bytes,
            ..HttpOptions::default()
        },
    )?;
    Ok((link, db))
}

/// Checks a network experiment's bandwidths (each above 0 Mbit/s) and client cache
/// (more than 0 bytes); `what` names the experiment in an error.
pub fn check_link(what: &str, mbits: &[f64], cache_bytes: usize) -> Result<()> {
    if let Some(m) = mbits.iter().find(|m| !(m.is_finite() && **m > 0.0)) {
        return Err(Error::Invalid(format!(
            "{what}: a bandwidth must be above 0 Mbit/s, not {m}"
        )));
    }
    if cache_bytes == 0 {
        return Err(Error::Invalid(format!(
            "{what}: the client cache must hold more than 0 bytes"
        )));
    }
    Ok(())
}

/// Runs `walk` over `db`: its answer, its real time, and what it cost the network
/// (`None` for a local file).
pub fn timed<R>(
    db: &Database,
    walk: impl FnOnce() -> Result<R>,
) -> Result<(R, Duration, Option<RemoteStats>)> {
    let before = db.remote_stats();
    let t = Instant::now();
    let r = walk()?;
    let took = t.elapsed();
    let net = db
        .remote_stats()
        .zip(before)
        .map(|(after, before)| after.since(&before));
    Ok((r, took, net))
}
