//! Truly selective streaming's packets on the wire (Kim–Lee–Kobbelt Fig. 3b): a batch
//! of vertex splits, each the node's ⟨tree-id, node-id⟩, its fundamental cut vertices'
//! names, the new vertex, and what `qrefine` reads of both children. A node-id is as
//! many bits as its node is deep, sent in whole bytes after its bit count.
//!
//! ```
//! use flaneur::lod::{HeapIndex, NodeName, VsplitPacket};
//! use flaneur_stream::selective_wire::{decode_vsplits, encode_vsplits};
//! let name = NodeName { tree: 7, node: HeapIndex::root().child(true) };
//! let packet = VsplitPacket {
//!     node: name.clone(),
//!     cuts: [Some(name), None],
//!     position: [1.0, 2.0, 3.0],
//!     normal: [0.0, 1.0, 0.0],
//!     children: [None, None],
//! };
//! let bytes = encode_vsplits(std::slice::from_ref(&packet));
//! assert_eq!(decode_vsplits(&bytes)?, [packet]);
//! # Ok::<(), flaneur_stream::StreamError>(())
//! ```

use flaneur::lod::{HeapIndex, NodeName, RefineInfo, VsplitPacket};

use crate::error::StreamError;
use crate::wire::{Reader, Writer};

/// The deepest node a name may name: far below what a hostile count could make a
/// reader allocate, far above any hierarchy of ours.
pub const MAX_NAME_BITS: usize = 1 << 16;

/// The fewest bytes one packet takes: a name of one byte, the flags, the new vertex.
const MIN_PACKET: usize = 4 + 2 + 1 + 1 + 24;

/// A batch of vsplit packets as bytes.
pub fn encode_vsplits(packets: &[VsplitPacket]) -> Vec<u8> {
    let mut w = Writer::default();
    w.count(packets.len());
    for p in packets {
        name(&mut w, &p.node);
        let flags = p.cuts[0].is_some() as u8
            | (p.cuts[1].is_some() as u8) << 1
            | (p.children[0].is_some() as u8) << 2
            | (p.children[1].is_some() as u8) << 3;
        w.u8(flags);
        for c in p.cuts.iter().flatten() {
            name(&mut w, c);
        }
        w.vec3(p.position);
        w.vec3(p.normal);
        for i in p.children.iter().flatten() {
            w.vec3(i.centre);
            w.vec3(i.axis);
            w.f32(i.radius);
            w.f32(i.cone_sin);
            w.f32(i.error);
        }
    }
    w.bytes
}

/// The batch `bytes` hold. An error naming the byte for anything that is not one
/// batch: a count past the bytes left, a name of zero or deeper than
/// [`MAX_NAME_BITS`], unknown flags, bytes past its end.
pub fn decode_vsplits(bytes: &[u8]) -> Result<Vec<VsplitPacket>, StreamError> {
    let mut r = Reader::new(bytes, "vsplit batch");
    let n = r.count(MIN_PACKET)?;
    let mut packets = Vec::with_capacity(n);
    for _ in 0..n {
        let node = read_name(&mut r)?;
        let flags = r.u8()?;
        if flags & !0b1111 != 0 {
            return Err(r.bad(format!("unknown flags {flags:#04x}")));
        }
        let cut = |r: &mut Reader<'_>, bit: u8| -> Result<Option<NodeName>, StreamError> {
            (flags & bit != 0).then(|| read_name(r)).transpose()
        };
        let cuts = [cut(&mut r, 1)?, cut(&mut r, 2)?];
        let (position, normal) = (r.vec3()?, r.vec3()?);
        let info = |r: &mut Reader<'_>, bit: u8| -> Result<Option<RefineInfo>, StreamError> {
            if flags & bit == 0 {
                return Ok(None);
            }
            Ok(Some(RefineInfo {
                centre: r.vec3()?,
                axis: r.vec3()?,
                radius: r.f32()?,
                cone_sin: r.f32()?,
                error: r.f32()?,
            }))
        };
        let children = [info(&mut r, 4)?, info(&mut r, 8)?];
        packets.push(VsplitPacket {
            node,
            cuts,
            position,
            normal,
            children,
        });
    }
    r.end()?;
    Ok(packets)
}

