//! The page file's framing: the header page with its segment table, and data pages.

use crate::hdov::node::HNode;
use crate::hdov::vd::decode_vpage;
use crate::store::{page, Extent, Header, PageKind, Store};

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
/// to the decoder of its kind. Then extents: the first 16 bytes as an extent reference
/// (whole or packed), the rest as blobs packed into a store of 1 KiB pages, each read
/// back as written, and the reference read against that store.
pub fn db_page(data: &[u8]) {
    extents(data);
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

/// The most blobs one input packs.
const MAX_BLOBS: usize = 4 * super::MAX_ITEMS;

/// Extents: `data`'s first 16 bytes decoded as a reference (it must encode back to the
/// same bytes), the rest cut into blobs (a length byte, times 8, then the bytes; its low
/// bit picks the kind) packed into a new store and read back whole and by range; then
/// the reference, its first page moved into the store, read whole and by range, which
/// must return or fail, never panic.
fn extents(data: &[u8]) {
    let Some((head, mut rest)) = data.split_first_chunk::<{ Extent::ENCODED_LEN }>() else {
        return;
    };
    let e = Extent::from_le_bytes(head);
    assert_eq!(
        &e.to_le_bytes(),
        head,
        "an extent reference re-encodes to other bytes"
    );
    super::with_file("extents", &[], |path| {
        let Ok(mut store) = Store::create(path, 1024) else {
            return;
        };
        let mut blobs = Vec::new();
        while let Some((&n, tail)) = rest.split_first() {
            if blobs.len() == MAX_BLOBS {
                break;
            }
            let len = (n as usize * 8).min(tail.len());
            let (blob, tail) = tail.split_at(len);
            rest = tail;
            let kind = if n & 1 == 0 {
                PageKind::Mesh
            } else {
                PageKind::Lod
            };
            let Ok(ext) = store.append_packed(kind, blob) else {
                return;
            };
            blobs.push((kind, ext, blob));
        }
        for (kind, ext, blob) in &blobs {
            let got = store.read_extent(ext, *kind).ok();
            assert_eq!(
                got.as_deref(),
                Some(*blob),
                "a packed blob reads back changed"
            );
            let mid = blob.len() / 2;
            let got = store
                .read_extent_range(ext, *kind, mid, blob.len() - mid)
                .ok();
            assert_eq!(
                got.as_deref(),
                Some(&blob[mid..]),
                "a packed range reads back changed"
            );
        }
        let pages = store.page_count();
        let inside = Extent {
            first_page: e.first_page % pages,
            ..e
        };
        for ext in [e, inside] {
            for kind in [PageKind::Mesh, PageKind::Lod] {
                let _ = store.read_extent(&ext, kind);
                let len = ext.byte_len as usize;
                let _ = store.read_extent_range(&ext, kind, len / 3, len / 3);
            }
        }
    });
}
