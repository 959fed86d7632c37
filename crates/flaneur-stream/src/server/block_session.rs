//! A session of El-Sana's view-dependence blocks (his client-server paper, §5–6): the
//! server's interface keeps per landmark the blocks it sent ([`BlockServer`]) over the
//! sources every session shares, and answers each SWITCH with one BLOCKS: it forgets
//! the blocks the client released (switch-up), then sends the blocks named down and
//! ahead that it had not sent, each after the blocks above it and with those the
//! partial order forces.
//!
//! Idle-time prediction (§6.2): when no message comes within [`ServerConfig::idle`]
//! of an answer, the session extrapolates the client's next view from the views of its
//! last two SWITCHes that differ (a view asked for over several rounds is one), one
//! step ahead (the first order of [`Predictor::Linear`], eye and aim-at point alike:
//! El-Sana tracks the motion's speed, velocity and tangent, and this follows the
//! velocity), and sends one BLOCKS flagged predicted of what that view will want, at
//! most [`ServerConfig::predict_blocks`] blocks asked for per landmark; then it waits
//! for the client as before. A client takes each block it does not hold and discards the
//! rest by name (§6.3), so a prediction that crosses a SWITCH on the wire is harmless:
//! what the SWITCH names that the prediction brought, the answer leaves out, and the
//! prediction, sent first, comes first.
//!
//! To tell the client's silence without tearing a frame half read, the session's
//! messages are read on a thread of their own into a channel of one message, which the
//! session waits on with a timeout. The channel's one place keeps a client that sends
//! faster than it is answered from having more than a message or two read ahead, as a
//! blocking read would. At the session's end the caller's `unblock` ends the reader's
//! read (on TCP, a shut read side), and the session returns once the reader is done.
//!
//! Departures: a session of blocks chooses them under both criteria (out-of-view and
//! back-face), as [`BlockServer`] and [`BlockClient`](flaneur::lod::BlockClient) do, so a
//! HELLO that asks otherwise is refused; and it does not resume (a client connects
//! afresh), El-Sana's clients keeping no session across connections either.
//!
//! A release may cross a prediction too (ours; §6.3 leaves it open): a client with a
//! bounded cache may drop a block while a predicted BLOCKS holding blocks below it is
//! on its way. The client saw every answer before its SWITCH, and drops blocks only
//! from the bottom of what it holds, so a block below a released one that the session
//! still counts as sent can only be one of the last prediction, sent after the last
//! answer and not yet seen: the session forgets it with the release, and the client,
//! which takes a predicted block only under a block it holds, discards it as it comes.
//! A block below a released one that was not in that prediction is the client's error,
//! and closes the session as [`BlockServer::release`] says.

use std::io::{Read, Write};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, SyncSender};
use std::thread;
use std::time::Instant;

use glam::Vec3;

use super::session::{each_once, out_of_place, receive_held, stalled, Session, Streams};
use super::{Selective, ServerConfig, Shared};
use crate::error::StreamError;
use crate::prediction::Predictor;
use crate::protocol::{Hello, Message, ObjectBlocks, Switch, MAX_SWITCH, MAX_TO_CLIENT};
use flaneur::lod::{Block, BlockServer, NodeName, SelectiveSource};

/// What the reader thread hands the session: a message, the end of the input (`None`),
/// or why it could not read one.
type Incoming = Result<Option<Message>, StreamError>;

/// A session of blocks' own state: each landmark's source and blocks sent, and the
/// views a prediction extrapolates.
pub(super) struct BlockStreams<'a> {
    sources: &'a [SelectiveSource],
    servers: Vec<BlockServer>,
    /// The last SWITCH's eye, aim-at point and τ.
    last: Option<(Vec3, Vec3, f32)>,
    /// The eye and aim-at point of the last SWITCH of another view before it.
    before: Option<(Vec3, Vec3)>,
    /// Per landmark, the tops of the blocks predicted since the last answer: those the
    /// client may not have seen when it sends its next SWITCH.
    unseen: Vec<Vec<NodeName>>,
}

