//! The client of a session of blocks (El-Sana's client-server paper, §5.2 and §6): per
//! landmark the blocks of the vertex hierarchy it was sent and its mesh over them
//! ([`BlockClient`]). For each view it refines and coarsens on its own, and sends one
//! SWITCH when the view wants a block it lacks, when a split reached its block's last
//! level (the blocks below are asked ahead, El-Sana's "lower quarter"), or when blocks
//! left its cache (switch-up); it waits for the BLOCKS answering it and refines again,
//! until the view wants nothing it lacks. Blocks the server predicted and sent unasked
//! on idle time are taken as they come, before a frame's refinement and while an answer
//! is awaited; one the client holds already is discarded by its name (§6.3), and so is
//! one under a block the client no longer holds: it crossed the release of that block
//! on the wire, and the server forgot it with the release (the server's side says why).
//!
//! The client keeps every block it is sent, or with [`BlockStreamClient::with_capacity`]
//! at most that many per landmark beyond those its mesh uses (El-Sana §6.1's cache:
//! [`BlockClient`]'s); what it drops goes in its next SWITCH.
//!
//! A message that does not fit what the client holds (blocks for an object it was not
//! welcomed with, a block holding a split of another block, an answer to another frame)
//! is an error naming it; after one, connect again. A session of blocks does not
//! resume.

use std::io::ErrorKind;
use std::net::{TcpStream, ToSocketAddrs};
use std::time::Duration;

use glam::Vec3;

use crate::client::open;
use crate::error::StreamError;
use crate::protocol::{
    receive, send, Hello, Message, ObjectBlocks, ObjectSwitch, Scheme, Switch, ViewPacket,
    MAX_SWITCH, MAX_TO_CLIENT,
};
use flaneur::lod::{block_of, Block, BlockClient, NodeName, View};
use flaneur::scene::Mesh;

/// One landmark as a client of blocks holds it.
#[derive(Clone, Debug)]
pub struct BlockLandmark {
    /// The landmark's id, as BLOCKS-WELCOME gave it.
    pub id: u64,
    held: BlockClient,
    /// Predicted blocks that came under a block dropped meanwhile.
    crossed: usize,
}

impl BlockLandmark {
    /// Its mesh's triangles, corners as node names.
    pub fn triangles(&self) -> Vec<[NodeName; 3]> {
        self.held.client().triangles()
    }

    /// The mesh to draw: its triangles over their corners' vertices.
    pub fn mesh(&self) -> Mesh {
        self.held.client().mesh()
    }

    /// The blocks it holds.
    pub fn blocks(&self) -> usize {
        self.held.blocks()
    }

    /// The blocks that came and were discarded over the session: held already, or
    /// predicted under a block dropped meanwhile.
    pub fn discarded(&self) -> usize {
        self.held.discarded + self.crossed
    }

    /// The blocks dropped from the cache over the session.
    pub fn dropped(&self) -> usize {
        self.held.dropped
    }

    /// The vertex splits and collapses the client made over the session (El-Sana's
    /// split and merge operations).
    pub fn operations(&self) -> (u64, u64) {
        self.held.client().operations()
    }

    /// Takes `blocks`, in order: how many were kept and how many discarded. A predicted
    /// block whose top's parent's split the client does not hold came under a block it
    /// dropped, and is discarded.
    fn take(&mut self, blocks: &[Block], predicted: bool) -> Result<(usize, usize), StreamError> {
        let before = self.discarded();
        let mut kept = 0;
        for b in blocks {
            let orphan = b.top.depth() > 0 && !self.held.client().holds_split(&b.top.up(1));
            if predicted && orphan {
                self.crossed += 1;
                continue;
            }
            let discarded = self.held.discarded;
            self.held.receive(std::slice::from_ref(b))?;
            kept += usize::from(self.held.discarded == discarded);
        }
        Ok((kept, self.discarded() - before))
    }
}

