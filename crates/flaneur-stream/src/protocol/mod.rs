//! The stream protocol, version 3: length-prefixed messages over one TCP connection.
//!
//! Every message is a frame: a `u32` length `L` (the bytes after it), then `L` bytes,
//! the first of them the message's kind. All numbers are little-endian; floats are
//! IEEE 754 `f32` and must be finite. A receiver refuses a frame longer than its bound
//! ([`MAX_TO_SERVER`], [`MAX_TO_CLIENT`]) before reading it (a server also one
//! longer than a session may hold: `ServerConfig::session_budget`), and reads one within
//! it as its bytes come, not into a buffer of the length announced ([`receive`]).
//!
//! ```text
//! client → server
//!   0x01 HELLO    magic "FLANEURS" (8)  version u16  traversal u8 (0 priority, 1 linear,
//!                 2 constant-time)  fov f32 (the view cone's full angle, radians)
//!                 budget u32 (triangles per object in budget mode; 0: none)
//!                 criteria u8 (bit 0 out-of-view, bit 1 back-face)
//!                 scheme u8 (0 Zheng's DAG, 1 truly selective, 2 cut-vertex-only,
//!                 3 El-Sana's blocks)                                          21 bytes
//!   0x02 VIEW     frame u32 (strictly increasing)  then Zheng's 33 bytes (§8.2.1):
//!                 eye 3×f32  aim-at 3×f32  τ f32  mode u8 (0 free, 1 budget)  N u32
//!                                                                              37 bytes
//!   0x03 BYE      nothing
//!   0x04 RESUME   next frame u32 (the lowest frame the next VIEW may have)
//!                 objects u32, then each: index u32 (in WELCOME's order)
//!                 nodes u32, then each: node u32 (a DAG node the client holds split)
//!   0x05 RESUME-LEAVES  next frame u32  objects u32, then each: index u32
//!                 names u32, then each a NAME (a node held whose split it was not sent)
//!   0x06 SWITCH   frame u32 (strictly increasing, as VIEW's)  eye 3×f32  aim-at 3×f32
//!                 τ f32  objects u32, then each object with tops: index u32
//!                 down u32, then each a NAME (a block's top: the view wants its splits)
//!                 ahead u32, then each a NAME (a block's top, asked ahead of need)
//!                 released u32, then each a NAME (a block's top, dropped from the
//!                 client's cache: a switch-up)
//! server → client
//!   0x81 WELCOME  magic (8)  version u16  objects u32, then each:
//!                 id u64  splits u32  base vertices u32  positions 3×f32 each
//!                 normals 3×f32 each  base triangles u32  corners 3×u32 each
//!   0x82 BATCH    frame u32 (the VIEW's)  objects u32, then each object with updates:
//!                 index u32 (in WELCOME's order)
//!                 collapses u32 (at most N), then each: node u32
//!                 splits u32 (at most N), then each: node u32  first split u32
//!                   run length u32 (at least 1),
//!                   then the run's vertex splits, each: v_p u32  position 3×f32
//!                   normal 3×f32  v_l u32  v_r u32 (u32::MAX: none)  corners 2×u8
//!                   adjusted u32, then that many triangle numbers u32
//!   0x83 REFUSED  reason, UTF-8, to the frame's end; the server closes after it
//!   0x84 SELECTIVE-WELCOME  magic (8)  version u16  objects u32, then each: id u64
//!                 roots u32, then each: position 3×f32  normal 3×f32  flag u8 (1: an
//!                 INFO follows)  base triangles u32, corners 3×u32 each (tree-ids)
//!                 placement u8 (0 cut vertices; 1 leaf corners: then each base
//!                 triangle's three corners' leaves, 3 NAMEs, each in its corner's tree)
//!   0x85 VSPLITS  frame u32 (the VIEW's)  objects u32, then each object with splits:
//!                 index u32  packets u32 (at least 1), then each:
//!                   NAME (the node)  flags u8 (bits 0, 1: left, right cut vertex;
//!                   bits 2, 3: the left, right child's INFO; bit 4: a run; bit 5:
//!                   leaves)  the cut vertices' NAMEs
//!                   position 3×f32  normal 3×f32 (the right child's vertex)
//!                   the children's INFOs
//!                   if bit 4: NAME (the node of its run's first split)
//!                   if bit 5: for each cut vertex sent, its triangle's leaves below
//!                   the left and the right child, 2 SUFFIXes
//!   0x86 BLOCKS-WELCOME  magic (8)  version u16  levels u8 (a block's, at least 1)
//!                 objects u32, then each as in SELECTIVE-WELCOME
//!   0x87 BLOCKS   frame u32 (the SWITCH's; a predicted one's, the last SWITCH's)
//!                 flags u8 (bit 0: predicted, sent unasked on idle time)
//!                 objects u32, then each object with blocks: index u32
//!                 blocks u32 (at least 1), then each: NAME (its top)
//!                   packets u32 (at least 1), then each packet as in VSPLITS
//!
//! NAME    tree u32  bits u16 (1 to 65,536)  the heap index in ⌈bits/8⌉ bytes, least
//!         significant first
//! SUFFIX  levels u16  the steps down from the child (1 right), most significant
//!         first, in ⌈levels/8⌉ bytes
//! INFO  centre 3×f32  axis 3×f32  radius f32  cone sin f32  error f32   44 bytes
//! ```
//!
//! A session: HELLO, WELCOME, then VIEW and BATCH in turn (the server answers every
//! VIEW with one BATCH of its collapses then its splits, at most N of each), until BYE
//! or the connection closes. A collapse names a node the client split earlier: it undoes
//! the run that node's split brought, in reverse, so it carries no geometry.
//!
//! A client that lost its connection resumes on a new one: HELLO, WELCOME (the same
//! objects as before, or it gives up), then RESUME, its first message after WELCOME and
//! the only one that may be longer than [`MAX_TO_SERVER`] (up to [`MAX_RESUME`]). RESUME
//! names, per object, the nodes the client holds split; the server splits the same ones
//! in a fresh session, so that its next BATCH starts from the meshes the client holds,
//! whatever batches were lost with the old connection. Nothing answers RESUME; a RESUME
//! the server cannot follow (a node out of range, or split with a parent that is not)
//! is refused as any other bad message is.
//!
//! **Truly selective sessions** (Kim–Lee–Kobbelt; HELLO's scheme 1 or 2) stream the
//! landmarks' vertex hierarchies instead: SELECTIVE-WELCOME gives each base mesh over
//! its roots, and each VIEW is answered with one VSPLITS of the splits the view asks
//! for that were not sent yet (`lod::selective`), at most N per object (a split begun
//! is sent whole with what the partial order forces for it, so a part may run a little
//! past N). A client of scheme 1 refines and coarsens locally and sends a VIEW only
//! when its view wants a split it lacks; one of scheme 2 (KLK §7) makes every split as
//! it comes, at the cut vertices the packet names as they stand on its mesh (under leaf
//! placement, by the leaves), and its packets carry no INFO. An object whose splits
//! come in crease runs, some adding no triangle, is sent with leaf placement: its
//! packets name their run and the leaves of the triangles they add (ours;
//! `lod::selective`). Budget mode is not part of these schemes: a VIEW in it is
//! refused. A client resumes with RESUME-LEAVES, naming the nodes it holds whose split
//! it was not sent: the server's front of what it sent.
//!
//! **Sessions of blocks** (El-Sana's view-dependence blocks; HELLO's scheme 3) stream
//! the same hierarchies cut into blocks of a few levels, each named by its top node
//! (`lod::selective`'s blocks): BLOCKS-WELCOME gives each base mesh and the blocks'
//! levels; the client refines on its own from the blocks it holds and, when its view
//! wants a block it lacks, asks ahead of need, or dropped blocks from its cache, sends
//! one SWITCH (El-Sana's switch-down and switch-up messages), which the server answers
//! with one BLOCKS (perhaps empty) of the blocks named that it had not sent, each after
//! the blocks above it, with those the partial order forces. The server releases before
//! it sends. When no message comes for a while after an answer, the server sends one
//! BLOCKS of its own, flagged predicted, for the view it extrapolates from the last
//! two SWITCHes (§6.2); a client takes each block it does not hold and discards the
//! rest by name (§6.3), and discards a predicted block under a block it released
//! before the prediction came, which the server forgets with that release (the blocks
//! of the last prediction below a released block are forgotten with it). A SWITCH may
//! be longer than [`MAX_TO_SERVER`], up to [`MAX_SWITCH`]. A session of blocks does not
//! resume: a client connects afresh.
//!
//! The codec is this module's; the truly selective messages' longer decoders are in
//! `protocol/selective.rs`, the blocks' messages in `protocol/blocks.rs`.
//!
//! Version 3 added the scheme, the truly selective messages and the blocks' messages,
//! version 2 RESUME; peers of another version are refused by version.

