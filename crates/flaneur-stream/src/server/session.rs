//! One client's session, from HELLO to its end: the protocol's dialogue (Zheng's DAG
//! scheme and the truly selective ones here, El-Sana's blocks in `block_session`), what
//! the session refines with and what it has done, and how it ended.

use std::io::{self, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpStream};
use std::time::Duration;

use glam::Vec3;

use super::block_session::{self, BlockStreams};
use super::{ServerConfig, SessionEnd, Shared};
use crate::error::StreamError;
use crate::protocol::{
    receive, receive_within, send, HeldLeaves, HeldNodes, Hello, Message, NodeSplit, ObjectUpdates,
    ObjectVsplits, Scheme, ViewPacket, MAX_N, MAX_RESUME, MAX_TO_SERVER,
};
use flaneur::lod::{Criteria, RefineParams, Refiner, SelectiveServer, SelectiveSource, View};

/// A session's state: its HELLO, what it refines with, what it has done.
pub(super) struct Session<'a> {
    pub(super) hello: Hello,
    pub(super) streams: Streams<'a>,
    pub(super) last_frame: Option<u32>,
    pub(super) frames: u64,
    pub(super) bytes_out: u64,
    pub(super) answer_times: Vec<Duration>,
    pub(super) traversal_times: Vec<Duration>,
    pub(super) most_evaluated: usize,
    pub(super) operations: u64,
    pub(super) predicted_blocks: u64,
}

/// What a session refines with, by its scheme.
pub(super) enum Streams<'a> {
    /// One refiner per landmark.
    Dag(Vec<Refiner<'static>>),
    /// Each landmark's source and the session's front of what it sent.
    Selective(&'a [SelectiveSource], Vec<SelectiveServer>),
    /// Each landmark's source and the session's blocks sent.
    Blocks(BlockStreams<'a>),
}

impl Streams<'_> {
    /// The session's own bytes.
    pub(super) fn memory(&self) -> usize {
        match self {
            Streams::Dag(refiners) => refiners.iter().map(Refiner::memory).sum(),
            Streams::Selective(_, servers) => servers.iter().map(SelectiveServer::memory).sum(),
            Streams::Blocks(blocks) => blocks.memory(),
        }
    }
}

/// Runs one TCP client's session to its end.
pub(super) fn session(
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
pub(super) fn ended(
    peer: SocketAddr,
    s: Option<Session<'_>>,
    reason: Option<String>,
) -> SessionEnd {
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
pub(super) fn serve<R: Read + Send, W: Write>(
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
        match receive_held(input, bound, config.session_budget)? {
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

/// Reads the client's next frame, of at most `bound` bytes (the protocol's bound for
/// it) and at most `budget` (what the session may hold of it).
pub(super) fn receive_held(
    input: &mut impl Read,
    bound: usize,
    budget: usize,
) -> Result<Option<(Message, usize)>, StreamError> {
    if budget < bound {
        let why = "bytes a session may hold on this server (its memory budget per session)";
        receive_within(input, budget, why)
    } else {
        receive(input, bound)
    }
}

/// A write that timed out is a client that stopped reading.
pub(super) fn stalled(e: StreamError) -> StreamError {
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

pub(super) fn out_of_place(wanted: &str, got: &Message) -> StreamError {
    StreamError::Malformed(format!("{} where {wanted} was due", got.kind()))
}

/// Checks that each object of a RESUME (`what`) is in the session's `objects` and
/// named once, and hands each to `restore` with its place.
pub(super) fn each_once<T>(
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
    pub(super) fn follows(&self, kind: &str, frame: u32) -> Result<(), StreamError> {
        match self.last_frame.filter(|&l| frame <= l) {
            Some(last) => Err(StreamError::Malformed(format!(
                "{kind} of frame {frame} after frame {last}: frames must increase"
            ))),
            None => Ok(()),
        }
    }

    /// The view a message of the session's gives: eye, aim-at point, its HELLO's cone.
    pub(super) fn view(&self, eye: [f32; 3], aim: [f32; 3]) -> Result<View, StreamError> {
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