/// What one frame's refinement did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SwitchReport {
    /// The last SWITCH's frame; the view's when none went.
    pub frame: u32,
    /// The vertex splits the client made, over every landmark and round.
    pub splits: u64,
    /// The collapses the client made, likewise (splits and collapses are El-Sana's
    /// operations).
    pub collapses: u64,
    /// Blocks dropped from the cache, and released in a SWITCH.
    pub released: usize,
    /// Bytes of BLOCKS received on the wire, answers and predictions.
    pub bytes: usize,
    /// Blocks received in answers.
    pub blocks: usize,
    /// Predicted blocks taken.
    pub predicted_kept: usize,
    /// Predicted blocks discarded, held already.
    pub predicted_discarded: usize,
    /// SWITCHes sent and answered.
    pub round_trips: usize,
}

/// A session of blocks with a stream server.
///
/// ```
/// use std::sync::Arc;
/// use std::time::Duration;
/// use flaneur::lod::{Dag, DagConstruction, ProgressiveMesh, Traversal};
/// use flaneur_stream::{BlockStreamClient, Hello, Landmark, Scheme, ServerConfig, StreamServer, ViewPacket};
///
/// let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
/// let dag = Dag::build(&pm, DagConstruction::MiniRedundant)?;
/// let bunny = Landmark { id: 1, pm: Arc::new(pm), dag: Arc::new(dag) };
/// let server = StreamServer::bind("127.0.0.1:0", vec![bunny], ServerConfig::default())?.spawn()?;
///
/// let hello = Hello { traversal: Traversal::Priority, fov: 1.0, budget: None,
///                     out_of_view: true, back_face: true, scheme: Scheme::Blocks };
/// let mut client = BlockStreamClient::connect(server.addr(), hello, Duration::from_secs(5))?;
/// let base = client.objects()[0].triangles().len();
/// let view = ViewPacket { frame: 0, eye: [0.0, 0.1, 0.4], aim: [0.0, 0.1, 0.0], tau: 0.001,
///                         budget_mode: false, n: 500 };
/// // Switches until the client holds the blocks the view wants.
/// let report = client.select(&view)?;
/// assert!(report.round_trips > 0 && report.blocks > 0);
/// assert!(client.objects()[0].triangles().len() > base);
/// client.bye()?;
/// # Ok::<(), flaneur_stream::StreamError>(())
/// ```
#[derive(Debug)]
pub struct BlockStreamClient {
    stream: TcpStream,
    objects: Vec<BlockLandmark>,
    /// A block's levels, as BLOCKS-WELCOME gave them.
    levels: u32,
    hello: Hello,
    /// One past the last SWITCH's frame.
    next_frame: u32,
}

impl BlockStreamClient {
    /// Connects, says `hello` (of the blocks scheme, with both criteria), and takes the
    /// server's base meshes and a block's levels; `timeout` bounds each wait for the
    /// server. The client keeps every block it is sent
    /// ([`BlockStreamClient::with_capacity`] bounds them).
    pub fn connect(
        addr: impl ToSocketAddrs,
        hello: Hello,
        timeout: Duration,
    ) -> Result<BlockStreamClient, StreamError> {
        if hello.scheme != Scheme::Blocks {
            return Err(StreamError::Malformed(format!(
                "a HELLO of the {:?} scheme: BlockStreamClient speaks the blocks scheme",
                hello.scheme
            )));
        }
        if !(hello.out_of_view && hello.back_face) {
            return Err(StreamError::Malformed(
                "a HELLO of the blocks scheme without both criteria: its blocks are \
                 chosen under out-of-view and back-face culling both"
                    .into(),
            ));
        }
        let (stream, welcome) = open(TcpStream::connect(addr)?, hello, timeout)?;
        let Message::BlocksWelcome { levels, objects } = welcome else {
            return Err(StreamError::Malformed(format!(
                "the server answered a HELLO of the blocks scheme with {}",
                welcome.kind()
            )));
        };
        let levels = u32::from(levels);
        let objects = objects
            .into_iter()
            .map(|o| BlockLandmark {
                id: o.id,
                held: BlockClient::new(o.base, levels),
                crossed: 0,
            })
            .collect();
        Ok(BlockStreamClient {
            stream,
            objects,
            levels,
            hello,
            next_frame: 0,
        })
    }