mod blocks;
mod selective;

pub use blocks::{ObjectBlocks, ObjectSwitch, Switch};

use crate::error::StreamError;
use crate::selective_wire::{write_name, write_vsplits};
use crate::wire::{Reader, Writer};
use flaneur::lod::{NodeName, SelectiveBase, Traversal, VertexSplit, VsplitPacket};
use flaneur::scene::Mesh;

/// The first bytes of HELLO and WELCOME.
pub const MAGIC: [u8; 8] = *b"FLANEURS";
/// The protocol's version; a peer of another is refused.
pub const VERSION: u16 = 3;
/// The longest frame a server reads: a VIEW is 38 bytes, a HELLO 22.
pub const MAX_TO_SERVER: usize = 4 << 10;
/// The longest SWITCH a server reads. A view's switch-down names every block it wants a
/// split from and every block it asks ahead, about 10 bytes a name: on a first view of
/// a large landmark that is thousands of names, past [`MAX_TO_SERVER`]. 1 MiB holds
/// about a hundred thousand; a client asks for what does not fit at its next round.
pub const MAX_SWITCH: usize = 1 << 20;
/// The longest RESUME a server reads: 4 bytes a node held split, so about four million
/// nodes over every object.
pub const MAX_RESUME: usize = 16 << 20;
/// The longest frame a client reads (a WELCOME carries every object's base mesh).
pub const MAX_TO_CLIENT: usize = 64 << 20;
/// The most operators of each kind a VIEW may ask for (Zheng's 500 + 500, §5.4.1).
pub const MAX_N: u32 = 500;
/// The most objects a session streams: WELCOME, BATCH and RESUME list no more, so that
/// what a frame decodes to stays near its bytes (a hostile peer's frame of empty
/// entries would otherwise decode to several times its length).
pub const MAX_OBJECTS: usize = 1 << 16;

