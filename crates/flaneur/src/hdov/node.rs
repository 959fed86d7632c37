//! The page layout of one HDoV-tree node: its view-invariant part (Shou 2002 §5.2.2).
//! One node is one page; the nodes are written in depth-first preorder, back to back,
//! so that node `n` is page `first + n` and a child is named by its number alone.
//!
//! ```text
//! node payload (inside a store page of kind HdovNode, after the page header)
//!   0  level   u16   0 = leaf
//!   2  count   u16   entries in this node
//!   4  number  u32   the node's depth-first number (its V-entries' place in a V-page
//!                    index segment)
//!   8  entries, `count` of them, 56 bytes each:
//!      internal entry                       leaf entry (as the R-tree's)
//!        0 mbr      6 x f32                   0 mbr        6 x f32
//!       24 child    u32, its number          24 id         u64
//!       28 objects  u32, m: objects below    32 mesh       Extent (16 bytes)
//!       32 h        f32, log_M m (eq. 5.3)   48 triangles  u32
//!       36 s        f32, its faces over its  52 kind       u8
//!                   children's (eq. 5.4)     53 reserved   3 bytes
//!       40 lods     Extent (16 bytes): the child's internal LODs, an LOD chain
//!                   (`lod::encode_chain`), empty when it has none
//! ```
//!
//! A parent's entry carries what the search needs to stop at the child (h, s and its
//! LODs), so that stopping reads no page of the child.

use crate::geom::Aabb;
use crate::rtree::ObjectEntry;
use crate::store::framing::{f32_at, u32_at, u64_at};
use crate::store::Extent;

const HEADER_LEN: usize = 8;
/// Bytes of one entry, internal or leaf.
pub const ENTRY_LEN: usize = 56;
const MBR_LEN: usize = 24;

/// The entries a node page of `payload` bytes holds.
pub fn capacity(payload: usize) -> usize {
    payload.saturating_sub(HEADER_LEN) / ENTRY_LEN
}

/// An internal node's entry: a child node and what the search decides by.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChildRef {
    pub mbr: Aabb,
    /// The child's depth-first number.
    pub node: u32,
    /// Objects below the child (m), its estimated height h = log_M m, and s, its
    /// faces over its children's total (eqs. 5.3–5.4).
    pub objects: u32,
    pub h: f32,
    pub s: f32,
    /// The child's internal LODs (an LOD chain), empty when it has none.
    pub lods: Extent,
}

/// A decoded node.
#[derive(Clone, Debug, PartialEq)]
pub struct HNode {
    /// Its depth-first number.
    pub number: u32,
    pub kind: HNodeKind,
}

/// A node's entries.
#[derive(Clone, Debug, PartialEq)]
pub enum HNodeKind {
    Leaf(Vec<ObjectEntry>),
    Internal { level: u16, children: Vec<ChildRef> },
}

impl HNode {
    /// Entries in the node.
    pub fn len(&self) -> usize {
        match &self.kind {
            HNodeKind::Leaf(o) => o.len(),
            HNodeKind::Internal { children, .. } => children.len(),
        }
    }