    /// The client with a cache (El-Sana §6.1) of at most `blocks` blocks per landmark
    /// beyond those its mesh uses ([`BlockClient::with_capacity`]): past it, each
    /// frame drops the blocks furthest below those in use, then the least recently
    /// used, and names them in its SWITCH. Set before the first frame.
    pub fn with_capacity(self, blocks: usize) -> BlockStreamClient {
        let objects = self
            .objects
            .into_iter()
            .map(|o| BlockLandmark {
                held: o.held.with_capacity(blocks),
                ..o
            })
            .collect();
        BlockStreamClient { objects, ..self }
    }

    /// The session's landmarks, in the server's order.
    pub fn objects(&self) -> &[BlockLandmark] {
        &self.objects
    }

    /// A block's levels.
    pub fn levels(&self) -> u32 {
        self.levels
    }

    /// Brings every landmark's mesh to `v` (its eye, aim-at point and τ; its mode and
    /// N are not read): the blocks predicted that have come are taken, then each round
    /// refines with the blocks held and, when it names any block, sends one SWITCH and
    /// takes what comes up to its answer, until the view wants no block the client
    /// lacks. SWITCHes go with frames from `v.frame` on, each above the last.
    pub fn select(&mut self, v: &ViewPacket) -> Result<SwitchReport, StreamError> {
        let eye = Vec3::from(v.eye);
        let view = View::new(eye, Vec3::from(v.aim) - eye, self.hello.fov)?;
        let mut report = SwitchReport {
            frame: v.frame,
            ..SwitchReport::default()
        };
        let operations = |objects: &[BlockLandmark]| {
            objects
                .iter()
                .map(BlockLandmark::operations)
                .fold((0, 0), |(s, c), (ds, dc)| (s + ds, c + dc))
        };
        let before = operations(&self.objects);
        while self.waiting()? {
            self.take_predicted(&mut report)?;
        }
        loop {
            let mut needed = false;
            let mut objects = Vec::new();
            for (index, o) in self.objects.iter_mut().enumerate() {
                let down = o.held.select(&view, v.tau)?;
                needed |= !down.needed.is_empty();
                report.released += down.released.len();
                let part = ObjectSwitch {
                    index: index as u32,
                    down: down.needed,
                    ahead: down.ahead,
                    released: down.released,
                };
                if !part.is_empty() {
                    objects.push(part);
                }
            }
            if objects.is_empty() {
                break;
            }
            let frame = v.frame.max(self.next_frame);
            let switch = Switch {
                frame,
                eye: v.eye,
                aim: v.aim,
                tau: v.tau,
                objects,
            }
            .within(MAX_SWITCH)?;
            send(&mut self.stream, &Message::Switch(switch))?;
            self.next_frame = frame.saturating_add(1);
            let kept = self.await_answer(frame, &mut report)?;
            report.frame = frame;
            report.round_trips += 1;
            if !needed {
                break;
            }
            if kept == 0 {
                return Err(StreamError::Malformed(format!(
                    "the server sent no block for frame {frame}, whose view wants some"
                )));
            }
        }
        let after = operations(&self.objects);
        (report.splits, report.collapses) = (after.0 - before.0, after.1 - before.1);
        Ok(report)
    }

    /// Ends the session.
    pub fn bye(mut self) -> Result<(), StreamError> {
        send(&mut self.stream, &Message::Bye)?;
        Ok(())
    }

    /// Whether a message has begun to come (or the server closed): then reading one
    /// waits no longer than it takes to come whole.
    fn waiting(&mut self) -> Result<bool, StreamError> {
        self.stream.set_nonblocking(true)?;
        let peeked = self.stream.peek(&mut [0u8; 1]);
        self.stream.set_nonblocking(false)?;
        match peeked {
            Ok(_) => Ok(true),
            Err(e) if e.kind() == ErrorKind::WouldBlock => Ok(false),
            Err(e) => Err(e.into()),
        }
    }

