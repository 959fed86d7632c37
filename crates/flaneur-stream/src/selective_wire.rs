//! Truly selective streaming's packets on the wire (Kim–Lee–Kobbelt Fig. 3b): a batch
//! of vertex splits, each the node's ⟨tree-id, node-id⟩, its fundamental cut vertices'
//! names, the new vertex, and what `qrefine` reads of both children; under leaf
//! placement (ours, for crease runs) also its run's first node and the leaves of the
//! triangles it adds. A node-id is as many bits as its node is deep, sent in whole
//! bytes after its bit count.
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
//!     run: None,
//!     leaves: [None, None],
//! };
//! let bytes = encode_vsplits(std::slice::from_ref(&packet));
//! assert_eq!(decode_vsplits(&bytes)?, [packet]);
//! # Ok::<(), flaneur_stream::StreamError>(())
//! ```

use flaneur::lod::{HeapIndex, NodeName, RefineInfo, SelectiveBase, VsplitPacket};

use crate::error::StreamError;
use crate::wire::{Reader, Writer};

/// The deepest node a name may name: far below what a hostile count could make a
/// reader allocate, far above any hierarchy of ours.
pub const MAX_NAME_BITS: usize = 1 << 16;

/// The fewest bytes a name takes: its tree-id, bit count and one byte.
pub(crate) const MIN_NAME: usize = 4 + 2 + 1;

/// The fewest bytes one packet takes: a name of one byte, the flags, the new vertex.
const MIN_PACKET: usize = MIN_NAME + 1 + 24;

/// A batch of vsplit packets as bytes.
pub fn encode_vsplits(packets: &[VsplitPacket]) -> Vec<u8> {
    let mut w = Writer::default();
    write_vsplits(&mut w, packets);
    w.bytes
}

/// The batch `bytes` hold. An error naming the byte for anything that is not one
/// batch: a count past the bytes left, a name of zero or deeper than
/// [`MAX_NAME_BITS`], unknown flags, bytes past its end.
pub fn decode_vsplits(bytes: &[u8]) -> Result<Vec<VsplitPacket>, StreamError> {
    let mut r = Reader::new(bytes, "vsplit batch");
    let packets = read_vsplits(&mut r)?;
    r.end()?;
    Ok(packets)
}

/// A batch: its count, then each packet.
pub(crate) fn write_vsplits(w: &mut Writer, packets: &[VsplitPacket]) {
    w.count(packets.len());
    for p in packets {
        write_name(w, &p.node);
        let leaves = p.leaves.iter().any(Option::is_some);
        let flags = p.cuts[0].is_some() as u8
            | (p.cuts[1].is_some() as u8) << 1
            | (p.children[0].is_some() as u8) << 2
            | (p.children[1].is_some() as u8) << 3
            | (p.run.is_some() as u8) << 4
            | (leaves as u8) << 5;
        w.u8(flags);
        for c in p.cuts.iter().flatten() {
            write_name(w, c);
        }
        w.vec3(p.position);
        w.vec3(p.normal);
        for i in p.children.iter().flatten() {
            write_info(w, i);
        }
        if let Some(run) = &p.run {
            write_name(w, run);
        }
        if leaves {
            // Each triangle's leaves below the left and the right child, as the bits
            // below the child's.
            for (side, cut) in p.cuts.iter().enumerate() {
                if cut.is_some() {
                    let [left, right] = p.leaves[side]
                        .clone()
                        .unwrap_or_else(|| [child(&p.node, false), child(&p.node, true)]);
                    write_suffix(w, &child(&p.node, false), &left);
                    write_suffix(w, &child(&p.node, true), &right);
                }
            }
        }
    }
}

fn child(n: &NodeName, right: bool) -> NodeName {
    NodeName {
        tree: n.tree,
        node: n.node.child(right),
    }
}

/// The bits of `leaf` below `above` (which it descends from): their count, u16, then
/// the bits, most significant first, in whole bytes.
fn write_suffix(w: &mut Writer, above: &NodeName, leaf: &NodeName) {
    let k = leaf.depth().saturating_sub(above.depth());
    w.u16(u16::try_from(k).unwrap_or(u16::MAX));
    let mut bytes = vec![0u8; (k as usize).div_ceil(8)];
    for i in 0..k {
        // Bit i of the suffix, from the top: the step down from depth above + i.
        if leaf.up(k - 1 - i).node.words()[0] & 1 == 1 {
            bytes[(i / 8) as usize] |= 0x80 >> (i % 8);
        }
    }
    w.raw(&bytes);
}

/// The name below `above` that a suffix names.
fn read_suffix(r: &mut Reader<'_>, above: &NodeName) -> Result<NodeName, StreamError> {
    let k = r.u16()? as usize;
    if above.depth() as usize + 1 + k > MAX_NAME_BITS {
        return Err(r.bad(format!(
            "a leaf {k} levels below a node, deeper than allowed"
        )));
    }
    let bytes = r.raw(k.div_ceil(8))?;
    let mut node = above.node.clone();
    for i in 0..k {
        node = node.child(bytes[i / 8] & (0x80 >> (i % 8)) != 0);
    }
    Ok(NodeName {
        tree: above.tree,
        node,
    })
}

