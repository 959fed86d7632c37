//! The stream server: one thread per client over a shared, read-only set of landmarks
//! (El-Sana's interface thread per client, §5), each session holding its own fronts
//! and counters (Zheng 2007 §8.2.1) and running the traversal for every view it is sent.
//!
//! Plain threads, not an async runtime: a session's work is the traversal, which is
//! CPU-bound and short (well under a millisecond a frame for the thesis's settings,
//! `bench lod-refine`), between blocking reads of 38-byte views; a thread per client
//! keeps one client's slow link or stall from holding back another's traversal, with
//! no executor to starve.
//!
//! A session that sends what the protocol does not allow (bytes that are not a
//! message, a frame over the bound, a VIEW before HELLO, frames out of order, a view
//! the engine refuses) is answered REFUSED with the reason and closed; its reason goes
//! to the server's log of session ends, and no other session notices.
//!
//! A client that reconnects resumes with RESUME: a fresh session's refiners split the
//! nodes the client holds ([`Refiner::restore`]), so that the session goes on from the
//! meshes the client has, whatever batches the lost connection took with it.
//!
//! A session of a truly selective scheme (Kim–Lee–Kobbelt) keeps per landmark the front
//! of what it sent ([`SelectiveServer`]) over a [`SelectiveSource`] every session
//! shares; the sources are made when the first such session comes, so a server whose
//! clients all speak Zheng's scheme never holds them. Its resume is RESUME-LEAVES.
//!
//! A session of El-Sana's blocks runs in [`block_session`]: over the same sources, a
//! [`BlockServer`](flaneur::lod::BlockServer) per landmark, its messages read on a
//! thread of their own so that the session can tell the client's silence and predict
//! (El-Sana §6.2).
//!
//! Limits, so that no set of clients can take the server's memory: at most
//! [`ServerConfig::max_sessions`] sessions at once (a client past them is answered
//! REFUSED, saying so, and closed, and its end is logged as any other's), and per
//! session at most [`ServerConfig::session_budget`] bytes of the client's messages
//! held at once. A frame announced longer than the budget allows is refused before any
//! of it is read, and one within it is read as its bytes come (`protocol::receive`),
//! so that a client that announces a long message and stalls makes the server hold
//! only what it sent. What a session holds besides is its traversal's state, the same
//! for every session of a scheme (`SessionEnd::memory`).

mod block_session;
mod session;

use std::io::{self, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Arc, OnceLock};
use std::thread;
use std::time::{Duration, Instant};

use crate::error::StreamError;
use crate::landmark::Landmark;
use crate::protocol::{send, Message, SelectiveObject, WelcomeObject, MAX_OBJECTS, MAX_TO_SERVER};
use flaneur::lod::{Refiner, SelectiveSource};
use session::{serve, session};

/// How a server treats its sessions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ServerConfig {
    /// A session that sends nothing for this long, or does not read what it is sent
    /// for this long (a stalled client, whose batches fill the connection), is closed.
    pub idle_timeout: Duration,
    /// The levels of a block in sessions of blocks (at least 1), which BLOCKS-WELCOME
    /// tells their clients.
    pub block_levels: u8,
    /// How long a session of blocks waits for the client's next message after an
    /// answer before it predicts the client's next view and sends the blocks it will
    /// want (El-Sana §6.2); zero: it never predicts.
    pub idle: Duration,
    /// The most blocks a prediction asks for per landmark (each with the blocks above
    /// it and those its splits force, which come with it); zero: no prediction.
    pub predict_blocks: usize,
    /// The most sessions served at once (at least 1): a client that connects past them
    /// is answered REFUSED, saying so, and closed.
    pub max_sessions: usize,
    /// The most bytes of the client's messages one session holds at once, a message
    /// being received included (at least [`MIN_SESSION_BUDGET`]): a frame announced
    /// longer is refused before it is read. A RESUME is read up to this (and
    /// [`MAX_RESUME`](crate::protocol::MAX_RESUME)); a session of blocks, which reads
    /// a message ahead while it answers one, reads a SWITCH up to a third of it (and
    /// [`MAX_SWITCH`](crate::protocol::MAX_SWITCH)).
    pub session_budget: usize,
}

/// The least [`ServerConfig::session_budget`]: three of the longest frames a session
/// reads besides RESUME and SWITCH, so that every scheme's VIEW fits.
pub const MIN_SESSION_BUDGET: usize = 3 * MAX_TO_SERVER;

