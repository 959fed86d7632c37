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

use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::thread;
use std::time::Duration;

use glam::Vec3;

use crate::error::StreamError;
use crate::landmark::Landmark;
use crate::protocol::{
    receive, send, HeldNodes, Hello, Message, NodeSplit, ObjectUpdates, ViewPacket, WelcomeObject,
    MAX_N, MAX_OBJECTS, MAX_RESUME, MAX_TO_SERVER,
};
use flaneur::lod::{Criteria, RefineParams, Refiner, View};

/// How a server treats its sessions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ServerConfig {
    /// A session that sends nothing for this long, or does not read what it is sent
    /// for this long (a stalled client, whose batches fill the connection), is closed.
    pub idle_timeout: Duration,
}

impl Default for ServerConfig {
    fn default() -> ServerConfig {
        ServerConfig {
            idle_timeout: Duration::from_secs(60),
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
    /// Nodes split and collapsed over every view and landmark (El-Sana's operations).
    pub operations: u64,
    /// Why the server closed it; `None` when the client said BYE or closed.
    pub reason: Option<String>,
}

/// A server bound to its address, not yet accepting.
pub struct StreamServer {
    listener: TcpListener,
    landmarks: Arc<[Landmark]>,
    /// A refiner per landmark at its base mesh, which each session's are made from,
    /// sharing its node records.
    templates: Arc<[Refiner<'static>]>,
    config: ServerConfig,
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
        Ok(StreamServer {
            listener: TcpListener::bind(addr)?,
            landmarks: landmarks.into(),
            templates: templates.into(),
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
        self.templates
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
    pub fn serve(&self, input: impl Read, output: impl Write, peer: SocketAddr) -> SessionEnd {
        let welcome = welcome(&self.landmarks).encode();
        serve(
            (input, output),
            peer,
            &self.templates,
            &welcome,
            self.config,
        )
    }

    fn accept_until(&self, stop: &AtomicBool, ends: &mpsc::Sender<SessionEnd>) {
        let welcome = Arc::new(welcome(&self.landmarks).encode());
        while !stop.load(Ordering::Relaxed) {
            match self.listener.accept() {
                Ok((stream, peer)) => {
                    let (templates, welcome) = (self.templates.clone(), welcome.clone());
                    let (config, ends) = (self.config, ends.clone());
                    let _ =
                        thread::Builder::new()
                            .name(format!("stream-{peer}"))
                            .spawn(move || {
                                let end = session(stream, peer, &templates, &welcome, config);
                                let _ = ends.send(end);
                            });
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    thread::sleep(Duration::from_millis(5))
                }
                Err(_) => thread::sleep(Duration::from_millis(50)),
            }
        }
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

/// A session's state: its HELLO, one refiner per landmark, what it has done.
struct Session {
    hello: Hello,
    refiners: Vec<Refiner<'static>>,
    last_frame: Option<u32>,
    frames: u64,
    bytes_out: u64,
    answer_times: Vec<Duration>,
    traversal_times: Vec<Duration>,
    most_evaluated: usize,
    operations: u64,
}

/// Runs one TCP client's session to its end.
fn session(
    stream: TcpStream,
    peer: SocketAddr,
    templates: &[Refiner<'static>],
    welcome: &[u8],
    config: ServerConfig,
) -> SessionEnd {
    let set_up = stream
        .set_nonblocking(false)
        .and_then(|()| stream.set_read_timeout(Some(config.idle_timeout)))
        .and_then(|()| stream.set_write_timeout(Some(config.idle_timeout)))
        .and_then(|()| stream.set_nodelay(true));
    match set_up {
        Ok(()) => serve((&stream, &stream), peer, templates, welcome, config),
        Err(e) => ended(
            peer,
            None,
            Some(format!("the connection could not be set up: {e}")),
        ),
    }
}

/// How a session of `peer` ended, `s` what it did (`None` before WELCOME).
fn ended(peer: SocketAddr, s: Option<Session>, reason: Option<String>) -> SessionEnd {
    let Some(s) = s else {
        return SessionEnd {
            peer,
            frames: 0,
            bytes_out: 0,
            memory: 0,
            answer_times: Vec::new(),
            traversal_times: Vec::new(),
            most_evaluated: 0,
            operations: 0,
            reason,
        };
    };
    SessionEnd {
        peer,
        frames: s.frames,
        bytes_out: s.bytes_out,
        memory: s.refiners.iter().map(Refiner::memory).sum(),
        answer_times: s.answer_times,
        traversal_times: s.traversal_times,
        most_evaluated: s.most_evaluated,
        operations: s.operations,
        reason,
    }
}

/// Runs one session over `stream` (its input, its output) to its end.
fn serve<R: Read, W: Write>(
    mut stream: (R, W),
    peer: SocketAddr,
    templates: &[Refiner<'static>],
    welcome: &[u8],
    config: ServerConfig,
) -> SessionEnd {
    let mut s = None;
    let reason = run(&mut stream, templates, welcome, &mut s).err().map(|e| {
        let why = match &e {
            StreamError::Io(io)
                if matches!(
                    io.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                ) =>
            {
                format!("idle for {:?}", config.idle_timeout)
            }
            StreamError::Stalled => format!(
                "not reading for {:?}: its batches filled the connection",
                config.idle_timeout
            ),
            e => e.to_string(),
        };
        // The client hears why, if it still listens.
        let _ = send(&mut stream.1, &Message::Refused(why.clone()));
        why
    });
    ended(peer, s, reason)
}

/// The session's loop; `Ok` when the client said BYE or closed.
fn run<R: Read, W: Write>(
    (input, output): &mut (R, W),
    templates: &[Refiner<'static>],
    welcome: &[u8],
    state: &mut Option<Session>,
) -> Result<(), StreamError> {
    let hello = match receive(input, MAX_TO_SERVER)? {
        Some((Message::Hello(h), _)) => h,
        Some((m, _)) => return Err(out_of_place("HELLO", &m)),
        None => return Ok(()),
    };
    if !(hello.fov.is_finite() && hello.fov > 0.0 && hello.fov < std::f32::consts::PI) {
        return Err(StreamError::Malformed(format!(
            "HELLO: a view cone of {} radians; it must be within (0, π)",
            hello.fov
        )));
    }
    let refiners = templates
        .iter()
        .map(Refiner::fresh)
        .collect::<Result<Vec<_>, _>>()?;
    output.write_all(welcome).map_err(|e| stalled(e.into()))?;
    let s = state.insert(Session {
        hello,
        refiners,
        last_frame: None,
        frames: 0,
        bytes_out: welcome.len() as u64,
        answer_times: Vec::new(),
        traversal_times: Vec::new(),
        most_evaluated: 0,
        operations: 0,
    });
    // The first message after WELCOME may be a RESUME, the only long one.
    let mut first = true;
    loop {
        let bound = if first { MAX_RESUME } else { MAX_TO_SERVER };
        match receive(input, bound)? {
            Some((
                Message::Resume {
                    next_frame,
                    objects,
                },
                _,
            )) if first => {
                s.resume(next_frame, objects)?;
            }
            Some((Message::View(v), _)) => {
                let started = std::time::Instant::now();
                let batch = s.answer(&v)?;
                s.answer_times.push(started.elapsed());
                s.bytes_out += send(output, &batch).map_err(stalled)? as u64;
                s.frames += 1;
            }
            Some((Message::Bye, _)) | None => return Ok(()),
            Some((m, _)) => return Err(out_of_place("VIEW or BYE", &m)),
        }
        first = false;
    }
}

/// A write that timed out is a client that stopped reading.
fn stalled(e: StreamError) -> StreamError {
    match e {
        StreamError::Io(io)
            if matches!(
                io.kind(),
                io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
            ) =>
        {
            StreamError::Stalled
        }
        e => e,
    }
}

fn out_of_place(wanted: &str, got: &Message) -> StreamError {
    let kind = match got {
        Message::Hello(_) => "HELLO",
        Message::View(_) => "VIEW",
        Message::Bye => "BYE",
        Message::Resume { .. } => "RESUME",
        Message::Welcome(_) => "WELCOME",
        Message::Batch { .. } => "BATCH",
        Message::Refused(_) => "REFUSED",
    };
    StreamError::Malformed(format!("{kind} where {wanted} was due"))
}

impl Session {
    /// The session a resuming client left: each object's refiner with the nodes it
    /// holds split, and the frames it may send from `next_frame` on.
    fn resume(&mut self, next_frame: u32, objects: Vec<HeldNodes>) -> Result<(), StreamError> {
        let mut seen = vec![false; self.refiners.len()];
        for o in objects {
            let refiner = self.refiners.get_mut(o.index as usize).ok_or_else(|| {
                StreamError::Malformed(format!(
                    "RESUME: object {}, not in WELCOME's {}",
                    o.index,
                    seen.len()
                ))
            })?;
            if std::mem::replace(&mut seen[o.index as usize], true) {
                return Err(StreamError::Malformed(format!(
                    "RESUME: object {} named twice",
                    o.index
                )));
            }
            refiner
                .restore(&o.nodes)
                .map_err(|e| StreamError::Malformed(format!("RESUME: object {}: {e}", o.index)))?;
        }
        self.last_frame = next_frame.checked_sub(1);
        Ok(())
    }

    /// The BATCH for view `v`: each landmark refined for it, its collapses then its
    /// splits with their vertex splits.
    fn answer(&mut self, v: &ViewPacket) -> Result<Message, StreamError> {
        if let Some(last) = self.last_frame.filter(|&l| v.frame <= l) {
            return Err(StreamError::Malformed(format!(
                "VIEW of frame {} after frame {last}: frames must increase",
                v.frame
            )));
        }
        if !(1..=MAX_N).contains(&v.n) {
            return Err(StreamError::Malformed(format!(
                "VIEW of frame {}: N = {}, not within 1 to {MAX_N}",
                v.frame, v.n
            )));
        }
        let eye = Vec3::from(v.eye);
        let view = View::new(eye, Vec3::from(v.aim) - eye, self.hello.fov)?;
        let params = RefineParams {
            traversal: self.hello.traversal,
            tau: v.tau,
            budget: v
                .budget_mode
                .then_some(self.hello.budget)
                .flatten()
                .map(|b| b as usize),
            max_work: v.n as usize,
            criteria: Criteria {
                out_of_view: self.hello.out_of_view,
                back_face: self.hello.back_face,
            },
        };
        let mut objects = Vec::new();
        let mut traversal = Duration::ZERO;
        for (index, refiner) in self.refiners.iter_mut().enumerate() {
            let stats = refiner.refine(&view, &params)?.stats;
            traversal += stats.traversal;
            self.most_evaluated = self.most_evaluated.max(stats.evaluated());
            self.operations += stats.updates() as u64;
            let mut updates = ObjectUpdates {
                index: index as u32,
                ..Default::default()
            };
            let (pm, dag) = (refiner.progressive_mesh(), refiner.dag());
            for op in refiner.operators() {
                if op.split {
                    let run = dag.splits(op.node);
                    updates.splits.push(NodeSplit {
                        node: op.node,
                        first: run.start as u32,
                        run: pm.splits[run].to_vec(),
                    });
                } else {
                    updates.collapses.push(op.node);
                }
            }
            if !(updates.collapses.is_empty() && updates.splits.is_empty()) {
                objects.push(updates);
            }
        }
        self.last_frame = Some(v.frame);
        self.traversal_times.push(traversal);
        Ok(Message::Batch {
            frame: v.frame,
            objects,
        })
    }
}
