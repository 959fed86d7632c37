//! The page layout of one R-tree node. One node is one page (Shou 2002 §4.1: entries
//! of the form (MBR, ptr)); the fan-out follows from the page size.
//!
//! ```text
//! node payload (inside a store page of kind RtreeNode, after the page header)
//!   0  level   u16   0 = leaf
//!   2  count   u16   entries in this node
//!   4  reserved u32
//!   8  entries, `count` of them:
//!      internal entry (32 bytes)        leaf entry (56 bytes)
//!        0 mbr    6 x f32                 0 mbr        6 x f32
//!       24 child  u64 (page id)          24 id         u64
//!                                        32 mesh       Extent (16 bytes)
//!                                        48 triangles  u32
//!                                        52 kind       u8   (citygen::ObjectKind, 255 = other)
//!                                        53 reserved   3 bytes
//! ```
//!
//! A leaf entry carries everything a query needs to fetch the object (its mesh
//! extent), so no separate object table is read.

use crate::geom::Aabb;
use crate::store::Extent;

pub const NODE_HEADER_LEN: usize = 8;
const LEVEL_OFFSET: usize = 0;
const COUNT_OFFSET: usize = LEVEL_OFFSET + 2;

pub const MBR_LEN: usize = 24;
const CHILD_OFFSET: usize = MBR_LEN;
pub const INTERNAL_ENTRY_LEN: usize = CHILD_OFFSET + 8;

const ID_OFFSET: usize = MBR_LEN;
const MESH_OFFSET: usize = ID_OFFSET + 8;
const TRIANGLES_OFFSET: usize = MESH_OFFSET + 16;
const KIND_OFFSET: usize = TRIANGLES_OFFSET + 4;
pub const LEAF_ENTRY_LEN: usize = KIND_OFFSET + 4;

/// An object as the index knows it: what a query returns.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # citygen::write_city(&citygen::CityConfig { objects: 10, landmarks: 0.0, ..Default::default() }, &scene)?;
/// # flaneur::build_from_scene(&scene, &path, &Default::default())?;
/// let db = flaneur::Database::open(&path)?;
/// let first = db.range(&db.bounds())?.objects[0];
/// let mesh = db.mesh(&first)?; // the extent's pages, each checked
/// assert_eq!(mesh.triangle_count(), first.triangles as usize);
/// # Ok(()) }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObjectEntry {
    /// The object's id.
    pub id: u64,
    /// The box around the object's mesh.
    pub bounds: Aabb,
    /// Where the object's mesh lies in the database.
    pub mesh: Extent,
    /// Triangles of its full mesh.
    pub triangles: u32,
    /// `citygen::ObjectKind` as a byte; [`KIND_IMPORTED`](crate::scene::KIND_IMPORTED) (255)
    /// for imported objects.
    pub kind: u8,
}

/// An entry of an internal node: the MBR of a subtree and its page.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChildEntry {
    pub mbr: Aabb,
    pub page: u64,
}

/// A decoded node; the query path reads entries straight from the page instead.
#[derive(Clone, Debug, PartialEq)]
pub enum Node {
    Leaf(Vec<ObjectEntry>),
    Internal {
        level: u16,
        children: Vec<ChildEntry>,
    },
}

impl Node {
    pub fn level(&self) -> u16 {
        match self {
            Node::Leaf(_) => 0,
            Node::Internal { level, .. } => *level,
        }
    }

    pub fn len(&self) -> usize {
        match self {
            Node::Leaf(e) => e.len(),
            Node::Internal { children, .. } => children.len(),
        }
    }

    /// The MBR of all entries.
    pub fn mbr(&self) -> Aabb {
        match self {
            Node::Leaf(e) => e.iter().fold(Aabb::EMPTY, |b, o| b.union(&o.bounds)),
            Node::Internal { children, .. } => {
                children.iter().fold(Aabb::EMPTY, |b, c| b.union(&c.mbr))
            }
        }
    }

    pub fn encode(&self) -> Vec<u8> {
        let (entry_len, n) = match self {
            Node::Leaf(e) => (LEAF_ENTRY_LEN, e.len()),
            Node::Internal { children, .. } => (INTERNAL_ENTRY_LEN, children.len()),
        };
        let mut out = vec![0u8; NODE_HEADER_LEN + n * entry_len];
        out[LEVEL_OFFSET..LEVEL_OFFSET + 2].copy_from_slice(&self.level().to_le_bytes());
        out[COUNT_OFFSET..COUNT_OFFSET + 2].copy_from_slice(&(n as u16).to_le_bytes());
        for i in 0..n {
            let e = &mut out[NODE_HEADER_LEN + i * entry_len..][..entry_len];
            match self {
                Node::Leaf(objs) => {
                    let o = &objs[i];
                    e[..MBR_LEN].copy_from_slice(&o.bounds.to_le_bytes());
                    e[ID_OFFSET..ID_OFFSET + 8].copy_from_slice(&o.id.to_le_bytes());
                    e[MESH_OFFSET..MESH_OFFSET + 16].copy_from_slice(&o.mesh.to_le_bytes());
                    e[TRIANGLES_OFFSET..TRIANGLES_OFFSET + 4]
                        .copy_from_slice(&o.triangles.to_le_bytes());
                    e[KIND_OFFSET] = o.kind;
                }
                Node::Internal { children, .. } => {
                    let c = &children[i];
                    e[..MBR_LEN].copy_from_slice(&c.mbr.to_le_bytes());
                    e[CHILD_OFFSET..CHILD_OFFSET + 8].copy_from_slice(&c.page.to_le_bytes());
                }
            }
        }
        out
    }