const HELLO: u8 = 0x01;
const VIEW: u8 = 0x02;
const BYE: u8 = 0x03;
const RESUME: u8 = 0x04;
const RESUME_LEAVES: u8 = 0x05;
const WELCOME: u8 = 0x81;
const BATCH: u8 = 0x82;
const REFUSED: u8 = 0x83;
const SELECTIVE_WELCOME: u8 = 0x84;
const VSPLITS: u8 = 0x85;
const SWITCH: u8 = 0x06;
const BLOCKS_WELCOME: u8 = 0x86;
const BLOCKS: u8 = 0x87;

/// How a session streams its landmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Scheme {
    /// Zheng's: the server runs the DAG traversal and sends collapses and splits.
    #[default]
    Dag,
    /// Kim–Lee–Kobbelt's truly selective refinement: the server sends the vertex
    /// hierarchy's splits a view asks for, the client refines on its own.
    Selective,
    /// KLK §7's variant for clients that do not refine: each split at the cut vertices
    /// as they stand on the client's mesh.
    CutVertex,
    /// El-Sana's view-dependence blocks: the client refines on its own and asks for
    /// whole blocks of the hierarchy by name; the server predicts on idle time.
    Blocks,
}

/// What a client asks for once, at the session's start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hello {
    pub traversal: Traversal,
    /// The view cone's full angle, radians, in (0, π).
    pub fov: f32,
    /// Triangles per object in budget mode; `None` for no budget.
    pub budget: Option<u32>,
    pub out_of_view: bool,
    pub back_face: bool,
    pub scheme: Scheme,
}

