//! The messages of a session of blocks (El-Sana's client-server paper, §5.3):
//! BLOCKS-WELCOME, SWITCH (the client's switch-down and switch-up messages with its
//! view) and BLOCKS (whole blocks of the vertex hierarchy). Their byte layout is the
//! protocol module's.

use flaneur::lod::{Block, NodeName};

use super::selective::read_objects;
use super::{magic_and_version, Message, MAX_OBJECTS};
use crate::error::StreamError;
use crate::selective_wire::{
    name_len, read_name, read_vsplits, write_name, write_vsplits, MIN_NAME,
};
use crate::wire::{Reader, Writer};

/// SWITCH's kind, frame, view (eye, aim-at, τ) and object count.
const SWITCH_HEAD: usize = 1 + 4 + 12 + 12 + 4 + 4;

/// The fewest bytes an object's part of a SWITCH takes: its index and three counts.
const MIN_SWITCH_PART: usize = 4 + 3 * 4;

/// The fewest bytes an object's part of a BLOCKS takes: its index and its count.
const MIN_BLOCKS_PART: usize = 4 + 4;

/// The fewest bytes a block takes: its top's name and its packets' count.
const MIN_BLOCK: usize = MIN_NAME + 4;

/// BLOCKS' flag: sent unasked, on idle time.
const PREDICTED: u8 = 1;

/// A client's switch messages for one frame (El-Sana §5.2–5.3): the view they are
/// for, and per object the blocks it wants and those it dropped.
#[derive(Clone, Debug, PartialEq)]
pub struct Switch {
    /// The client's frame number; each SWITCH's is above the last.
    pub frame: u32,
    /// The eye's position.
    pub eye: [f32; 3],
    /// The point looked at.
    pub aim: [f32; 3],
    /// The screen-space error threshold, a fraction of the viewport.
    pub tau: f32,
    /// The objects with tops to name, each once.
    pub objects: Vec<ObjectSwitch>,
}

/// One object's part of a SWITCH, each list the blocks' tops.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjectSwitch {
    /// The object's place in BLOCKS-WELCOME's list.
    pub index: u32,
    /// Blocks the view wants a split from (switch-down).
    pub down: Vec<NodeName>,
    /// Blocks below splits that reached their block's last level, asked ahead.
    pub ahead: Vec<NodeName>,
    /// Blocks dropped from the client's cache (switch-up): the server forgets it sent
    /// them, before it sends.
    pub released: Vec<NodeName>,
}

impl Switch {
    /// The frame's length as its prefix gives it (its bytes after the prefix), which a
    /// server bounds by [`MAX_SWITCH`](super::MAX_SWITCH).
    pub fn frame_len(&self) -> usize {
        SWITCH_HEAD
            + self
                .objects
                .iter()
                .map(ObjectSwitch::wire_len)
                .sum::<usize>()
    }

    /// The switch cut to a frame of at most `max` bytes: every release kept, the tops
    /// asked ahead dropped from the last, then those down (the client asks for them
    /// again at its next round). An `Err` when its releases alone pass `max`.
    pub fn within(mut self, max: usize) -> Result<Switch, StreamError> {
        let mut len = self.frame_len();
        let lists: [fn(&mut ObjectSwitch) -> &mut Vec<NodeName>; 2] =
            [|o| &mut o.ahead, |o| &mut o.down];
        for list in lists {
            for o in self.objects.iter_mut().rev() {
                while len > max {
                    match list(o).pop() {
                        Some(n) => len -= name_len(&n),
                        None => break,
                    }
                }
            }
        }
        self.objects.retain(|o| !o.is_empty());
        match self.frame_len() {
            len if len <= max => Ok(self),
            len => Err(StreamError::Malformed(format!(
                "a SWITCH whose releases alone take {len} bytes, above the {max} a server \
                 reads"
            ))),
        }
    }
}

impl ObjectSwitch {
    /// Whether it names nothing (such a part is not sent).
    pub fn is_empty(&self) -> bool {
        self.down.is_empty() && self.ahead.is_empty() && self.released.is_empty()
    }

    /// The bytes this part takes in a SWITCH.
    pub fn wire_len(&self) -> usize {
        let names = |n: &[NodeName]| n.iter().map(name_len).sum::<usize>();
        MIN_SWITCH_PART + names(&self.down) + names(&self.ahead) + names(&self.released)
    }
}