    pub fn decode(payload: &[u8]) -> Result<Node, String> {
        let view = NodeView::parse(payload)?;
        Ok(if view.is_leaf() {
            Node::Leaf((0..view.len()).map(|i| view.object(i)).collect())
        } else {
            Node::Internal {
                level: view.level,
                children: (0..view.len()).map(|i| view.child(i)).collect(),
            }
        })
    }
}

/// A checked, zero-copy view of a node payload: the query path's reader.
pub struct NodeView<'a> {
    pub level: u16,
    count: usize,
    entries: &'a [u8],
}

impl<'a> NodeView<'a> {
    /// Checks the header and that all `count` entries lie inside the payload, so the
    /// accessors below cannot go out of bounds.
    pub fn parse(payload: &'a [u8]) -> Result<NodeView<'a>, String> {
        if payload.len() < NODE_HEADER_LEN {
            return Err(format!(
                "node payload of {} bytes is shorter than its header",
                payload.len()
            ));
        }
        let level = u16::from_le_bytes([payload[LEVEL_OFFSET], payload[LEVEL_OFFSET + 1]]);
        let count = u16::from_le_bytes([payload[COUNT_OFFSET], payload[COUNT_OFFSET + 1]]) as usize;
        let entry_len = if level == 0 {
            LEAF_ENTRY_LEN
        } else {
            INTERNAL_ENTRY_LEN
        };
        let need = NODE_HEADER_LEN + count * entry_len;
        if need > payload.len() {
            return Err(format!(
                "node claims {count} entries ({need} bytes) but holds {} bytes",
                payload.len()
            ));
        }
        Ok(NodeView {
            level,
            count,
            entries: &payload[NODE_HEADER_LEN..need],
        })
    }

    pub fn is_leaf(&self) -> bool {
        self.level == 0
    }

    pub fn len(&self) -> usize {
        self.count
    }

    #[inline]
    pub fn mbr(&self, i: usize) -> Aabb {
        let len = if self.is_leaf() {
            LEAF_ENTRY_LEN
        } else {
            INTERNAL_ENTRY_LEN
        };
        Aabb::from_le_bytes(self.entries[i * len..i * len + MBR_LEN].try_into().unwrap())
    }

    #[inline]
    pub fn child(&self, i: usize) -> ChildEntry {
        let e = &self.entries[i * INTERNAL_ENTRY_LEN..][..INTERNAL_ENTRY_LEN];
        ChildEntry {
            mbr: Aabb::from_le_bytes(e[..MBR_LEN].try_into().unwrap()),
            page: u64::from_le_bytes(e[CHILD_OFFSET..CHILD_OFFSET + 8].try_into().unwrap()),
        }
    }

    #[inline]
    pub fn object(&self, i: usize) -> ObjectEntry {
        let e = &self.entries[i * LEAF_ENTRY_LEN..][..LEAF_ENTRY_LEN];
        ObjectEntry {
            bounds: Aabb::from_le_bytes(e[..MBR_LEN].try_into().unwrap()),
            id: u64::from_le_bytes(e[ID_OFFSET..ID_OFFSET + 8].try_into().unwrap()),
            mesh: Extent::from_le_bytes(e[MESH_OFFSET..MESH_OFFSET + 16].try_into().unwrap()),
            triangles: u32::from_le_bytes(
                e[TRIANGLES_OFFSET..TRIANGLES_OFFSET + 4]
                    .try_into()
                    .unwrap(),
            ),
            kind: e[KIND_OFFSET],
        }
    }
}

/// Entries per node for a page payload size: the fan-out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fanout {
    /// The most entries of a leaf.
    pub leaf: usize,
    /// The most entries of an internal node.
    pub internal: usize,
}

impl Fanout {
    /// The fan-out of nodes in pages of `payload` bytes (a page less its header).
    pub fn for_payload(payload: usize) -> Fanout {
        let room = payload.saturating_sub(NODE_HEADER_LEN);
        Fanout {
            leaf: (room / LEAF_ENTRY_LEN).min(u16::MAX as usize),
            internal: (room / INTERNAL_ENTRY_LEN).min(u16::MAX as usize),
        }
    }

    /// The most entries of a node at `level` (0: a leaf).
    pub fn max(&self, level: u16) -> usize {
        if level == 0 {
            self.leaf
        } else {
            self.internal
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obj(id: u64) -> ObjectEntry {
        ObjectEntry {
            id,
            bounds: Aabb::new([id as f32, 0.0, 1.0], [id as f32 + 1.0, 2.0, 3.0]).unwrap(),
            mesh: Extent {
                first_page: 7 + id,
                page_count: 2,
                byte_len: 5000,
                ..Extent::default()
            },
            triangles: 300,
            kind: 1,
        }
    }

    #[test]
    fn round_trips() {
        let leaf = Node::Leaf((0..5).map(obj).collect());
        assert_eq!(Node::decode(&leaf.encode()).unwrap(), leaf);
        let internal = Node::Internal {
            level: 3,
            children: (0..4)
                .map(|i| ChildEntry {
                    mbr: obj(i).bounds,
                    page: 100 + i,
                })
                .collect(),
        };
        assert_eq!(Node::decode(&internal.encode()).unwrap(), internal);
    }

    #[test]
    fn a_count_past_the_payload_is_an_error() {
        let mut bytes = Node::Leaf((0..3).map(obj).collect()).encode();
        bytes[COUNT_OFFSET] = 200;
        assert!(Node::decode(&bytes).unwrap_err().contains("200 entries"));
        assert!(Node::decode(&bytes[..4]).is_err());
    }

    #[test]
    fn fanout_of_a_4k_page() {
        let f = Fanout::for_payload(4096 - 12);
        assert_eq!((f.leaf, f.internal), (72, 127));
    }
}