/// One frame's view parameters (Zheng 2007 §8.2.1: E, A, τ, mode, N).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewPacket {
    /// The client's frame number; each VIEW's is above the last.
    pub frame: u32,
    pub eye: [f32; 3],
    /// The point looked at.
    pub aim: [f32; 3],
    /// The screen-space error threshold, a fraction of the viewport.
    pub tau: f32,
    /// Budget mode (the HELLO's budget bounds the mesh) or free mode.
    pub budget_mode: bool,
    /// The most collapses and the most splits of the reply (1 to [`MAX_N`]).
    pub n: u32,
}

/// One object's nodes a resuming client holds split (RESUME).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct HeldNodes {
    /// The object's place in WELCOME's list.
    pub index: u32,
    /// The DAG nodes split, in any order.
    pub nodes: Vec<u32>,
}

/// One object's leaves a resuming client of a truly selective session holds
/// (RESUME-LEAVES).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct HeldLeaves {
    /// The object's place in SELECTIVE-WELCOME's list.
    pub index: u32,
    /// The nodes it holds whose split it was not sent.
    pub leaves: Vec<NodeName>,
}

/// An object a truly selective session may stream: its id and the base mesh over its
/// hierarchy's roots.
#[derive(Clone, Debug, PartialEq)]
pub struct SelectiveObject {
    pub id: u64,
    pub base: SelectiveBase,
}

/// One object's splits in a VSPLITS.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectVsplits {
    /// The object's place in SELECTIVE-WELCOME's list.
    pub index: u32,
    pub packets: Vec<VsplitPacket>,
}

/// An object a session may stream: its id and the base mesh its splits refine.
#[derive(Clone, Debug, PartialEq)]
pub struct WelcomeObject {
    pub id: u64,
    /// Vertex splits of its progressive mesh.
    pub splits: u32,
    pub base: Mesh,
}

/// A node split: the node and the run of vertex splits it applies, in order.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeSplit {
    pub node: u32,
    /// The run's first vertex split's number in the progressive mesh.
    pub first: u32,
    pub run: Vec<VertexSplit>,
}

/// One object's updates in a batch.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjectUpdates {
    /// The object's place in WELCOME's list.
    pub index: u32,
    /// Nodes to collapse, in order, before the splits.
    pub collapses: Vec<u32>,
    pub splits: Vec<NodeSplit>,
}

impl ObjectUpdates {
    /// The bytes this object's part of a BATCH takes on the wire. Zheng's batches were
    /// at most 64 KiB for N = 500 (§5.4.1); here each object's part is its own batch of
    /// at most N + N operators.
    pub fn wire_len(&self) -> usize {
        let split = |s: &VertexSplit| SPLIT_MIN + 4 * s.adjusted.len();
        let node = |n: &NodeSplit| 12 + n.run.iter().map(split).sum::<usize>();
        12 + 4 * self.collapses.len() + self.splits.iter().map(node).sum::<usize>()
    }
}

/// A message of the protocol.
#[derive(Clone, Debug, PartialEq)]
pub enum Message {
    Hello(Hello),
    View(ViewPacket),
    Bye,
    /// A client resuming its session on a new connection: the lowest frame its next
    /// VIEW may have, and what it holds of each object.
    Resume {
        next_frame: u32,
        objects: Vec<HeldNodes>,
    },
    Welcome(Vec<WelcomeObject>),
    Batch {
        frame: u32,
        objects: Vec<ObjectUpdates>,
    },
    Refused(String),
    /// A client of a truly selective session resuming on a new connection.
    ResumeLeaves {
        next_frame: u32,
        objects: Vec<HeldLeaves>,
    },
    SelectiveWelcome(Vec<SelectiveObject>),
    Vsplits {
        frame: u32,
        objects: Vec<ObjectVsplits>,
    },
    /// A session of blocks' greeting: each object's base mesh, and a block's levels.
    BlocksWelcome {
        /// The levels of the hierarchy a block spans (at least 1).
        levels: u8,
        objects: Vec<SelectiveObject>,
    },
    /// A client of blocks' switch-down and switch-up messages for one view.
    Switch(Switch),
    /// Blocks for a SWITCH's frame, or predicted (sent unasked) after it.
    Blocks {
        /// The SWITCH's frame; a predicted one's, the last SWITCH's.
        frame: u32,
        /// Sent unasked, on idle time.
        predicted: bool,
        /// The objects with blocks, each once.
        objects: Vec<ObjectBlocks>,
    },
}