impl Default for ServerConfig {
    fn default() -> ServerConfig {
        ServerConfig {
            idle_timeout: Duration::from_secs(60),
            block_levels: 2,
            idle: Duration::from_millis(10),
            predict_blocks: 8,
            max_sessions: 64,
            // A RESUME of a million nodes held split; a session of blocks' SWITCH of
            // MAX_SWITCH, three at once.
            session_budget: 4 << 20,
        }
    }
}

/// How one session ended, for the server's log.
#[derive(Clone, Debug, PartialEq)]
pub struct SessionEnd {
    pub peer: SocketAddr,
    /// Views answered.
    pub frames: u64,
    /// Bytes sent to the client.
    pub bytes_out: u64,
    /// The session's own memory at its end: its refiners' (the landmarks and their
    /// node records are shared by every session).
    pub memory: usize,
    /// The time to answer each view (the traversal and the batch's encoding), in order.
    pub answer_times: Vec<Duration>,
    /// The traversals' time for each view, over every landmark, in order.
    pub traversal_times: Vec<Duration>,
    /// The most front nodes one landmark's traversal evaluated for one view: at most
    /// 2N with the constant-time traversal (Zheng §4.4.3, N per pass).
    pub most_evaluated: usize,
    /// Nodes split and collapsed over every view and landmark (El-Sana's operations);
    /// in a truly selective session or one of blocks, the splits sent.
    pub operations: u64,
    /// Blocks sent unasked, on idle time (a session of blocks; 0 in others).
    pub predicted_blocks: u64,
    /// Why the server closed it; `None` when the client said BYE or closed.
    pub reason: Option<String>,
}

/// A server bound to its address, not yet accepting.
pub struct StreamServer {
    listener: TcpListener,
    shared: Arc<Shared>,
    config: ServerConfig,
}

/// What every session reads and none changes.
struct Shared {
    landmarks: Vec<Landmark>,
    /// A refiner per landmark at its base mesh, which each session's are made from,
    /// sharing its node records.
    templates: Vec<Refiner<'static>>,
    /// WELCOME, encoded once.
    welcome: Vec<u8>,
    /// The landmarks' vertex hierarchies, made for the first truly selective session
    /// (or why they cannot be).
    selective: OnceLock<Result<Selective, String>>,
    /// The levels of a block, as the server's configuration gives them.
    block_levels: u8,
}

/// The truly selective schemes' shared part: each landmark's source, and
/// SELECTIVE-WELCOME encoded once; BLOCKS-WELCOME once the first session of blocks
/// comes.
struct Selective {
    sources: Vec<SelectiveSource>,
    welcome: Vec<u8>,
    blocks_welcome: OnceLock<Vec<u8>>,
}

impl Shared {
    fn selective(&self) -> Result<&Selective, StreamError> {
        let made = self.selective.get_or_init(|| {
            let sources = self
                .landmarks
                .iter()
                .map(|l| {
                    SelectiveSource::new(&l.pm, &l.dag).map_err(|e| {
                        format!(
                            "landmark {} cannot be streamed truly selectively: {e}",
                            l.id
                        )
                    })
                })
                .collect::<Result<Vec<_>, String>>()?;
            let welcome = Message::SelectiveWelcome(self.selective_objects(&sources)).encode();
            Ok(Selective {
                sources,
                welcome,
                blocks_welcome: OnceLock::new(),
            })
        });
        made.as_ref()
            .map_err(|why| StreamError::Malformed(why.clone()))
    }

    /// Each landmark's id and its base mesh over `sources`' roots.
    fn selective_objects(&self, sources: &[SelectiveSource]) -> Vec<SelectiveObject> {
        self.landmarks
            .iter()
            .zip(sources)
            .map(|(l, s)| SelectiveObject {
                id: l.id,
                base: s.base(),
            })
            .collect()
    }
}

/// A server accepting on a thread of its own; dropped, it stops accepting (sessions
/// under way run to their end).
pub struct RunningServer {
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    ends: mpsc::Receiver<SessionEnd>,
}