    pub fn level(&self) -> u16 {
        match &self.kind {
            HNodeKind::Leaf(_) => 0,
            HNodeKind::Internal { level, .. } => *level,
        }
    }

    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(HEADER_LEN + self.len() * ENTRY_LEN);
        out.extend_from_slice(&self.level().to_le_bytes());
        out.extend_from_slice(&(self.len() as u16).to_le_bytes());
        out.extend_from_slice(&self.number.to_le_bytes());
        match &self.kind {
            HNodeKind::Leaf(objects) => {
                for o in objects {
                    out.extend_from_slice(&o.bounds.to_le_bytes());
                    out.extend_from_slice(&o.id.to_le_bytes());
                    out.extend_from_slice(&o.mesh.to_le_bytes());
                    out.extend_from_slice(&o.triangles.to_le_bytes());
                    out.extend_from_slice(&[o.kind, 0, 0, 0]);
                }
            }
            HNodeKind::Internal { children, .. } => {
                for c in children {
                    out.extend_from_slice(&c.mbr.to_le_bytes());
                    out.extend_from_slice(&c.node.to_le_bytes());
                    out.extend_from_slice(&c.objects.to_le_bytes());
                    out.extend_from_slice(&c.h.to_le_bytes());
                    out.extend_from_slice(&c.s.to_le_bytes());
                    out.extend_from_slice(&c.lods.to_le_bytes());
                }
            }
        }
        out
    }

    /// Decodes a node's payload; the complaint names what is wrong. `nodes` is how many
    /// nodes the tree has, so that a child's number is checked.
    pub fn decode(b: &[u8], nodes: u32) -> Result<HNode, String> {
        if b.len() < HEADER_LEN {
            return Err(format!("an HDoV node of {} bytes has no header", b.len()));
        }
        let level = u16::from_le_bytes([b[0], b[1]]);
        let count = u16::from_le_bytes([b[2], b[3]]) as usize;
        let number = u32_at(b, 4);
        if b.len() != HEADER_LEN + count * ENTRY_LEN {
            return Err(format!(
                "an HDoV node of {count} entries takes {} bytes, the page holds {}",
                HEADER_LEN + count * ENTRY_LEN,
                b.len()
            ));
        }
        let entry = |i: usize| &b[HEADER_LEN + i * ENTRY_LEN..][..ENTRY_LEN];
        let mbr = |e: &[u8]| -> Result<Aabb, String> {
            let bounds = Aabb::from_le_bytes(e[..MBR_LEN].try_into().expect("24 bytes"));
            bounds.validate().map_err(|e| e.to_string())?;
            Ok(bounds)
        };
        let extent = |e: &[u8], at: usize| {
            Extent::from_le_bytes(e[at..at + Extent::ENCODED_LEN].try_into().expect("16"))
        };
        let kind = if level == 0 {
            let mut objects = Vec::with_capacity(count);
            for i in 0..count {
                let e = entry(i);
                objects.push(ObjectEntry {
                    bounds: mbr(e)?,
                    id: u64_at(e, 24),
                    mesh: extent(e, 32),
                    triangles: u32_at(e, 48),
                    kind: e[52],
                });
            }
            HNodeKind::Leaf(objects)
        } else {
            let mut children = Vec::with_capacity(count);
            for i in 0..count {
                let e = entry(i);
                let c = ChildRef {
                    mbr: mbr(e)?,
                    node: u32_at(e, 24),
                    objects: u32_at(e, 28),
                    h: f32_at(e, 32),
                    s: f32_at(e, 36),
                    lods: extent(e, 40),
                };
                if c.node <= number || c.node >= nodes {
                    return Err(format!(
                        "entry {i} names child node {} (this node is {number}, the tree has {nodes})",
                        c.node
                    ));
                }
                if !(c.h.is_finite() && c.h >= 0.0 && c.s.is_finite() && c.s > 0.0) {
                    return Err(format!(
                        "entry {i}: h {} and s {} are not a node's",
                        c.h, c.s
                    ));
                }
                children.push(c);
            }
            HNodeKind::Internal { level, children }
        };
        Ok(HNode { number, kind })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn object(id: u64) -> ObjectEntry {
        ObjectEntry {
            id,
            bounds: Aabb::new([0.0; 3], [id as f32 + 1.0; 3]).unwrap(),
            mesh: Extent {
                first_page: 3 + id,
                page_count: 1,
                byte_len: 100,
                ..Extent::default()
            },
            triangles: 12,
            kind: 2,
        }
    }

    #[test]
    fn nodes_round_trip_and_bad_children_are_named() {
        let leaf = HNode {
            number: 4,
            kind: HNodeKind::Leaf(vec![object(1), object(2)]),
        };
        assert_eq!(HNode::decode(&leaf.encode(), 9).unwrap(), leaf);
        let child = ChildRef {
            mbr: object(1).bounds,
            node: 5,
            objects: 70,
            h: 1.1,
            s: 0.2,
            lods: Extent::default(),
        };
        let internal = HNode {
            number: 2,
            kind: HNodeKind::Internal {
                level: 1,
                children: vec![child],
            },
        };
        assert_eq!(HNode::decode(&internal.encode(), 9).unwrap(), internal);
        let e = HNode::decode(&internal.encode(), 5).unwrap_err();
        assert!(e.contains("child node 5"), "{e}");
        let e = HNode::decode(&internal.encode()[..20], 9).unwrap_err();
        assert!(e.contains("takes 64 bytes"), "{e}");
        assert_eq!(capacity(4096 - 16), (4096 - 16 - 8) / 56);
    }
}