fn scheme_code(s: Scheme) -> u8 {
    match s {
        Scheme::Dag => 0,
        Scheme::Selective => 1,
        Scheme::CutVertex => 2,
        Scheme::Blocks => 3,
    }
}

fn traversal_code(t: Traversal) -> u8 {
    match t {
        Traversal::Priority => 0,
        Traversal::Linear => 1,
        Traversal::ConstantTime => 2,
    }
}

impl Message {
    /// The message's name, as the byte layout above spells it.
    pub fn kind(&self) -> &'static str {
        match self {
            Message::Hello(_) => "HELLO",
            Message::View(_) => "VIEW",
            Message::Bye => "BYE",
            Message::Resume { .. } => "RESUME",
            Message::Welcome(_) => "WELCOME",
            Message::Batch { .. } => "BATCH",
            Message::Refused(_) => "REFUSED",
            Message::ResumeLeaves { .. } => "RESUME-LEAVES",
            Message::SelectiveWelcome(_) => "SELECTIVE-WELCOME",
            Message::Vsplits { .. } => "VSPLITS",
            Message::BlocksWelcome { .. } => "BLOCKS-WELCOME",
            Message::Switch(_) => "SWITCH",
            Message::Blocks { .. } => "BLOCKS",
        }
    }

    /// The frame: length, kind, body.
    pub fn encode(&self) -> Vec<u8> {
        let mut w = Writer::default();
        w.u32(0);
        match self {
            Message::Hello(h) => {
                w.u8(HELLO);
                w.raw(&MAGIC);
                w.u16(VERSION);
                w.u8(traversal_code(h.traversal));
                w.f32(h.fov);
                w.u32(h.budget.unwrap_or(0));
                w.u8(u8::from(h.out_of_view) | (u8::from(h.back_face) << 1));
                w.u8(scheme_code(h.scheme));
            }
            Message::View(v) => {
                w.u8(VIEW);
                w.u32(v.frame);
                w.vec3(v.eye);
                w.vec3(v.aim);
                w.f32(v.tau);
                w.u8(u8::from(v.budget_mode));
                w.u32(v.n);
            }
            Message::Bye => w.u8(BYE),
            Message::Resume {
                next_frame,
                objects,
            } => {
                w.u8(RESUME);
                w.u32(*next_frame);
                w.count(objects.len());
                for o in objects {
                    w.u32(o.index);
                    w.count(o.nodes.len());
                    o.nodes.iter().for_each(|&n| w.u32(n));
                }
            }
            Message::Welcome(objects) => {
                w.u8(WELCOME);
                w.raw(&MAGIC);
                w.u16(VERSION);
                write_welcome_objects(&mut w, objects);
            }
            Message::Batch { frame, objects } => {
                w.u8(BATCH);
                w.u32(*frame);
                write_batch_objects(&mut w, objects);
            }
            Message::Refused(why) => {
                w.u8(REFUSED);
                w.raw(why.as_bytes());
            }
            Message::ResumeLeaves {
                next_frame,
                objects,
            } => {
                w.u8(RESUME_LEAVES);
                w.u32(*next_frame);
                w.count(objects.len());
                for o in objects {
                    w.u32(o.index);
                    w.count(o.leaves.len());
                    o.leaves.iter().for_each(|n| write_name(&mut w, n));
                }
            }
            Message::SelectiveWelcome(objects) => {
                w.u8(SELECTIVE_WELCOME);
                w.raw(&MAGIC);
                w.u16(VERSION);
                selective::write_objects(&mut w, objects);
            }
            Message::Vsplits { frame, objects } => {
                w.u8(VSPLITS);
                w.u32(*frame);
                w.count(objects.len());
                for o in objects {
                    w.u32(o.index);
                    write_vsplits(&mut w, &o.packets);
                }
            }
            Message::BlocksWelcome { levels, objects } => {
                w.u8(BLOCKS_WELCOME);
                w.raw(&MAGIC);
                w.u16(VERSION);
                w.u8(*levels);
                selective::write_objects(&mut w, objects);
            }
            Message::Switch(s) => {
                w.u8(SWITCH);
                blocks::write_switch(&mut w, s);
            }
            Message::Blocks {
                frame,
                predicted,
                objects,
            } => {
                w.u8(BLOCKS);
                blocks::write_blocks(&mut w, *frame, *predicted, objects);
            }
        }
        let len = (w.bytes.len() - 4) as u32;
        w.bytes[..4].copy_from_slice(&len.to_le_bytes());
        w.bytes
    }

    /// The message in `body` (a frame's bytes after its length).
    pub fn decode(body: &[u8]) -> Result<Message, StreamError> {
        let (&kind, rest) = body
            .split_first()
            .ok_or_else(|| StreamError::Malformed("an empty frame".into()))?;
        let m = match kind {
            HELLO => {
                let mut r = Reader::new(rest, "HELLO");
                magic_and_version(&mut r)?;
                let traversal = match r.u8()? {
                    0 => Traversal::Priority,
                    1 => Traversal::Linear,
                    2 => Traversal::ConstantTime,
                    t => return Err(r.bad(format!("traversal {t}, not 0, 1 or 2"))),
                };
                let fov = r.f32()?;
                let budget = r.u32()?;
                let criteria = r.u8()?;
                if criteria > 3 {
                    return Err(r.bad(format!("criteria bits {criteria:#x}")));
                }
                let scheme = match r.u8()? {
                    0 => Scheme::Dag,
                    1 => Scheme::Selective,
                    2 => Scheme::CutVertex,
                    3 => Scheme::Blocks,
                    s => return Err(r.bad(format!("scheme {s}, not 0 to 3"))),
                };
                r.end()?;
                Message::Hello(Hello {
                    traversal,
                    fov,
                    budget: (budget > 0).then_some(budget),
                    out_of_view: criteria & 1 != 0,
                    back_face: criteria & 2 != 0,
                    scheme,
                })
            }
            VIEW => {
                let mut r = Reader::new(rest, "VIEW");
                let frame = r.u32()?;
                let eye = r.vec3()?;
                let aim = r.vec3()?;
                let tau = r.f32()?;
                let budget_mode = match r.u8()? {
                    0 => false,
                    1 => true,
                    m => return Err(r.bad(format!("mode {m}, not 0 (free) or 1 (budget)"))),
                };
                let n = r.u32()?;
                r.end()?;
                Message::View(ViewPacket {
                    frame,
                    eye,
                    aim,
                    tau,
                    budget_mode,
                    n,
                })
            }
            BYE => {
                Reader::new(rest, "BYE").end()?;
                Message::Bye
            }
            RESUME => decode_resume(rest)?,
            WELCOME => decode_welcome(rest)?,
            BATCH => decode_batch(rest)?,
            REFUSED => Message::Refused(String::from_utf8_lossy(rest).into_owned()),
            RESUME_LEAVES => selective::decode_resume_leaves(rest)?,
            SELECTIVE_WELCOME => selective::decode_selective_welcome(rest)?,
            VSPLITS => selective::decode_vsplits(rest)?,
            BLOCKS_WELCOME => blocks::decode_blocks_welcome(rest)?,
            SWITCH => blocks::decode_switch(rest)?,
            BLOCKS => blocks::decode_blocks(rest)?,
            k => {
                return Err(StreamError::Malformed(format!(
                    "a message of kind {k:#04x}"
                )))
            }
        };
        Ok(m)
    }
}