impl StreamServer {
    /// Binds `addr` for `landmarks` (an empty list is refused: nothing to stream).
    pub fn bind(
        addr: impl ToSocketAddrs,
        landmarks: Vec<Landmark>,
        config: ServerConfig,
    ) -> Result<StreamServer, StreamError> {
        if landmarks.is_empty() {
            return Err(StreamError::Malformed(
                "a stream server needs at least one landmark to stream".into(),
            ));
        }
        if config.block_levels == 0 {
            return Err(StreamError::Malformed(
                "blocks of 0 levels: give at least 1".into(),
            ));
        }
        if config.max_sessions == 0 {
            return Err(StreamError::Malformed(
                "at most 0 sessions at once: give at least 1".into(),
            ));
        }
        if config.session_budget < MIN_SESSION_BUDGET {
            return Err(StreamError::Malformed(format!(
                "a session budget of {} bytes, below the {MIN_SESSION_BUDGET} a session \
                 needs to read its messages",
                config.session_budget
            )));
        }
        if landmarks.len() > MAX_OBJECTS {
            return Err(StreamError::Malformed(format!(
                "{} landmarks, above the {MAX_OBJECTS} a session streams",
                landmarks.len()
            )));
        }
        for l in &landmarks {
            if l.pm.splits.len() != l.dag.split_count() || l.pm.splits.len() > u32::MAX as usize {
                return Err(StreamError::Malformed(format!(
                    "landmark {}: a DAG of {} splits over a progressive mesh of {}",
                    l.id,
                    l.dag.split_count(),
                    l.pm.splits.len()
                )));
            }
        }
        let templates = landmarks
            .iter()
            .map(|l| Refiner::shared(l.pm.clone(), l.dag.clone()))
            .collect::<Result<Vec<_>, _>>()?;
        let welcome = welcome(&landmarks).encode();
        Ok(StreamServer {
            listener: TcpListener::bind(addr)?,
            shared: Arc::new(Shared {
                landmarks,
                templates,
                welcome,
                selective: OnceLock::new(),
                block_levels: config.block_levels,
            }),
            config,
        })
    }

    /// The address it listens on.
    pub fn local_addr(&self) -> io::Result<SocketAddr> {
        self.listener.local_addr()
    }

    /// Bytes every session shares besides the landmarks' progressive meshes and DAGs:
    /// each DAG node's record, made once per landmark rather than once per session.
    pub fn shared_memory(&self) -> usize {
        self.shared
            .templates
            .iter()
            .map(Refiner::node_records_memory)
            .sum()
    }

    /// Accepts clients on a thread of its own, a session thread each; each session's
    /// end comes out of [`RunningServer::ends`].
    pub fn spawn(self) -> Result<RunningServer, StreamError> {
        let addr = self.listener.local_addr()?;
        self.listener.set_nonblocking(true)?;
        let stop = Arc::new(AtomicBool::new(false));
        let (tx, ends) = mpsc::channel();
        let flag = stop.clone();
        thread::Builder::new()
            .name("stream-accept".into())
            .spawn(move || self.accept_until(&flag, &tx))?;
        Ok(RunningServer { addr, stop, ends })
    }

    /// One session, on the caller's thread, to its end: the client's messages read
    /// from `input`, the server's written to `output`. What each accepted client's
    /// thread runs over its connection once its idle timeout is set, open to any byte
    /// stream (a test's or a fuzzer's bytes). `peer` names the client in its end.
    ///
    /// A session of blocks reads `input` on a thread of its own (so that it can tell
    /// the client's silence), and returns once that thread is done: when `input` ends
    /// or fails after the session's end.
    ///
    /// ```
    /// use std::sync::Arc;
    /// use flaneur::lod::{Dag, DagConstruction, ProgressiveMesh};
    /// use flaneur_stream::{Landmark, ServerConfig, StreamServer};
    ///
    /// let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
    /// let dag = Dag::build(&pm, DagConstruction::MiniRedundant)?;
    /// let bunny = Landmark { id: 1, pm: Arc::new(pm), dag: Arc::new(dag) };
    /// let server = StreamServer::bind("127.0.0.1:0", vec![bunny], ServerConfig::default())?;
    /// // Bytes that are not a message: the session is refused, and says why.
    /// let (input, mut output) = (&[1u8, 0, 0, 0, 0x7f][..], Vec::new());
    /// let end = server.serve(input, &mut output, "127.0.0.1:9".parse().unwrap());
    /// assert!(end.reason.unwrap().contains("0x7f"));
    /// assert!(!output.is_empty(), "REFUSED, with the reason");
    /// # Ok::<(), flaneur_stream::StreamError>(())
    /// ```
    pub fn serve(
        &self,
        input: impl Read + Send,
        output: impl Write,
        peer: SocketAddr,
    ) -> SessionEnd {
        serve((input, output), peer, &self.shared, self.config, &|| {})
    }

