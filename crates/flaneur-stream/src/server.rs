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

mod block_session;

use std::io::{self, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, OnceLock};
use std::thread;
use std::time::Duration;

use glam::Vec3;

use crate::error::StreamError;
use crate::landmark::Landmark;
use crate::protocol::{
    receive, send, HeldLeaves, HeldNodes, Hello, Message, NodeSplit, ObjectUpdates, ObjectVsplits,
    Scheme, SelectiveObject, ViewPacket, WelcomeObject, MAX_N, MAX_OBJECTS, MAX_RESUME,
    MAX_TO_SERVER,
};
use block_session::BlockStreams;
use flaneur::lod::{Criteria, RefineParams, Refiner, SelectiveServer, SelectiveSource, View};

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
}

impl Default for ServerConfig {
    fn default() -> ServerConfig {
        ServerConfig {
            idle_timeout: Duration::from_secs(60),
            block_levels: 2,
            idle: Duration::from_millis(10),
            predict_blocks: 8,
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
        while !stop.load(Ordering::Relaxed) {
            match self.listener.accept() {
                Ok((stream, peer)) => {
                    let (shared, config, ends) = (self.shared.clone(), self.config, ends.clone());
                    let _ =
                        thread::Builder::new()
                            .name(format!("stream-{peer}"))
                            .spawn(move || {
                                let _ = ends.send(session(stream, peer, &shared, config));
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

/// A session's state: its HELLO, what it refines with, what it has done.
struct Session<'a> {
    hello: Hello,
    streams: Streams<'a>,
    last_frame: Option<u32>,
    frames: u64,
    bytes_out: u64,
    answer_times: Vec<Duration>,
    traversal_times: Vec<Duration>,
    most_evaluated: usize,
    operations: u64,
    predicted_blocks: u64,
}

/// What a session refines with, by its scheme.
enum Streams<'a> {
    /// One refiner per landmark.
    Dag(Vec<Refiner<'static>>),
    /// Each landmark's source and the session's front of what it sent.
    Selective(&'a [SelectiveSource], Vec<SelectiveServer>),
    /// Each landmark's source and the session's blocks sent.
    Blocks(BlockStreams<'a>),
}

impl Streams<'_> {
    /// The session's own bytes.
    fn memory(&self) -> usize {
        match self {
            Streams::Dag(refiners) => refiners.iter().map(Refiner::memory).sum(),
            Streams::Selective(_, servers) => servers.iter().map(SelectiveServer::memory).sum(),
            Streams::Blocks(blocks) => blocks.memory(),
        }
    }
}

/// Runs one TCP client's session to its end.
fn session(
    stream: TcpStream,
    peer: SocketAddr,
    shared: &Shared,
    config: ServerConfig,
) -> SessionEnd {
    let set_up = stream
        .set_nonblocking(false)
        .and_then(|()| stream.set_read_timeout(Some(config.idle_timeout)))
        .and_then(|()| stream.set_write_timeout(Some(config.idle_timeout)))
        .and_then(|()| stream.set_nodelay(true));
    match set_up {
        // A session of blocks reads on a thread of its own: a shut read side ends it.
        Ok(()) => serve((&stream, &stream), peer, shared, config, &|| {
            let _ = stream.shutdown(Shutdown::Read);
        }),
        Err(e) => ended(
            peer,
            None,
            Some(format!("the connection could not be set up: {e}")),
        ),
    }
}

/// How a session of `peer` ended, `s` what it did (`None` before WELCOME).
fn ended(peer: SocketAddr, s: Option<Session<'_>>, reason: Option<String>) -> SessionEnd {
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
            predicted_blocks: 0,
            reason,
        };
    };
    SessionEnd {
        peer,
        frames: s.frames,
        bytes_out: s.bytes_out,
        memory: s.streams.memory(),
        answer_times: s.answer_times,
        traversal_times: s.traversal_times,
        most_evaluated: s.most_evaluated,
        operations: s.operations,
        predicted_blocks: s.predicted_blocks,
        reason,
    }
}

/// Runs one session over `stream` (its input, its output) to its end; `unblock` ends
/// a read of the input under way (a session of blocks calls it at its end).
fn serve<R: Read + Send, W: Write>(
    mut stream: (R, W),
    peer: SocketAddr,
    shared: &Shared,
    config: ServerConfig,
    unblock: &dyn Fn(),
) -> SessionEnd {
    let mut s = None;
    let end = run(&mut stream, shared, config, &mut s, unblock);
    let reason = end.err().map(|e| {
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
fn run<'a, R: Read + Send, W: Write>(
    (input, output): &mut (R, W),
    shared: &'a Shared,
    config: ServerConfig,
    state: &mut Option<Session<'a>>,
    unblock: &dyn Fn(),
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
    let (streams, welcome) = match hello.scheme {
        Scheme::Dag => {
            let refiners = shared
                .templates
                .iter()
                .map(Refiner::fresh)
                .collect::<Result<Vec<_>, _>>()?;
            (Streams::Dag(refiners), &shared.welcome[..])
        }
        Scheme::Selective | Scheme::CutVertex => {
            let selective = shared.selective()?;
            let criteria = Criteria {
                out_of_view: hello.out_of_view,
                back_face: hello.back_face,
            };
            let servers = selective
                .sources
                .iter()
                .map(|source| {
                    let server = SelectiveServer::new(source).with_criteria(criteria);
                    match hello.scheme {
                        Scheme::CutVertex => server.cut_vertex_only(),
                        _ => server,
                    }
                })
                .collect();
            (
                Streams::Selective(&selective.sources, servers),
                &selective.welcome[..],
            )
        }
        Scheme::Blocks => {
            let selective = shared.selective()?;
            let streams = BlockStreams::new(&selective.sources, &hello, config.block_levels)?;
            (Streams::Blocks(streams), shared.blocks_welcome(selective))
        }
    };
    output.write_all(welcome).map_err(|e| stalled(e.into()))?;
    let s = state.insert(Session {
        hello,
        streams,
        last_frame: None,
        frames: 0,
        bytes_out: welcome.len() as u64,
        answer_times: Vec::new(),
        traversal_times: Vec::new(),
        most_evaluated: 0,
        operations: 0,
        predicted_blocks: 0,
    });
    if let Streams::Blocks(_) = s.streams {
        return block_session::dialogue(input, output, s, config, unblock);
    }
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
            Some((
                Message::ResumeLeaves {
                    next_frame,
                    objects,
                },
                _,
            )) if first => {
                s.resume_leaves(next_frame, objects)?;
            }
            Some((Message::View(v), _)) => {
                let started = std::time::Instant::now();
                let batch = s.answer(&v)?;
                s.answer_times.push(started.elapsed());
                s.bytes_out += send(output, &batch).map_err(stalled)? as u64;
                s.frames += 1;
            }
            Some((Message::Bye, _)) | None => return Ok(()),
            Some((Message::Switch(_), _)) => return Err(block_session::switch_refused()),
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
    StreamError::Malformed(format!("{} where {wanted} was due", got.kind()))
}

/// Checks that each object of a RESUME (`what`) is in the session's `objects` and
/// named once, and hands each to `restore` with its place.
fn each_once<T>(
    what: &str,
    objects: usize,
    held: Vec<(u32, T)>,
    mut restore: impl FnMut(usize, T) -> Result<(), String>,
) -> Result<(), StreamError> {
    let mut seen = vec![false; objects];
    for (index, o) in held {
        let Some(seen) = seen.get_mut(index as usize) else {
            return Err(StreamError::Malformed(format!(
                "{what}: object {index}, not in WELCOME's {objects}"
            )));
        };
        if std::mem::replace(seen, true) {
            return Err(StreamError::Malformed(format!(
                "{what}: object {index} named twice"
            )));
        }
        restore(index as usize, o)
            .map_err(|e| StreamError::Malformed(format!("{what}: object {index}: {e}")))?;
    }
    Ok(())
}

impl Session<'_> {
    /// The session a resuming client left: each object's refiner with the nodes it
    /// holds split, and the frames it may send from `next_frame` on.
    fn resume(&mut self, next_frame: u32, objects: Vec<HeldNodes>) -> Result<(), StreamError> {
        let Streams::Dag(refiners) = &mut self.streams else {
            return Err(StreamError::Malformed(
                "RESUME in a truly selective session: it resumes with RESUME-LEAVES".into(),
            ));
        };
        let held = objects.into_iter().map(|o| (o.index, o.nodes)).collect();
        each_once("RESUME", refiners.len(), held, |k, nodes| {
            refiners[k].restore(&nodes).map_err(|e| e.to_string())
        })?;
        self.last_frame = next_frame.checked_sub(1);
        Ok(())
    }

    /// The truly selective session a resuming client left: each object's front of what
    /// was sent, from the leaves the client holds.
    fn resume_leaves(
        &mut self,
        next_frame: u32,
        objects: Vec<HeldLeaves>,
    ) -> Result<(), StreamError> {
        let Streams::Selective(sources, servers) = &mut self.streams else {
            return Err(StreamError::Malformed(
                "RESUME-LEAVES in a session of Zheng's scheme: it resumes with RESUME".into(),
            ));
        };
        let held = objects.into_iter().map(|o| (o.index, o.leaves)).collect();
        each_once("RESUME-LEAVES", servers.len(), held, |k, leaves| {
            servers[k] = servers[k]
                .resume(&sources[k], &leaves)
                .map_err(|e| e.to_string())?;
            Ok(())
        })?;
        self.last_frame = next_frame.checked_sub(1);
        Ok(())
    }

    /// Refuses a message `kind` of `frame` that does not follow the last one's.
    fn follows(&self, kind: &str, frame: u32) -> Result<(), StreamError> {
        match self.last_frame.filter(|&l| frame <= l) {
            Some(last) => Err(StreamError::Malformed(format!(
                "{kind} of frame {frame} after frame {last}: frames must increase"
            ))),
            None => Ok(()),
        }
    }

    /// The view a message of the session's gives: eye, aim-at point, its HELLO's cone.
    fn view(&self, eye: [f32; 3], aim: [f32; 3]) -> Result<View, StreamError> {
        let eye = Vec3::from(eye);
        Ok(View::new(eye, Vec3::from(aim) - eye, self.hello.fov)?)
    }

    /// The answer to view `v`: a BATCH of each landmark's collapses then splits with
    /// their vertex splits, or in a truly selective session a VSPLITS.
    fn answer(&mut self, v: &ViewPacket) -> Result<Message, StreamError> {
        self.follows("VIEW", v.frame)?;
        if !(1..=MAX_N).contains(&v.n) {
            return Err(StreamError::Malformed(format!(
                "VIEW of frame {}: N = {}, not within 1 to {MAX_N}",
                v.frame, v.n
            )));
        }
        let view = self.view(v.eye, v.aim)?;
        let Session {
            hello,
            streams,
            traversal_times,
            most_evaluated,
            operations,
            ..
        } = self;
        let message = match streams {
            Streams::Dag(refiners) => {
                let (objects, traversal) =
                    answer_dag(refiners, hello, &view, v, most_evaluated, operations)?;
                traversal_times.push(traversal);
                Message::Batch {
                    frame: v.frame,
                    objects,
                }
            }
            Streams::Selective(sources, servers) => {
                if v.budget_mode {
                    return Err(StreamError::Malformed(format!(
                        "VIEW of frame {} in budget mode: the truly selective schemes \
                         have none",
                        v.frame
                    )));
                }
                let mut objects = Vec::new();
                let started = std::time::Instant::now();
                for (index, (source, server)) in sources.iter().zip(servers).enumerate() {
                    let packets = server.refine_at_most(source, &view, v.tau, v.n as usize)?;
                    *operations += packets.len() as u64;
                    if !packets.is_empty() {
                        objects.push(ObjectVsplits {
                            index: index as u32,
                            packets,
                        });
                    }
                }
                traversal_times.push(started.elapsed());
                Message::Vsplits {
                    frame: v.frame,
                    objects,
                }
            }
            Streams::Blocks(_) => return Err(block_session::view_refused()),
        };
        self.last_frame = Some(v.frame);
        Ok(message)
    }
}

/// Zheng's scheme's answer to `v` (seen as `view`) under `hello`: each landmark's part,
/// and the traversals' time; the most nodes evaluated and the operations counted in.
fn answer_dag(
    refiners: &mut [Refiner<'static>],
    hello: &Hello,
    view: &View,
    v: &ViewPacket,
    most_evaluated: &mut usize,
    operations: &mut u64,
) -> Result<(Vec<ObjectUpdates>, Duration), StreamError> {
    let params = RefineParams {
        traversal: hello.traversal,
        tau: v.tau,
        budget: v
            .budget_mode
            .then_some(hello.budget)
            .flatten()
            .map(|b| b as usize),
        max_work: v.n as usize,
        criteria: Criteria {
            out_of_view: hello.out_of_view,
            back_face: hello.back_face,
        },
    };
    let mut objects = Vec::new();
    let mut traversal = Duration::ZERO;
    for (index, refiner) in refiners.iter_mut().enumerate() {
        let stats = refiner.refine(view, &params)?.stats;
        traversal += stats.traversal;
        *most_evaluated = (*most_evaluated).max(stats.evaluated());
        *operations += stats.updates() as u64;
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
    Ok((objects, traversal))
}