fn magic_and_version(r: &mut Reader) -> Result<(), StreamError> {
    if r.raw(MAGIC.len())? != MAGIC {
        return Err(r.bad("not a flaneur stream (bad magic)"));
    }
    match r.u16()? {
        VERSION => Ok(()),
        v => Err(r.bad(format!("protocol version {v}; this side speaks {VERSION}"))),
    }
}

/// A WELCOME's objects: each one's id, split count and base mesh.
fn write_welcome_objects(w: &mut Writer, objects: &[WelcomeObject]) {
    w.count(objects.len());
    for o in objects {
        w.u64(o.id);
        w.u32(o.splits);
        w.count(o.base.positions.len());
        o.base.positions.iter().for_each(|p| w.vec3(*p));
        o.base.normals.iter().for_each(|n| w.vec3(*n));
        w.count(o.base.indices.len() / 3);
        o.base.indices.iter().for_each(|&i| w.u32(i));
    }
}

/// A BATCH's objects: each one's collapses, then its runs of splits.
fn write_batch_objects(w: &mut Writer, objects: &[ObjectUpdates]) {
    w.count(objects.len());
    for o in objects {
        w.u32(o.index);
        w.count(o.collapses.len());
        o.collapses.iter().for_each(|&n| w.u32(n));
        w.count(o.splits.len());
        for s in &o.splits {
            w.u32(s.node);
            w.u32(s.first);
            w.count(s.run.len());
            s.run.iter().for_each(|v| write_split(w, v));
        }
    }
}