    fn accept_until(&self, stop: &AtomicBool, ends: &mpsc::Sender<SessionEnd>) {
        let active = Arc::new(AtomicUsize::new(0));
        let mut refused = Refused::default();
        while !stop.load(Ordering::Relaxed) {
            refused.drain();
            match self.listener.accept() {
                Ok((stream, peer))
                    if active.load(Ordering::Acquire) >= self.config.max_sessions =>
                {
                    let why = format!(
                        "the server is serving its most sessions at once ({}): try again later",
                        self.config.max_sessions
                    );
                    refused.refuse(stream, &why);
                    let _ = ends.send(session::ended(peer, None, Some(why)));
                }
                Ok((stream, peer)) => {
                    let (shared, config, log) = (self.shared.clone(), self.config, ends.clone());
                    // Counted before the thread starts, so that the next accept sees it.
                    let slot = Slot::take(&active);
                    let spawned =
                        thread::Builder::new()
                            .name(format!("stream-{peer}"))
                            .spawn(move || {
                                let end = session(stream, peer, &shared, config);
                                // Free before the end is logged: whoever reads the log
                                // may connect again at once.
                                drop(slot);
                                let _ = log.send(end);
                            });
                    if let Err(e) = spawned {
                        let why = format!("no thread for the session: {e}");
                        let _ = ends.send(session::ended(peer, None, Some(why)));
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    thread::sleep(Duration::from_millis(5))
                }
                Err(_) => thread::sleep(Duration::from_millis(50)),
            }
        }
    }
}

/// A session's place among [`ServerConfig::max_sessions`], given back when dropped:
/// when its thread ends, however it ends, or with the closure of a thread that could
/// not start.
struct Slot(Arc<AtomicUsize>);

impl Slot {
    fn take(active: &Arc<AtomicUsize>) -> Slot {
        active.fetch_add(1, Ordering::AcqRel);
        Slot(active.clone())
    }
}

impl Drop for Slot {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::AcqRel);
    }
}

/// Connections refused past the sessions' limit, each told why and kept open a little
/// while, its input read and thrown away: a connection closed with a HELLO unread is
/// reset, which may reach the client before it reads the reason.
#[derive(Default)]
struct Refused(Vec<(TcpStream, Instant)>);

impl Refused {
    /// How long a refused connection is kept for its client to read why.
    const LINGER: Duration = Duration::from_secs(2);
    /// The most refused connections kept at once; past them, the oldest is closed.
    const MOST: usize = 256;

    /// Tells `stream`'s client `why` and keeps the connection.
    fn refuse(&mut self, stream: TcpStream, why: &str) {
        // A refusal is a few dozen bytes into an empty send buffer: it never waits.
        let told = stream.set_nonblocking(true).is_ok()
            && send(&mut &stream, &Message::Refused(why.into())).is_ok()
            && stream.shutdown(Shutdown::Write).is_ok();
        if !told {
            return;
        }
        if self.0.len() >= Self::MOST {
            self.0.remove(0);
        }
        self.0.push((stream, Instant::now()));
    }

    /// Reads what the refused clients sent, and closes those that closed, failed, or
    /// were kept long enough.
    fn drain(&mut self) {
        let mut scratch = [0u8; 4096];
        self.0.retain(|(stream, since)| {
            if since.elapsed() > Self::LINGER {
                return false;
            }
            loop {
                match (&*stream).read(&mut scratch) {
                    Ok(0) => return false,
                    Ok(_) => continue,
                    Err(e) if e.kind() == io::ErrorKind::WouldBlock => return true,
                    Err(_) => return false,
                }
            }
        });
    }
}

impl RunningServer {
    /// Where clients connect.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// The ends of the sessions so far, as they come.
    pub fn ends(&self) -> &mpsc::Receiver<SessionEnd> {
        &self.ends
    }
}

impl Drop for RunningServer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

/// WELCOME for `landmarks`.
fn welcome(landmarks: &[Landmark]) -> Message {
    Message::Welcome(
        landmarks
            .iter()
            .map(|l| WelcomeObject {
                id: l.id,
                splits: l.pm.splits.len() as u32,
                base: l.pm.base.clone(),
            })
            .collect(),
    )
}