impl<'a> BlockStreams<'a> {
    /// A session of blocks of `levels` levels over `sources`, for `hello`.
    pub(super) fn new(
        sources: &'a [SelectiveSource],
        hello: &Hello,
        levels: u8,
    ) -> Result<BlockStreams<'a>, StreamError> {
        if !(hello.out_of_view && hello.back_face) {
            return Err(StreamError::Malformed(
                "HELLO of the blocks scheme without both criteria: its blocks are chosen \
                 under out-of-view and back-face culling both"
                    .into(),
            ));
        }
        let servers = sources
            .iter()
            .map(|source| BlockServer::new(source, u32::from(levels)))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(BlockStreams {
            sources,
            unseen: vec![Vec::new(); servers.len()],
            servers,
            last: None,
            before: None,
        })
    }

    /// The session's own bytes (the sources are shared).
    pub(super) fn memory(&self) -> usize {
        self.servers.iter().map(BlockServer::memory).sum()
    }

    /// Landmark `k` forgets the blocks `released` names, and the blocks of the last
    /// prediction below them, which the client cannot have seen (the module's rule).
    fn release(&mut self, k: usize, released: &[NodeName]) -> flaneur::Result<()> {
        let below = |u: &NodeName| {
            released.iter().any(|top| {
                u.tree == top.tree
                    && u.depth() > top.depth()
                    && u.up(u.depth() - top.depth()) == *top
            })
        };
        let unseen = std::mem::take(&mut self.unseen[k]);
        let (crossed, still): (Vec<NodeName>, Vec<NodeName>) = unseen
            .into_iter()
            .filter(|u| !released.contains(u))
            .partition(below);
        self.unseen[k] = still;
        let forgotten: Vec<NodeName> = released.iter().cloned().chain(crossed).collect();
        self.servers[k].release(&self.sources[k], &forgotten)
    }
}

impl Shared {
    /// BLOCKS-WELCOME, encoded for the first session of blocks.
    pub(super) fn blocks_welcome<'a>(&self, selective: &'a Selective) -> &'a [u8] {
        selective.blocks_welcome.get_or_init(|| {
            Message::BlocksWelcome {
                levels: self.block_levels,
                objects: self.selective_objects(&selective.sources),
            }
            .encode()
        })
    }
}

/// Why a VIEW closes a session of blocks.
pub(super) fn view_refused() -> StreamError {
    StreamError::Malformed("VIEW in a session of blocks: it sends SWITCH".into())
}

/// Why a SWITCH closes a session of another scheme.
pub(super) fn switch_refused() -> StreamError {
    StreamError::Malformed(
        "SWITCH outside a session of blocks: this session's scheme sends VIEW".into(),
    )
}

/// Runs the session of blocks `s` from its first message after BLOCKS-WELCOME to its
/// end, its messages read from `input` on a thread of their own; `Ok` when the client
/// said BYE or closed. `unblock` ends a read of `input` under way.
pub(super) fn dialogue<R: Read + Send, W: Write>(
    input: &mut R,
    output: &mut W,
    s: &mut Session<'_>,
    config: ServerConfig,
    unblock: &dyn Fn(),
) -> Result<(), StreamError> {
    thread::scope(|scope| {
        let (tx, rx) = mpsc::sync_channel(1);
        let reader = thread::Builder::new()
            .name("stream-blocks-reader".into())
            .spawn_scoped(scope, move || {
                read_messages(input, &tx, config.session_budget)
            })?;
        let end = answer_until_bye(&rx, output, s, config);
        // The reader's next hand-over fails; a read under way ends.
        drop(rx);
        unblock();
        // Joined by hand: the scope's end waits for the reader's work, not for its
        // thread to be gone, whose thread-locals would outlive the session.
        let _ = reader.join();
        end
    })
}

/// Reads messages into `tx` until the input ends, fails or says BYE, or the session
/// stops taking them. The session holds up to three at once (one answered, one in
/// the channel, one being read), so each is at most a third of the session's `budget`.
fn read_messages(input: &mut impl Read, tx: &SyncSender<Incoming>, budget: usize) {
    loop {
        let next: Incoming = receive_held(input, MAX_SWITCH, budget / 3).map(|m| m.map(|(m, _)| m));
        let goes_on = matches!(&next, Ok(Some(m)) if !matches!(m, Message::Bye));
        if tx.send(next).is_err() || !goes_on {
            return;
        }
    }
}

/// The session's loop: each SWITCH answered, and after an answer, a prediction once
/// the client has been silent for the configured idle time.
fn answer_until_bye<W: Write>(
    rx: &Receiver<Incoming>,
    output: &mut W,
    s: &mut Session<'_>,
    config: ServerConfig,
) -> Result<(), StreamError> {
    let predicts = !config.idle.is_zero() && config.predict_blocks > 0;
    let mut answered = false;
    loop {
        let next = if answered && predicts {
            match rx.recv_timeout(config.idle) {
                Ok(next) => next,
                Err(RecvTimeoutError::Timeout) => {
                    answered = false;
                    if let Some(m) = s.predicted(config.predict_blocks)? {
                        s.bytes_out += send_blocks(output, &m)? as u64;
                    }
                    continue;
                }
                Err(RecvTimeoutError::Disconnected) => Ok(None),
            }
        } else {
            rx.recv().unwrap_or(Ok(None))
        };
        match next? {
            Some(Message::Switch(switch)) => {
                let started = Instant::now();
                let answer = s.switch(switch)?;
                s.answer_times.push(started.elapsed());
                s.bytes_out += send_blocks(output, &answer)? as u64;
                s.frames += 1;
                answered = true;
            }
            Some(Message::Bye) | None => return Ok(()),
            Some(Message::View(_)) => return Err(view_refused()),
            Some(m) => return Err(out_of_place("SWITCH or BYE", &m)),
        }
    }
}