fn write_split(w: &mut Writer, s: &VertexSplit) {
    w.u32(s.v_p);
    w.vec3(s.position);
    w.vec3(s.normal);
    w.u32(s.v_l.unwrap_or(u32::MAX));
    w.u32(s.v_r.unwrap_or(u32::MAX));
    w.u8(s.corners[0]);
    w.u8(s.corners[1]);
    w.count(s.adjusted.len());
    s.adjusted.iter().for_each(|&t| w.u32(t));
}

/// The fewest bytes one vertex split takes on the wire (no adjusted triangle).
const SPLIT_MIN: usize = 4 + 12 + 12 + 4 + 4 + 2 + 4;

fn read_split(r: &mut Reader) -> Result<VertexSplit, StreamError> {
    let v_p = r.u32()?;
    let position = r.vec3()?;
    let normal = r.vec3()?;
    let pivot = |v: u32| (v != u32::MAX).then_some(v);
    let v_l = pivot(r.u32()?);
    let v_r = pivot(r.u32()?);
    let corners = [r.u8()?, r.u8()?];
    if corners.iter().any(|&c| c > 2) {
        return Err(r.bad(format!("corners {corners:?}, each 0 to 2")));
    }
    let n = r.count(4)?;
    let adjusted = (0..n).map(|_| r.u32()).collect::<Result<Vec<_>, _>>()?;
    Ok(VertexSplit {
        v_p,
        position,
        normal,
        v_l,
        v_r,
        adjusted,
        corners,
        // Neither is read by a client applying the split.
        error: 0.0,
        joins_previous: false,
    })
}

fn decode_resume(body: &[u8]) -> Result<Message, StreamError> {
    let mut r = Reader::new(body, "RESUME");
    let next_frame = r.u32()?;
    let n = r.count_at_most(8, MAX_OBJECTS, "objects")?;
    let mut objects = Vec::with_capacity(n);
    for _ in 0..n {
        let index = r.u32()?;
        let len = r.count(4)?;
        let nodes = (0..len).map(|_| r.u32()).collect::<Result<Vec<_>, _>>()?;
        objects.push(HeldNodes { index, nodes });
    }
    r.end()?;
    Ok(Message::Resume {
        next_frame,
        objects,
    })
}

