//! The page file's framing: the header page with its segment table, and data pages.

use crate::hdov::node::HNode;
use crate::hdov::vd::decode_vpage;
use crate::store::{page, Header, PageKind};

/// Header and segment table: the bytes as a header page, then cut or padded to the page
/// size their prefix names with the checksum rewritten. A header that decodes encodes
/// back to one that decodes the same.
pub fn db_header(data: &[u8]) {
    let _ = Header::check_prefix(data);
    let _ = Header::decode(data);
    let Ok(Some(page_size)) = Header::check_prefix(data) else {
        return;
    };
    let mut page = data.to_vec();
    page.resize(page_size, 0);
    Header::reseal(&mut page);
    if let Ok(header) = Header::decode(&page) {
        let mut again = vec![0; page_size];
        header.encode(&mut again);
        assert_eq!(
            Header::decode(&again).ok(),
            Some(header),
            "a decoded header encodes back to another"
        );
    }
}

/// Page framing: the bytes as one data page (their length its page size) checked as
/// every kind, as they are and with the checksum rewritten; a payload that passes goes
/// to the decoder of its kind.
pub fn db_page(data: &[u8]) {
    let mut sealed = data.to_vec();
    page::reseal(&mut sealed);
    for bytes in [data, &sealed[..]] {
        let _ = page::intact(bytes);
        for kind in PageKind::ALL {
            if let Ok(payload) = page::decode(bytes, kind) {
                payload_of(kind, payload);
            }
        }
    }
}

/// A checked page's payload to the decoder of its kind.
fn payload_of(kind: PageKind, payload: &[u8]) {
    match kind {
        PageKind::RtreeNode => super::rtree_node(payload),
        PageKind::Mesh => super::mesh_codec(payload),
        PageKind::HdovNode => {
            let _ = HNode::decode(payload, u32::MAX);
        }
        PageKind::VPage => {
            let _ = decode_vpage(payload, payload.len() / 8, u64::MAX);
        }
        _ => {}
    }
}