/// One object's blocks in a BLOCKS.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectBlocks {
    /// The object's place in BLOCKS-WELCOME's list.
    pub index: u32,
    /// In the order a client takes them: each after the blocks above it.
    pub blocks: Vec<Block>,
}

fn write_names(w: &mut Writer, names: &[NodeName]) {
    w.count(names.len());
    names.iter().for_each(|n| write_name(w, n));
}

fn read_names(r: &mut Reader<'_>) -> Result<Vec<NodeName>, StreamError> {
    let n = r.count(MIN_NAME)?;
    (0..n).map(|_| read_name(r)).collect()
}

/// SWITCH's body after its kind.
pub(super) fn write_switch(w: &mut Writer, s: &Switch) {
    w.u32(s.frame);
    w.vec3(s.eye);
    w.vec3(s.aim);
    w.f32(s.tau);
    w.count(s.objects.len());
    for o in &s.objects {
        w.u32(o.index);
        write_names(w, &o.down);
        write_names(w, &o.ahead);
        write_names(w, &o.released);
    }
}

pub(super) fn decode_switch(body: &[u8]) -> Result<Message, StreamError> {
    let mut r = Reader::new(body, "SWITCH");
    let frame = r.u32()?;
    let eye = r.vec3()?;
    let aim = r.vec3()?;
    let tau = r.f32()?;
    let n = r.count_at_most(MIN_SWITCH_PART, MAX_OBJECTS, "objects")?;
    let mut objects = Vec::with_capacity(n);
    for _ in 0..n {
        let index = r.u32()?;
        let part = ObjectSwitch {
            index,
            down: read_names(&mut r)?,
            ahead: read_names(&mut r)?,
            released: read_names(&mut r)?,
        };
        if part.is_empty() {
            return Err(r.bad(format!("object {index}'s part names no block")));
        }
        objects.push(part);
    }
    r.end()?;
    Ok(Message::Switch(Switch {
        frame,
        eye,
        aim,
        tau,
        objects,
    }))
}

pub(super) fn decode_blocks_welcome(body: &[u8]) -> Result<Message, StreamError> {
    let mut r = Reader::new(body, "BLOCKS-WELCOME");
    magic_and_version(&mut r)?;
    let levels = r.u8()?;
    if levels == 0 {
        return Err(r.bad("blocks of 0 levels"));
    }
    let objects = read_objects(&mut r)?;
    r.end()?;
    Ok(Message::BlocksWelcome { levels, objects })
}

/// BLOCKS' body after its kind.
pub(super) fn write_blocks(w: &mut Writer, frame: u32, predicted: bool, objects: &[ObjectBlocks]) {
    w.u32(frame);
    w.u8(if predicted { PREDICTED } else { 0 });
    w.count(objects.len());
    for o in objects {
        w.u32(o.index);
        w.count(o.blocks.len());
        for b in &o.blocks {
            write_name(w, &b.top);
            write_vsplits(w, &b.packets);
        }
    }
}

pub(super) fn decode_blocks(body: &[u8]) -> Result<Message, StreamError> {
    let mut r = Reader::new(body, "BLOCKS");
    let frame = r.u32()?;
    let flags = r.u8()?;
    if flags & !PREDICTED != 0 {
        return Err(r.bad(format!("unknown flags {flags:#04x}")));
    }
    let n = r.count_at_most(MIN_BLOCKS_PART, MAX_OBJECTS, "objects")?;
    let mut objects = Vec::with_capacity(n);
    for _ in 0..n {
        let index = r.u32()?;
        let count = r.count(MIN_BLOCK)?;
        if count == 0 {
            return Err(r.bad(format!("object {index}'s part has no block")));
        }
        let mut blocks = Vec::with_capacity(count);
        for _ in 0..count {
            let top = read_name(&mut r)?;
            let packets = read_vsplits(&mut r)?;
            if packets.is_empty() {
                return Err(r.bad(format!("block {top:?} has no split")));
            }
            blocks.push(Block { top, packets });
        }
        objects.push(ObjectBlocks { index, blocks });
    }
    r.end()?;
    Ok(Message::Blocks {
        frame,
        predicted: flags & PREDICTED != 0,
        objects,
    })
}
