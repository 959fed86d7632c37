//! What a page of the indexes holds: an R-tree node, an object's mesh, the HDoV-tree's
//! head, nodes and V-pages.

use crate::hdov::node::HNode;
use crate::hdov::vd::decode_vpage;
use crate::hdov::TreeHead;
use crate::rtree::node::{Node, NodeView};
use crate::scene::{decode_level_v2, decode_mesh, encode_mesh, Mesh, MeshCodec};

use super::{dictionaries, MAX_ITEMS};

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

/// An object's mesh as its extent holds it, in either codec `MeshCodec::from_bytes`
/// reads (format version 1's raw floats, version 2's meshoptimizer buffers with or
/// without zstd, with or without a dictionary, the target's own (`dictionaries`), in
/// either of its layouts). A version-2 blob's levels are each decoded
/// from its bytes too. A mesh that decodes must be one (`Mesh::validate`: indices name
/// vertices, positions and normals finite) and must round-trip: through version 1 to
/// the same positions and triangles, and through version 2 (zstd as the input had it)
/// to the same triangles, each with its corners where quantisation puts them.
pub fn mesh_codec(data: &[u8]) {
    let v2 = data.starts_with(GEOMETRY_MAGIC);
    if v2 && data.len() >= 8 {
        let levels = u16::from_le_bytes([data[6], data[7]]) as usize;
        for j in 0..levels.min(MAX_ITEMS) {
            if let Ok(level) = decode_level_v2(data, j, Some(dictionaries())) {
                valid(&level);
            }
        }
    }
    let Ok(mesh) = MeshCodec::from_bytes_with(data, Some(dictionaries())) else {
        return;
    };
    valid(&mesh);
    let again = decode_mesh(&encode_mesh(&mesh), None).expect("a decoded mesh encodes to a mesh");
    assert_eq!(
        (&again.positions, &again.indices),
        (&mesh.positions, &mesh.indices),
        "a mesh changed in its round trip"
    );
    let (lo, hi) = mesh.bounds();
    let flags = data.get(4).copied().filter(|_| v2).unwrap_or(0);
    let zstd = (flags & 1 != 0).then_some(1);
    let dict = (flags & 4 != 0).then(dictionaries);
    let written = MeshCodec::Meshopt { zstd }.encode_with(&mesh, dict);
    if (0..3).any(|k| !(hi[k] - lo[k]).is_finite()) && !mesh.positions.is_empty() {
        // Version 2 cannot hold a box wider than an f32 spans (its step would be
        // infinite): its writer must refuse the mesh, as its reader refuses the box.
        assert!(
            written.is_err(),
            "a mesh wider than an f32 spans was written"
        );
        return;
    }
    let bytes = written.expect("a decoded mesh encodes in format version 2");
    let again =
        MeshCodec::from_bytes_with(&bytes, dict).expect("a mesh encoded in version 2 decodes");
    valid(&again);
    let quantised = triangles(&mesh, |p| on_grid(lo, hi, p));
    assert!(
        triangles(&again, |p| p.map(f32::to_bits)) == quantised,
        "version 2 did not give back the triangles of a mesh of {} vertices and {} \
         triangles, quantised",
        mesh.positions.len(),
        mesh.triangle_count()
    );
}

/// The first bytes of a format-version-2 mesh (`scene::mesh_codec::geometry`).
const GEOMETRY_MAGIC: &[u8] = b"FLG2";

fn valid(mesh: &Mesh) {
    if let Err(what) = mesh.validate() {
        panic!("a decoded mesh is no mesh: {what}");
    }
}

/// Where version 2 reads back the position `p` of a mesh whose box is `lo..hi`: its 16
/// bits an axis over the box, the operations of `scene::mesh_codec::quantize` one for
/// one, so that the bits are the decoder's.
fn on_grid(lo: [f32; 3], hi: [f32; 3], p: [f32; 3]) -> [u32; 3] {
    const STEPS: f32 = 65535.0;
    std::array::from_fn(|k| {
        let span = hi[k] - lo[k];
        let q = if span > 0.0 {
            (((p[k] - lo[k]) / span).clamp(0.0, 1.0) * STEPS).round() as u16
        } else {
            0
        };
        (lo[k] + f32::from(q) * (span / STEPS))
            .clamp(lo[k], hi[k])
            .to_bits()
    })
}

/// A mesh's triangles as its corners' positions (`at` of each), in an order neither the
/// triangles' order nor a rotation of a triangle's corners changes (version 2 orders
/// triangles for the vertex cache, and meshoptimizer's index codec rotates them); the
/// winding stays.
fn triangles(mesh: &Mesh, at: impl Fn([f32; 3]) -> [u32; 3]) -> Vec<[[u32; 3]; 3]> {
    let mut all: Vec<[[u32; 3]; 3]> = mesh
        .indices
        .chunks_exact(3)
        .map(|t| {
            let c = [0, 1, 2].map(|i| at(mesh.positions[t[i] as usize]));
            let rotations = [c, [c[1], c[2], c[0]], [c[2], c[0], c[1]]];
            rotations.into_iter().min().expect("three rotations")
        })
        .collect();
    all.sort_unstable();
    all
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
