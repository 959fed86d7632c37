//! Data pages: the page header (kind, length, checksum) and its codec.
//!
//! Every page but page 0 (the file header, see `header.rs`) has this layout,
//! little-endian, `page_size` bytes in all:
//!
//! ```text
//! offset  width  field
//! ------  -----  --------------------------------------------------------------
//!      0      1  kind            PageKind as u8 (0 = never written)
//!      1      1  reserved        zero
//!      2      2  reserved        zero
//!      4      4  payload length  u32, at most page_size - PAGE_HEADER_LEN
//!      8      4  crc32           over bytes 0..8 and the payload bytes
//!     12      …  payload         `payload length` bytes
//!      …      …  padding         zero up to page_size (not checksummed)
//! ```
//!
//! The checksum covers the kind, the reserved bytes and the length as well as the
//! payload, so a page that was torn, rotted or written as another kind fails its check.

use std::fmt;

/// Offset of the kind byte.
pub(crate) const KIND_OFFSET: usize = 0;
/// Offset of the first reserved byte.
pub(crate) const RESERVED_U8_OFFSET: usize = KIND_OFFSET + 1;
/// Offset of the reserved u16.
pub(crate) const RESERVED_U16_OFFSET: usize = RESERVED_U8_OFFSET + 1;
/// Offset of the payload length (u32).
pub(crate) const LEN_OFFSET: usize = RESERVED_U16_OFFSET + 2;
/// Offset of the crc32 (u32).
pub(crate) const CRC_OFFSET: usize = LEN_OFFSET + 4;
/// Offset of the payload.
pub(crate) const PAYLOAD_OFFSET: usize = CRC_OFFSET + 4;

/// Bytes taken by the page header at the start of every data page; the payload of a
/// page is at most `page_size - PAGE_HEADER_LEN` bytes.
pub const PAGE_HEADER_LEN: usize = PAYLOAD_OFFSET;

/// Number of counter slots indexed by kind byte: room for kinds added later.
pub const KIND_SLOTS: usize = 16;

/// What a page holds. Stored as the first byte of every data page and checked on every
/// read, so that a reader asking for an R-tree node never decodes a mesh.
///
/// ```
/// use flaneur::store::PageKind;
/// assert_eq!(PageKind::from_u8(2), Some(PageKind::RtreeNode));
/// assert_eq!(PageKind::Mesh.name(), "mesh");
/// assert_eq!(PageKind::from_u8(5), Some(PageKind::Lod));
/// assert_eq!(PageKind::from_u8(6), Some(PageKind::Visibility));
/// assert_eq!(PageKind::from_u8(8), Some(PageKind::VPage));
/// assert_eq!(PageKind::ALL.len(), 8);
/// ```
#[repr(u8)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PageKind {
    /// Page 0, the file header (it has its own layout, see `header.rs`).
    Header = 1,
    /// A node of a disk-resident R-tree.
    RtreeNode = 2,
    /// An object's full-detail mesh.
    Mesh = 3,
    /// Anything else an owner wants to store (metadata blobs, tables).
    Meta = 4,
    /// Level-of-detail data: an object's chain of coarser levels, its progressive mesh
    /// and DAG, and the table that finds them by object id. A kind of its own so that
    /// reads of LOD pages are counted apart from reads of full meshes.
    Lod = 5,
    /// Precomputed visibility: the viewcells, and each cell's potentially visible set
    /// with its objects' degrees of visibility. Counted apart, as PVS reads are the
    /// currency of the PVS prefetcher.
    Visibility = 6,
    /// A node of the HDoV-tree (its view-invariant part: the entries, with each
    /// child's h, s and internal LODs), and the tree's head.
    HdovNode = 7,
    /// The HDoV-tree's view-variant part: V-pages (each node's DoV and count of visible
    /// objects per entry, for one viewcell) and the V-page-indexes that find them.
    VPage = 8,
}

const _: () = assert!((PageKind::VPage as usize) < KIND_SLOTS);

impl PageKind {
    /// Every kind, in kind-byte order.
    pub const ALL: [PageKind; 8] = [
        PageKind::Header,
        PageKind::RtreeNode,
        PageKind::Mesh,
        PageKind::Meta,
        PageKind::Lod,
        PageKind::Visibility,
        PageKind::HdovNode,
        PageKind::VPage,
    ];

