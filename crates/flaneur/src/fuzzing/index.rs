//! What a page of the indexes holds: an R-tree node, an object's mesh, the HDoV-tree's
//! head, nodes and V-pages.

use crate::hdov::node::HNode;
use crate::hdov::vd::decode_vpage;
use crate::hdov::TreeHead;
use crate::rtree::node::{Node, NodeView};
use crate::scene::{decode_mesh, encode_mesh};

/// An R-tree node's payload, through the query path's checked view (every entry read)
/// and the whole-node decoder; a node that decodes encodes back to the same node.
pub fn rtree_node(data: &[u8]) {
    if let Ok(view) = NodeView::parse(data) {
        for i in 0..view.len() {
            let _ = view.mbr(i);
            if view.is_leaf() {
                let _ = view.object(i);
            } else {
                let _ = view.child(i);
            }
        }
    }
    if let Ok(node) = Node::decode(data) {
        let again = Node::decode(&node.encode()).expect("a decoded node encodes to a node");
        assert_eq!(
            again.encode(),
            node.encode(),
            "a node changed in its round trip"
        );
    }
}

/// An object's mesh as its extent holds it; a mesh that decodes encodes back to one
/// with the same positions and triangles.
pub fn mesh_codec(data: &[u8]) {
    if let Ok(mesh) = decode_mesh(data) {
        let again = decode_mesh(&encode_mesh(&mesh)).expect("a decoded mesh encodes to a mesh");
        assert_eq!(
            (again.positions, again.indices),
            (mesh.positions, mesh.indices),
            "a mesh changed in its round trip"
        );
    }
}

/// The HDoV-tree's pieces, the first byte choosing which: 0 the tree's head (as it is,
/// and with its checksum rewritten); 1 a node's payload, after the tree's node count
/// (u32); 2 a V-page, after its entry count (u16) and the tree's object count (u64).
pub fn hdov(data: &[u8]) {
    let Some((&which, rest)) = data.split_first() else {
        return;
    };
    match which % 3 {
        0 => {
            for b in [rest.to_vec(), super::resealed_tail(rest)] {
                if let Ok(head) = TreeHead::decode(&b) {
                    let _ = head.smallest_scheme();
                    let again =
                        TreeHead::decode(&head.encode()).expect("a decoded head encodes to a head");
                    assert_eq!(
                        again.encode(),
                        head.encode(),
                        "a head changed in its round trip"
                    );
                }
            }
        }
        1 => {
            let Some((nodes, payload)) = rest.split_first_chunk::<4>() else {
                return;
            };
            if let Ok(node) = HNode::decode(payload, u32::from_le_bytes(*nodes)) {
                let again = HNode::decode(&node.encode(), u32::from_le_bytes(*nodes))
                    .expect("a decoded node encodes to a node");
                assert_eq!(
                    again.encode(),
                    node.encode(),
                    "a node changed in its round trip"
                );
            }
        }
        _ => {
            let Some((entries, rest)) = rest.split_first_chunk::<2>() else {
                return;
            };
            let Some((objects, payload)) = rest.split_first_chunk::<8>() else {
                return;
            };
            let entries = u16::from_le_bytes(*entries) as usize;
            let _ = decode_vpage(payload, entries, u64::from_le_bytes(*objects));
        }
    }
}
