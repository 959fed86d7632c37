//! `flaneur serve-stream`: the papers' stateful server over a database's landmarks (the
//! objects its build stored a progressive mesh and DAG for), one thread per client. It
//! prints each session's end, with the reason when the server closed it.

use crate::cli::args::{idle_seconds, wait_ms};
use std::net::{IpAddr, SocketAddr};
use std::path::PathBuf;
use std::time::Duration;

use anyhow::{bail, Context, Result};

use super::source::SourceArgs;

use clap::builder::RangedU64ValueParser;
use flaneur_stream::{Landmark, ServerConfig, StreamServer};

/// `flaneur serve-stream`'s arguments.
#[derive(clap::Args)]
pub struct ServeStreamArgs {
    /// The database (a file, or an http:// or https:// URL): built with LODs, its
    /// objects above `--pm-threshold` have the progressive meshes it streams.
    db: PathBuf,
    /// The port to listen on; 0 picks a free one (printed).
    #[arg(long, default_value_t = 7878)]
    port: u16,
    /// The address to listen on: loopback by default, 0.0.0.0 for every interface.
    #[arg(long, default_value = "127.0.0.1")]
    bind: IpAddr,
    /// Stream at most this many landmarks, the largest.
    #[arg(long, default_value_t = 64)]
    landmarks: usize,
    /// Close a session that sends nothing for this many seconds, within (0, 86400] (a
    /// day).
    #[arg(long, value_name = "SECONDS", default_value_t = 60.0, value_parser = idle_seconds, allow_negative_numbers = true)]
    idle_s: f64,
    /// Levels of a block in sessions of El-Sana's blocks.
    #[arg(long, default_value_t = ServerConfig::default().block_levels)]
    block_levels: u8,
    /// In sessions of blocks, predict the client's next view and send the blocks it
    /// will want after this many milliseconds without a message (0: never), within
    /// [0, 3600000] (an hour).
    #[arg(long, value_name = "MS", default_value_t = ServerConfig::default().idle.as_millis() as u64, value_parser = wait_ms)]
    predict_after_ms: u64,
    /// The most blocks a prediction asks for per landmark.
    #[arg(long, default_value_t = ServerConfig::default().predict_blocks)]
    predict_blocks: usize,
    /// The most sessions served at once, 1 to 65536: a client that connects past them
    /// is told so (REFUSED) and closed.
    #[arg(long, value_name = "N", default_value_t = ServerConfig::default().max_sessions,
          value_parser = RangedU64ValueParser::<usize>::new().range(1..=65536))]
    max_sessions: usize,
    /// The most MiB of a client's messages one session holds at once, a message being
    /// received included, 1 to 1024: a longer message is refused before it is read.
    #[arg(long, value_name = "MIB", default_value_t = ServerConfig::default().session_budget >> 20,
          value_parser = RangedU64ValueParser::<usize>::new().range(1..=1024))]
    session_mb: usize,
    #[command(flatten)]
    source: SourceArgs,
}

impl ServeStreamArgs {
    /// Loads the landmarks and serves them until the process is stopped.
    pub fn run(self) -> Result<()> {
        if !(self.idle_s.is_finite() && self.idle_s > 0.0) {
            bail!(
                "--idle-s must be a positive number of seconds, not {}",
                self.idle_s
            );
        }
        if self.block_levels == 0 {
            bail!("--block-levels must be at least 1");
        }
        return_freed_blocks();
        let db = self.source.open(&self.db)?;
        let landmarks = Landmark::all_in(&db, self.landmarks)
            .with_context(|| format!("reading the landmarks of {}", self.db.display()))?;
        if landmarks.is_empty() {
            bail!(
                "{} has no object with a progressive mesh to stream: build it with LODs \
                 (objects above --pm-threshold get one)",
                self.db.display()
            );
        }
        let triangles: usize = landmarks.iter().map(Landmark::triangles).sum();
        let count = landmarks.len();
        let config = ServerConfig {
            idle_timeout: Duration::from_secs_f64(self.idle_s),
            block_levels: self.block_levels,
            idle: Duration::from_millis(self.predict_after_ms),
            predict_blocks: self.predict_blocks,
            max_sessions: self.max_sessions,
            session_budget: self.session_mb << 20,
        };
        let server = StreamServer::bind(SocketAddr::new(self.bind, self.port), landmarks, config)
            .with_context(|| format!("listening on {}:{}", self.bind, self.port))?
            .spawn()?;
        println!(
            "streaming {count} landmarks ({triangles} triangles in full) on tcp://{}; at most \
             {} sessions at once, each holding at most {} MiB of its client's messages; stop \
             with Ctrl-C",
            server.addr(),
            self.max_sessions,
            self.session_mb
        );
        for end in server.ends() {
            match end.reason {
                None => println!(
                    "{}: {} views answered, {} bytes sent; the client ended it",
                    end.peer, end.frames, end.bytes_out
                ),
                Some(why) => println!(
                    "{}: {} views answered, {} bytes sent; closed: {why}",
                    end.peer, end.frames, end.bytes_out
                ),
            }
        }
        Ok(())
    }
}

/// Fixes glibc's mmap and trim thresholds at their defaults (128 KiB). Left dynamic,
/// each large block freed raises the mmap threshold to its size (up to 32 MiB) and the
/// trim threshold to twice that, so that once a session's large arrays or a long
/// message have been freed, later ones come from the per-thread arenas, each of which
/// keeps what it is given back: a server of one thread per session then holds far
/// more than its sessions. Fixed, a block above 128 KiB is mapped on its own and
/// returned when freed. (Fewer arenas, `M_ARENA_MAX`, made it worse: sessions on
/// many threads then share and fragment them.)
fn return_freed_blocks() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets the allocator's parameters, and is called before the
    // server starts its threads.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 128 << 10);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 128 << 10);
    }
}