fn name(w: &mut Writer, n: &NodeName) {
    w.u32(n.tree);
    let bits = n.node.bits() as usize;
    w.u16(u16::try_from(bits).unwrap_or(u16::MAX));
    let bytes: Vec<u8> = n
        .node
        .words()
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    w.raw(&bytes[..bits.div_ceil(8)]);
}

fn read_name(r: &mut Reader<'_>) -> Result<NodeName, StreamError> {
    let tree = r.u32()?;
    let bits = r.u16()? as usize;
    if bits == 0 || bits > MAX_NAME_BITS {
        return Err(r.bad(format!("a node-id of {bits} bits")));
    }
    let raw = r.raw(bits.div_ceil(8))?;
    let mut words = vec![0u64; bits.div_ceil(64)];
    for (k, b) in raw.iter().enumerate() {
        words[k / 8] |= u64::from(*b) << (8 * (k % 8));
    }
    let node = HeapIndex::from_words(words).ok_or_else(|| r.bad("a node-id of 0"))?;
    if node.bits() as usize != bits {
        return Err(r.bad(format!(
            "a node-id said to be {bits} bits long is {}",
            node.bits()
        )));
    }
    Ok(NodeName { tree, node })
}

#[cfg(test)]
mod tests {
    use super::*;
    use flaneur::lod::{Dag, DagConstruction, ProgressiveMesh, View};
    use flaneur::lod::{SelectiveClient, SelectiveServer, SelectiveSource};
    use glam::Vec3;

    #[test]
    fn a_streamed_view_survives_the_wire_and_bad_bytes_are_named() {
        let pm = ProgressiveMesh::build(&flaneur::lod::bumpy_torus(1200)).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        let source = SelectiveSource::new(&pm, &dag).unwrap();
        let mut server = SelectiveServer::new(&source);
        let mut client = SelectiveClient::new(source.base());
        let view = View::new(Vec3::new(0.3, 0.2, 2.0), Vec3::NEG_Z, 1.0).unwrap();
        let mut batches = 0;
        while !client.select(&view, 0.002).unwrap().is_empty() {
            let packets = server.refine(&source, &view, 0.002).unwrap();
            let bytes = encode_vsplits(&packets);
            assert_eq!(decode_vsplits(&bytes).unwrap(), packets);
            client.receive(&decode_vsplits(&bytes).unwrap()).unwrap();
            batches += 1;
            // Every cut short of the whole is refused, never read past.
            for cut in [0, 3, bytes.len() / 2, bytes.len() - 1] {
                assert!(decode_vsplits(&bytes[..cut]).is_err());
            }
            let mut long = bytes.clone();
            long.push(0);
            let e = decode_vsplits(&long).unwrap_err();
            assert!(e.to_string().contains("past the message's end"), "{e}");
        }
        assert!(batches >= 1);
        // A count far past the bytes, and a name of zero bits.
        let e = decode_vsplits(&[0xff, 0xff, 0xff, 0x7f]).unwrap_err();
        assert!(e.to_string().contains("count"), "{e}");
        let mut zero = vec![1, 0, 0, 0, 0, 0, 0, 0, 0, 0];
        zero.resize(40, 0);
        assert!(decode_vsplits(&zero).is_err());
    }

    /// Hostile bytes never panic the decoder: random ones, and a real batch with bytes
    /// flipped, are a batch or an error.
    #[test]
    fn random_and_flipped_bytes_are_a_batch_or_an_error() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        for _ in 0..5000 {
            let len = rng.gen_range(0..200);
            let bytes: Vec<u8> = (0..len).map(|_| rng.gen()).collect();
            let _ = decode_vsplits(&bytes);
        }
        let pm = ProgressiveMesh::build(&flaneur::lod::bumpy_torus(600)).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        let source = SelectiveSource::new(&pm, &dag).unwrap();
        let view = View::new(Vec3::new(0.0, 0.0, 2.0), Vec3::NEG_Z, 1.0).unwrap();
        let packets = SelectiveServer::new(&source)
            .refine(&source, &view, 0.001)
            .unwrap();
        let good = encode_vsplits(&packets);
        for _ in 0..5000 {
            let mut bytes = good.clone();
            for _ in 0..rng.gen_range(1..4) {
                let k = rng.gen_range(0..bytes.len());
                bytes[k] = rng.gen();
            }
            let _ = decode_vsplits(&bytes);
        }
    }
}