    /// The next message and its bytes; a REFUSED or the connection's end is an `Err`.
    fn next_message(&mut self) -> Result<(Message, usize), StreamError> {
        match receive(&mut self.stream, MAX_TO_CLIENT)? {
            Some((Message::Refused(why), _)) => Err(StreamError::Refused(why)),
            Some(got) => Ok(got),
            None => Err(StreamError::Refused("closed mid-session".into())),
        }
    }

    /// Takes a message between frames: a BLOCKS predicted after a SWITCH sent.
    fn take_predicted(&mut self, report: &mut SwitchReport) -> Result<(), StreamError> {
        match self.next_message()? {
            (
                Message::Blocks {
                    frame,
                    predicted: true,
                    objects,
                },
                bytes,
            ) if frame < self.next_frame => {
                let (kept, discarded) = self.take(&objects, true)?;
                report.bytes += bytes;
                report.predicted_kept += kept;
                report.predicted_discarded += discarded;
                Ok(())
            }
            (m, _) => Err(StreamError::Malformed(format!(
                "{} between frames, where only predicted BLOCKS come",
                describe(&m)
            ))),
        }
    }

    /// Takes messages until the BLOCKS answering SWITCH `frame`, the predicted ones
    /// before it too: the blocks kept.
    fn await_answer(
        &mut self,
        frame: u32,
        report: &mut SwitchReport,
    ) -> Result<usize, StreamError> {
        let mut kept = 0;
        loop {
            let (m, bytes) = self.next_message()?;
            let (got, predicted, objects) = match m {
                Message::Blocks {
                    frame: got,
                    predicted,
                    objects,
                } if (predicted && got < frame) || (!predicted && got == frame) => {
                    (got, predicted, objects)
                }
                m => {
                    return Err(StreamError::Malformed(format!(
                        "{} where the BLOCKS of frame {frame} was due",
                        describe(&m)
                    )))
                }
            };
            let (k, discarded) = self.take(&objects, predicted)?;
            report.bytes += bytes;
            kept += k;
            if predicted {
                report.predicted_kept += k;
                report.predicted_discarded += discarded;
            } else {
                debug_assert_eq!(got, frame);
                report.blocks += k + discarded;
                return Ok(kept);
            }
        }
    }

    /// Takes `objects`' blocks (`predicted` or an answer's), each landmark's in order:
    /// how many were kept and how many discarded.
    fn take(
        &mut self,
        objects: &[ObjectBlocks],
        predicted: bool,
    ) -> Result<(usize, usize), StreamError> {
        let (mut kept, mut discarded) = (0, 0);
        for o in objects {
            let object = self.objects.get_mut(o.index as usize).ok_or_else(|| {
                StreamError::Malformed(format!(
                    "blocks for object {}, not in BLOCKS-WELCOME",
                    o.index
                ))
            })?;
            for b in &o.blocks {
                let outside = b
                    .packets
                    .iter()
                    .find(|p| block_of(&p.node, self.levels) != b.top);
                if let Some(p) = outside {
                    return Err(StreamError::Malformed(format!(
                        "object {}'s block {:?} holds the split of {:?}, which is not in it",
                        o.index, b.top, p.node
                    )));
                }
            }
            let (k, d) = object.take(&o.blocks, predicted)?;
            kept += k;
            discarded += d;
        }
        Ok((kept, discarded))
    }
}

/// A message as an error names it: its kind, and a BLOCKS' frame and flag.
fn describe(m: &Message) -> String {
    match m {
        Message::Blocks {
            frame, predicted, ..
        } => format!(
            "BLOCKS of frame {frame}{}",
            if *predicted { " (predicted)" } else { "" }
        ),
        m => format!("a {}", m.kind()),
    }
}