pub(crate) fn read_vsplits(r: &mut Reader<'_>) -> Result<Vec<VsplitPacket>, StreamError> {
    let n = r.count(MIN_PACKET)?;
    let mut packets = Vec::with_capacity(n);
    for _ in 0..n {
        let node = read_name(r)?;
        let flags = r.u8()?;
        if flags & !0b11_1111 != 0 {
            return Err(r.bad(format!("unknown flags {flags:#04x}")));
        }
        let cut = |r: &mut Reader<'_>, bit: u8| -> Result<Option<NodeName>, StreamError> {
            (flags & bit != 0).then(|| read_name(r)).transpose()
        };
        let cuts = [cut(r, 1)?, cut(r, 2)?];
        let (position, normal) = (r.vec3()?, r.vec3()?);
        let info = |r: &mut Reader<'_>, bit: u8| -> Result<Option<RefineInfo>, StreamError> {
            (flags & bit != 0).then(|| read_info(r)).transpose()
        };
        let children = [info(r, 4)?, info(r, 8)?];
        let run = (flags & 16 != 0).then(|| read_name(r)).transpose()?;
        let mut leaves = [None, None];
        if flags & 32 != 0 {
            for (side, cut) in cuts.iter().enumerate() {
                if cut.is_some() {
                    let left = read_suffix(r, &child(&node, false))?;
                    let right = read_suffix(r, &child(&node, true))?;
                    leaves[side] = Some([left, right]);
                }
            }
        }
        packets.push(VsplitPacket {
            node,
            cuts,
            position,
            normal,
            children,
            run,
            leaves,
        });
    }
    Ok(packets)
}

/// What `qrefine` reads of a node: 44 bytes.
fn write_info(w: &mut Writer, i: &RefineInfo) {
    w.vec3(i.centre);
    w.vec3(i.axis);
    w.f32(i.radius);
    w.f32(i.cone_sin);
    w.f32(i.error);
}

fn read_info(r: &mut Reader<'_>) -> Result<RefineInfo, StreamError> {
    Ok(RefineInfo {
        centre: r.vec3()?,
        axis: r.vec3()?,
        radius: r.f32()?,
        cone_sin: r.f32()?,
        error: r.f32()?,
    })
}

/// A client's start: its roots (position, normal, a flag and what `qrefine` reads of
/// it when the flag is 1), the base triangles, corners as tree-ids, then the placement
/// (0 cut vertices, 1 leaf corners, each base triangle's three leaves following).
pub(crate) fn write_base(w: &mut Writer, base: &SelectiveBase) {
    w.count(base.roots.len());
    for (position, normal, info) in &base.roots {
        w.vec3(*position);
        w.vec3(*normal);
        w.u8(info.is_some() as u8);
        if let Some(i) = info {
            write_info(w, i);
        }
    }
    w.count(base.triangles.len());
    base.triangles.iter().flatten().for_each(|&v| w.u32(v));
    match &base.leaves {
        None => w.u8(0),
        Some(leaves) => {
            w.u8(1);
            leaves.iter().flatten().for_each(|n| write_name(w, n));
        }
    }
}

pub(crate) fn read_base(r: &mut Reader<'_>) -> Result<SelectiveBase, StreamError> {
    let n = r.count(25)?;
    let mut roots = Vec::with_capacity(n);
    for _ in 0..n {
        let (position, normal) = (r.vec3()?, r.vec3()?);
        let info = match r.u8()? {
            0 => None,
            1 => Some(read_info(r)?),
            f => return Err(r.bad(format!("a root's flag {f}, not 0 or 1"))),
        };
        roots.push((position, normal, info));
    }
    let nt = r.count(12)?;
    let mut triangles = Vec::with_capacity(nt);
    for _ in 0..nt {
        let t = [r.u32()?, r.u32()?, r.u32()?];
        if let Some(v) = t.iter().find(|&&v| v as usize >= n) {
            return Err(r.bad(format!("a base triangle's corner {v}, of {n} roots")));
        }
        triangles.push(t);
    }
    let leaves = match r.u8()? {
        0 => None,
        1 => {
            r.fits(nt, 3 * MIN_NAME)?;
            let mut leaves = Vec::with_capacity(nt);
            for t in &triangles {
                let corners = [read_name(r)?, read_name(r)?, read_name(r)?];
                if let Some(k) = (0..3).find(|&k| corners[k].tree != t[k]) {
                    return Err(r.bad(format!(
                        "a base triangle's leaf in tree {}, its corner being root {}",
                        corners[k].tree, t[k]
                    )));
                }
                leaves.push(corners);
            }
            Some(leaves)
        }
        p => return Err(r.bad(format!("placement {p}, not 0 or 1"))),
    };
    Ok(SelectiveBase {
        triangles,
        roots,
        leaves,
    })
}

/// A name: its tree-id, its node-id's bit count, then the node-id in whole bytes,
/// least significant first.
pub(crate) fn write_name(w: &mut Writer, n: &NodeName) {
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

/// The bytes [`write_name`] writes for `n`.
pub(crate) fn name_len(n: &NodeName) -> usize {
    4 + 2 + (n.node.bits() as usize).div_ceil(8)
}

pub(crate) fn read_name(r: &mut Reader<'_>) -> Result<NodeName, StreamError> {
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
