//! The LOD data a build stores: an object's chain of levels, its progressive mesh and
//! DAG, and the table that finds them.

use crate::error::Error;
use crate::lod::stored::chain::{head_len, ChainDirectory};
use crate::lod::stored::read::ProgressiveBytes;
use crate::lod::stored::table::{decode_head, reseal_head};
use crate::lod::{Dag, ProgressiveMesh, SelectiveSource};
use crate::scene::{expand_frame, is_frame, squeeze};

/// The payload of a page of each page size the LOD table's target may choose.
const PAYLOADS: [usize; 3] = [1012, 4084, 65524];

/// An LOD chain (directory and levels) of either version (1: each level a mesh of its
/// own; 2: one blob of meshoptimizer's buffers whose levels share a vertex buffer, a
/// level read with every coarser one), as it is and with its checksums rewritten: its
/// directory from the whole chain and from its first page, then every level from the
/// bytes the directory says a reader of it takes.
pub fn lod_chain(data: &[u8]) {
    let mut sealed = data.to_vec();
    ChainDirectory::reseal(&mut sealed);
    for b in [data, &sealed[..]] {
        let _ = head_len(b, PAYLOADS[0]);
        let _ = ChainDirectory::decode(&b[..b.len().min(PAYLOADS[0])], b.len());
        let Ok(dir) = ChainDirectory::decode(b, b.len()) else {
            continue;
        };
        let _ = dir.levels();
        for level in 0..=dir.stored_levels() + 1 {
            let Ok((start, end)) = dir.read_range(level) else {
                continue;
            };
            if let Some(bytes) = b.get(start..end) {
                let _ = dir.decode_level(level, bytes, None);
            }
        }
    }
}

/// A progressive mesh and its DAG: a u32 (the PM's share of the rest, modulo its
/// length), the PM's bytes, the DAG's, each its own codec's bytes (format version 1) or a
/// zstd frame around them (version 2). Each decoded as it is and with its checksum
/// rewritten (inside the frame, framed again), then the two checked against each other
/// as a database's are; a pair that passes is walked split by split to the full mesh and
/// back, and served selectively.
pub fn lod_pm_dag(data: &[u8]) {
    let Some((split, rest)) = data.split_first_chunk::<4>() else {
        return;
    };
    let at = u32::from_le_bytes(*split) as usize % (rest.len() + 1);
    let (pm, dag) = rest.split_at(at);
    for (pm, dag) in [
        (pm.to_vec(), dag.to_vec()),
        (resealed_inside(pm), resealed_inside(dag)),
    ] {
        let triangles = match unframed(&pm).map(|b| ProgressiveMesh::from_bytes(&b)) {
            Some(Ok(p)) => p.triangle_map.len() as u32,
            _ => 0,
        };
        if let Some(b) = unframed(&dag) {
            let _ = Dag::from_bytes(&b);
        }
        let Ok((pm, dag)) = ProgressiveBytes::from_parts(0, triangles, pm, dag).decode() else {
            continue;
        };
        if let Ok(mut cursor) = pm.cursor() {
            while let Ok(true) = cursor.refine() {}
            while let Ok(true) = cursor.coarsen() {}
        }
        let _ = SelectiveSource::new(&pm, &dag);
    }
}

/// The most a PM's or DAG's zstd frame expands to here: the reader's bound
/// (`lod::stored::read`), 64 times the frame and 64 KiB.
fn frame_bound(frame: &[u8]) -> usize {
    frame.len().saturating_mul(64).saturating_add(1 << 16)
}

/// The codec's bytes of a PM or DAG: a zstd frame's contents, or the bytes themselves;
/// `None` for a frame that does not expand.
fn unframed(b: &[u8]) -> Option<Vec<u8>> {
    if is_frame(b) {
        expand_frame(b, frame_bound(b)).ok()
    } else {
        Some(b.to_vec())
    }
}

/// `b` with its checksum (its last four bytes) rewritten, inside its zstd frame when it
/// is one (framed again as a build frames it), so that mutated contents reach the
/// codec's checks.
fn resealed_inside(b: &[u8]) -> Vec<u8> {
    if !is_frame(b) {
        return super::resealed_tail(b);
    }
    match expand_frame(b, frame_bound(b)) {
        Ok(inner) => squeeze(&super::resealed_tail(&inner), Some(1)).unwrap_or_else(|_| b.to_vec()),
        Err(_) => b.to_vec(),
    }
}

/// The LOD table: the first byte chooses the page size (payload 1012, 4084 or 65524
/// bytes), the rest is the table. Its head as it is and with its checksum rewritten;
/// then each entry page against the fence, and each entry against a file of as many
/// pages as the table could name.
pub fn lod_table(data: &[u8]) {
    let Some((&which, table)) = data.split_first() else {
        return;
    };
    let payload = PAYLOADS[which as usize % PAYLOADS.len()];
    let mut sealed = table.to_vec();
    reseal_head(&mut sealed, payload);
    for b in [table, &sealed[..]] {
        let first = b[..b.len().min(payload)].to_vec();
        let more = |start: usize, len: usize| {
            start
                .checked_add(len)
                .and_then(|end| b.get(start..end))
                .map(<[u8]>::to_vec)
                .ok_or_else(|| Error::Invalid("the head lies beyond the table".into()))
        };
        let Ok(head) = decode_head(first, b.len(), payload, 0, more) else {
            continue;
        };
        for k in 0..head.entry_pages() {
            let (start, len) = head.entry_page_place(k, payload);
            let Some(page) = start.checked_add(len).and_then(|end| b.get(start..end)) else {
                continue;
            };
            for e in head.entry_page(k, page).into_iter().flatten() {
                let _ = e.problem(u64::MAX, payload);
            }
        }
    }
}