/// Writes BLOCKS `m`: its bytes, or an `Err` when a client could not read it (past
/// [`MAX_TO_CLIENT`]: blocks asked for all at once of a very large landmark).
fn send_blocks<W: Write>(output: &mut W, m: &Message) -> Result<usize, StreamError> {
    let bytes = m.encode();
    if bytes.len() - 4 > MAX_TO_CLIENT {
        return Err(StreamError::Malformed(format!(
            "BLOCKS of {} bytes, above the {MAX_TO_CLIENT} a client reads: ask for fewer \
             blocks a SWITCH",
            bytes.len() - 4
        )));
    }
    output
        .write_all(&bytes)
        .and_then(|()| output.flush())
        .map_err(|e| stalled(e.into()))?;
    Ok(bytes.len())
}

/// The splits `objects`' blocks hold, and the blocks.
fn count(objects: &[ObjectBlocks]) -> (u64, u64) {
    let blocks = || objects.iter().flat_map(|o| &o.blocks);
    let packets: usize = blocks().map(|b: &Block| b.packets.len()).sum();
    (packets as u64, blocks().count() as u64)
}

impl Session<'_> {
    /// The answer to `switch`: per landmark, its releases forgotten, then the blocks it
    /// names down and ahead that were not sent.
    fn switch(&mut self, switch: Switch) -> Result<Message, StreamError> {
        self.follows("SWITCH", switch.frame)?;
        if !(switch.tau.is_finite() && switch.tau > 0.0) {
            return Err(StreamError::Malformed(format!(
                "SWITCH of frame {}: τ = {}, not a positive fraction of the viewport",
                switch.frame, switch.tau
            )));
        }
        // A view the session can predict from.
        self.view(switch.eye, switch.aim)?;
        let Streams::Blocks(b) = &mut self.streams else {
            unreachable!("a SWITCH is answered in a session of blocks")
        };
        let started = Instant::now();
        let mut objects = Vec::new();
        let parts = switch.objects.into_iter().map(|o| (o.index, o)).collect();
        each_once("SWITCH", b.servers.len(), parts, |k, o| {
            b.release(k, &o.released).map_err(|e| e.to_string())?;
            let tops: Vec<NodeName> = o.down.into_iter().chain(o.ahead).collect();
            let blocks = b.servers[k]
                .send(&b.sources[k], &tops)
                .map_err(|e| e.to_string())?;
            if !blocks.is_empty() {
                objects.push(ObjectBlocks {
                    index: k as u32,
                    blocks,
                });
            }
            Ok(())
        })?;
        self.traversal_times.push(started.elapsed());
        // The client sees the last prediction before this answer.
        b.unseen.iter_mut().for_each(Vec::clear);
        let (eye, aim) = (Vec3::from(switch.eye), Vec3::from(switch.aim));
        // A view asked for over several rounds is one view: the one before it stays.
        if let Some(last) = b.last.filter(|&(e, a, _)| (e, a) != (eye, aim)) {
            b.before = Some((last.0, last.1));
        }
        b.last = Some((eye, aim, switch.tau));
        self.operations += count(&objects).0;
        self.last_frame = Some(switch.frame);
        Ok(Message::Blocks {
            frame: switch.frame,
            predicted: false,
            objects,
        })
    }

    /// A predicted BLOCKS for the view extrapolated a step ahead of the last two (the
    /// last itself while there is one), at most `most` blocks asked for per landmark;
    /// `None` before any SWITCH, when the
    /// extrapolation is no view (the eye run onto the aim-at point), or when the view
    /// wants nothing that was not sent.
    fn predicted(&mut self, most: usize) -> Result<Option<Message>, StreamError> {
        let fov = self.hello.fov;
        let (Some(frame), Streams::Blocks(b)) = (self.last_frame, &mut self.streams) else {
            return Ok(None);
        };
        let Some((eye, aim, tau)) = b.last else {
            return Ok(None);
        };
        let (eye, aim) = Predictor::Linear.predict(1.0, (eye, aim), b.before, None);
        let Ok(view) = flaneur::lod::View::new(eye, aim - eye, fov) else {
            return Ok(None);
        };
        let mut objects = Vec::new();
        for (index, (source, server)) in b.sources.iter().zip(&mut b.servers).enumerate() {
            let blocks = server.predict(source, &view, tau, most)?;
            b.unseen[index] = blocks.iter().map(|block| block.top.clone()).collect();
            if !blocks.is_empty() {
                objects.push(ObjectBlocks {
                    index: index as u32,
                    blocks,
                });
            }
        }
        if objects.is_empty() {
            return Ok(None);
        }
        let (packets, blocks) = count(&objects);
        self.operations += packets;
        self.predicted_blocks += blocks;
        Ok(Some(Message::Blocks {
            frame,
            predicted: true,
            objects,
        }))
    }
}