    /// The kind stored as byte `b`, if any.
    pub fn from_u8(b: u8) -> Option<PageKind> {
        PageKind::ALL.into_iter().find(|k| *k as u8 == b)
    }

    /// A short lower-case name, for messages and reports.
    pub fn name(self) -> &'static str {
        match self {
            PageKind::Header => "header",
            PageKind::RtreeNode => "rtree-node",
            PageKind::Mesh => "mesh",
            PageKind::Meta => "meta",
            PageKind::Lod => "lod",
            PageKind::Visibility => "visibility",
            PageKind::HdovNode => "hdov-node",
            PageKind::VPage => "v-page",
        }
    }
}

impl fmt::Display for PageKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The name of a kind byte for messages, known or not.
fn byte_name(b: u8) -> String {
    match PageKind::from_u8(b) {
        Some(k) => k.name().to_string(),
        None => format!("unknown kind byte {b:#04x}"),
    }
}

fn page_crc(head: &[u8], payload: &[u8]) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(head);
    h.update(payload);
    h.finalize()
}

/// Appends one encoded page (`page_size` bytes) holding `payload` to `out`.
/// The caller has checked `payload.len() <= page_size - PAGE_HEADER_LEN`.
pub(crate) fn encode_into(kind: PageKind, payload: &[u8], page_size: usize, out: &mut Vec<u8>) {
    debug_assert!(payload.len() <= page_size - PAGE_HEADER_LEN);
    let mut head = [0u8; PAGE_HEADER_LEN];
    head[KIND_OFFSET] = kind as u8;
    // Reserved bytes stay zero. The length fits in u32: page_size <= 64 KiB.
    head[LEN_OFFSET..CRC_OFFSET].copy_from_slice(&(payload.len() as u32).to_le_bytes());
    let crc = page_crc(&head[..CRC_OFFSET], payload);
    head[CRC_OFFSET..PAYLOAD_OFFSET].copy_from_slice(&crc.to_le_bytes());
    let start = out.len();
    out.extend_from_slice(&head);
    out.extend_from_slice(payload);
    out.resize(start + page_size, 0);
}

/// Encodes one page into `dst`, which is exactly one page long.
pub(crate) fn encode_in_place(kind: PageKind, payload: &[u8], dst: &mut [u8]) {
    let mut v = Vec::with_capacity(dst.len());
    encode_into(kind, payload, dst.len(), &mut v);
    dst.copy_from_slice(&v);
}

fn read_u32(b: &[u8], at: usize) -> u32 {
    let mut w = [0u8; 4];
    if let Some(s) = b.get(at..at + 4) {
        w.copy_from_slice(s);
    }
    u32::from_le_bytes(w)
}

/// Whether one whole page is intact: written (kind byte not 0), its payload length
/// within the page, its checksum right. What a cache of raw pages checks before it
/// trusts one it kept (a hole in a sparse file reads as a blank page).
pub(crate) fn intact(page: &[u8]) -> bool {
    if page.len() < PAGE_HEADER_LEN || page[KIND_OFFSET] == 0 {
        return false;
    }
    let len = read_u32(page, LEN_OFFSET) as usize;
    len <= page.len() - PAGE_HEADER_LEN
        && read_u32(page, CRC_OFFSET)
            == page_crc(
                &page[..CRC_OFFSET],
                &page[PAYLOAD_OFFSET..PAYLOAD_OFFSET + len],
            )
}

/// Rewrites the checksum of `page` to that of its head and payload, when its payload
/// length fits the page: damaged bytes that pass the checksum, so that a fuzz target
/// reaches the checks after it.
pub(crate) fn reseal(page: &mut [u8]) {
    if page.len() < PAGE_HEADER_LEN {
        return;
    }
    let len = read_u32(page, LEN_OFFSET) as usize;
    if len > page.len() - PAGE_HEADER_LEN {
        return;
    }
    let crc = page_crc(
        &page[..CRC_OFFSET],
        &page[PAYLOAD_OFFSET..PAYLOAD_OFFSET + len],
    );
    page[CRC_OFFSET..PAYLOAD_OFFSET].copy_from_slice(&crc.to_le_bytes());
}

