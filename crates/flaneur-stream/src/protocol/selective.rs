//! The truly selective schemes' messages (Kim–Lee–Kobbelt) that are more than a few
//! fields: SELECTIVE-WELCOME's objects (which BLOCKS-WELCOME shares), VSPLITS and
//! RESUME-LEAVES. Their byte layout is the protocol module's; the packets' own codec is
//! `selective_wire`'s.

use super::{magic_and_version, HeldLeaves, Message, ObjectVsplits, SelectiveObject, MAX_OBJECTS};
use crate::error::StreamError;
use crate::selective_wire::{read_base, read_name, read_vsplits, write_base, MIN_NAME};
use crate::wire::{Reader, Writer};

pub(super) fn decode_resume_leaves(body: &[u8]) -> Result<Message, StreamError> {
    let mut r = Reader::new(body, "RESUME-LEAVES");
    let next_frame = r.u32()?;
    let n = r.count_at_most(8, MAX_OBJECTS, "objects")?;
    let mut objects = Vec::with_capacity(n);
    for _ in 0..n {
        let index = r.u32()?;
        let len = r.count(MIN_NAME)?;
        let leaves = (0..len)
            .map(|_| read_name(&mut r))
            .collect::<Result<Vec<_>, _>>()?;
        objects.push(HeldLeaves { index, leaves });
    }
    r.end()?;
    Ok(Message::ResumeLeaves {
        next_frame,
        objects,
    })
}

pub(super) fn decode_selective_welcome(body: &[u8]) -> Result<Message, StreamError> {
    let mut r = Reader::new(body, "SELECTIVE-WELCOME");
    magic_and_version(&mut r)?;
    let objects = read_objects(&mut r)?;
    r.end()?;
    Ok(Message::SelectiveWelcome(objects))
}

/// Each object's id and base mesh, after their count (SELECTIVE-WELCOME's and
/// BLOCKS-WELCOME's list).
pub(super) fn write_objects(w: &mut Writer, objects: &[SelectiveObject]) {
    w.count(objects.len());
    for o in objects {
        w.u64(o.id);
        write_base(w, &o.base);
    }
}

pub(super) fn read_objects(r: &mut Reader) -> Result<Vec<SelectiveObject>, StreamError> {
    let n = r.count_at_most(8 + 4 + 4, MAX_OBJECTS, "objects")?;
    let mut objects = Vec::with_capacity(n);
    for _ in 0..n {
        let id = r.u64()?;
        let base = read_base(r)?;
        objects.push(SelectiveObject { id, base });
    }
    Ok(objects)
}

pub(super) fn decode_vsplits(body: &[u8]) -> Result<Message, StreamError> {
    let mut r = Reader::new(body, "VSPLITS");
    let frame = r.u32()?;
    let n = r.count_at_most(8, MAX_OBJECTS, "objects")?;
    let mut objects = Vec::with_capacity(n);
    for _ in 0..n {
        let index = r.u32()?;
        let packets = read_vsplits(&mut r)?;
        if packets.is_empty() {
            return Err(r.bad(format!("object {index}'s part has no split")));
        }
        objects.push(ObjectVsplits { index, packets });
    }
    r.end()?;
    Ok(Message::Vsplits { frame, objects })
}