fn decode_welcome(body: &[u8]) -> Result<Message, StreamError> {
    let mut r = Reader::new(body, "WELCOME");
    magic_and_version(&mut r)?;
    let n = r.count_at_most(8 + 4 + 4 + 4, MAX_OBJECTS, "objects")?;
    let mut objects = Vec::with_capacity(n);
    for _ in 0..n {
        let id = r.u64()?;
        let splits = r.u32()?;
        let nv = r.count(24)?;
        let positions = (0..nv).map(|_| r.vec3()).collect::<Result<Vec<_>, _>>()?;
        let normals = (0..nv).map(|_| r.vec3()).collect::<Result<Vec<_>, _>>()?;
        let nt = r.count(12)?;
        let indices = (0..3 * nt)
            .map(|_| r.u32())
            .collect::<Result<Vec<_>, _>>()?;
        let base = Mesh {
            positions,
            normals,
            indices,
        };
        base.validate()
            .map_err(|e| r.bad(format!("object {id}'s base mesh: {e}")))?;
        objects.push(WelcomeObject { id, splits, base });
    }
    r.end()?;
    Ok(Message::Welcome(objects))
}

fn decode_batch(body: &[u8]) -> Result<Message, StreamError> {
    let mut r = Reader::new(body, "BATCH");
    let frame = r.u32()?;
    let n = r.count_at_most(12, MAX_OBJECTS, "objects")?;
    let mut objects = Vec::with_capacity(n);
    for _ in 0..n {
        let index = r.u32()?;
        let nc = r.count_at_most(4, MAX_N as usize, "collapses")?;
        let collapses = (0..nc).map(|_| r.u32()).collect::<Result<Vec<_>, _>>()?;
        let ns = r.count_at_most(12, MAX_N as usize, "splits")?;
        if nc + ns == 0 {
            return Err(r.bad(format!("object {index}'s part has no update")));
        }
        let mut splits = Vec::with_capacity(ns);
        for _ in 0..ns {
            let node = r.u32()?;
            let first = r.u32()?;
            let len = r.count(SPLIT_MIN)?;
            if len == 0 {
                return Err(r.bad(format!("node {node}'s split has no vertex split")));
            }
            let run = (0..len)
                .map(|_| read_split(&mut r))
                .collect::<Result<Vec<_>, _>>()?;
            splits.push(NodeSplit { node, first, run });
        }
        objects.push(ObjectUpdates {
            index,
            collapses,
            splits,
        });
    }
    r.end()?;
    Ok(Message::Batch { frame, objects })
}

/// Writes `m` as one frame.
pub fn send(out: &mut impl std::io::Write, m: &Message) -> Result<usize, StreamError> {
    let bytes = m.encode();
    out.write_all(&bytes)?;
    out.flush()?;
    Ok(bytes.len())
}

/// Reads one frame of at most `max` bytes and decodes it; `Ok(None)` when the peer
/// closed the connection between frames. Also returns the frame's length on the wire.
///
/// The frame's buffer grows with the bytes that come (see [`READ_CHUNK`]), not to the
/// length the peer announced, so a peer that announces a long frame and sends little
/// of it makes this side hold little.
pub fn receive(
    input: &mut impl std::io::Read,
    max: usize,
) -> Result<Option<(Message, usize)>, StreamError> {
    receive_within(input, max, "this side reads")
}

/// The most a frame's buffer grows by before the bytes already in it have come: a
/// frame is read in pieces of this size, then of the size read so far, so that what a
/// frame holds is at most twice what was sent of it, or this.
pub const READ_CHUNK: usize = 64 << 10;

/// [`receive`], a frame over `max` refused as above the `max` of `bound`'s naming.
pub(crate) fn receive_within(
    input: &mut impl std::io::Read,
    max: usize,
    bound: &str,
) -> Result<Option<(Message, usize)>, StreamError> {
    let mut len = [0u8; 4];
    match input.read_exact(&mut len) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(None),
        Err(e) => return Err(e.into()),
    }
    let len = u32::from_le_bytes(len) as usize;
    if len > max {
        return Err(StreamError::Malformed(format!(
            "a frame of {len} bytes, above the {max} {bound}"
        )));
    }
    let mut body = Vec::new();
    while body.len() < len {
        let (start, grow) = (body.len(), body.len().max(READ_CHUNK).min(len - body.len()));
        body.reserve_exact(grow);
        body.resize(start + grow, 0);
        input.read_exact(&mut body[start..])?;
    }
    Ok(Some((Message::decode(&body)?, 4 + len)))
}

#[cfg(test)]
mod tests;