/// Checks one whole page (`page.len()` = page size) against its header and the
/// expected kind, and returns its payload. The error says what is wrong, for
/// `Error::CorruptPage`.
pub(crate) fn decode(page: &[u8], expected: PageKind) -> Result<&[u8], String> {
    if page.len() < PAGE_HEADER_LEN {
        return Err(format!(
            "page is {} bytes, shorter than its header",
            page.len()
        ));
    }
    let kind_byte = page[KIND_OFFSET];
    if kind_byte == 0 {
        return Err("blank page (kind byte 0): it was never written".to_string());
    }
    let len = read_u32(page, LEN_OFFSET) as usize;
    let capacity = page.len() - PAGE_HEADER_LEN;
    if len > capacity {
        return Err(format!(
            "payload length {len} exceeds the {capacity} bytes a page can hold"
        ));
    }
    let payload = &page[PAYLOAD_OFFSET..PAYLOAD_OFFSET + len];
    let stored = read_u32(page, CRC_OFFSET);
    let actual = page_crc(&page[..CRC_OFFSET], payload);
    if stored != actual {
        return Err(format!(
            "checksum mismatch (stored {stored:#010x}, computed {actual:#010x})"
        ));
    }
    if kind_byte != expected as u8 {
        return Err(format!(
            "wrong page kind: expected {}, found {}",
            expected.name(),
            byte_name(kind_byte)
        ));
    }
    Ok(payload)
}

#[cfg(test)]
mod tests {
    use super::*;

    const PS: usize = 1024;

    fn page(kind: PageKind, payload: &[u8]) -> Vec<u8> {
        let mut v = Vec::new();
        encode_into(kind, payload, PS, &mut v);
        v
    }

    #[test]
    fn layout_constants() {
        assert_eq!(LEN_OFFSET, 4);
        assert_eq!(CRC_OFFSET, 8);
        assert_eq!(PAGE_HEADER_LEN, 12);
    }

    #[test]
    fn kinds_round_trip() {
        for k in PageKind::ALL {
            assert_eq!(PageKind::from_u8(k as u8), Some(k));
            assert!(!k.name().is_empty());
        }
        assert_eq!(PageKind::from_u8(0), None);
        assert_eq!(PageKind::from_u8(200), None);
    }

    #[test]
    fn encode_decode() {
        for len in [0, 1, 100, PS - PAGE_HEADER_LEN] {
            let payload: Vec<u8> = (0..len).map(|i| (i * 7) as u8).collect();
            let p = page(PageKind::Mesh, &payload);
            assert_eq!(p.len(), PS);
            assert_eq!(decode(&p, PageKind::Mesh).unwrap(), &payload[..]);
            let mut q = vec![0u8; PS];
            encode_in_place(PageKind::Mesh, &payload, &mut q);
            assert_eq!(p, q);
        }
    }

    #[test]
    fn every_header_and_payload_byte_is_checked() {
        let payload = [9u8; 40];
        let p = page(PageKind::RtreeNode, &payload);
        for i in 0..PAGE_HEADER_LEN + payload.len() {
            let mut q = p.clone();
            q[i] ^= 0x10;
            assert!(
                decode(&q, PageKind::RtreeNode).is_err(),
                "flip at byte {i} undetected"
            );
        }
    }

    #[test]
    fn errors_say_what() {
        let p = page(PageKind::Mesh, b"abc");
        let e = decode(&p, PageKind::RtreeNode).unwrap_err();
        assert!(
            e.contains("expected rtree-node") && e.contains("found mesh"),
            "{e}"
        );
        assert!(decode(&vec![0u8; PS], PageKind::Mesh)
            .unwrap_err()
            .contains("blank"));
        let mut q = p.clone();
        q[LEN_OFFSET..CRC_OFFSET].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(decode(&q, PageKind::Mesh)
            .unwrap_err()
            .contains("payload length"));
        let mut q = p.clone();
        q[PAYLOAD_OFFSET] ^= 1;
        assert!(decode(&q, PageKind::Mesh).unwrap_err().contains("checksum"));
        assert!(decode(&p[..5], PageKind::Mesh).is_err());
    }
}
