//! Extents: a blob stored in a run of contiguous pages of one kind.
//!
//! Each page of an extent is an ordinary data page (own header and checksum, see
//! `page.rs`). An extent is either *whole* (written by `Store::append_extent`: it owns
//! its pages, every page but the last is full, the last holds the remainder) or
//! *packed* (written by `Store::append_packed`: it starts at a byte offset inside its
//! first page's payload and may share its first and last pages with other packed blobs
//! of the same kind; every page of its run but the last is full, and the last holds at
//! least the blob's end). A reference to an extent is 16 bytes, little-endian:
//!
//! ```text
//! offset  width  field
//! ------  -----  ---------------------------------------------------------------
//!      0      8  first page  u64
//!      8      4  whole:  page count u32 (0 for an empty blob), bit 31 clear
//!                packed: bit 31 set; bits 16..30 page count (1..=32767),
//!                        bits 0..15 byte offset of the blob in its first page's payload
//!     12      4  byte length u32, the blob's length
//! ```
//!
//! Why the flag lives in the page count's top bit: it keeps the reference 16 bytes, so
//! that every structure holding extents (R-tree leaves, HDoV nodes, LOD tables) keeps
//! its layout, and a whole extent encodes exactly as in every file written before
//! packing, bit for bit. No such file sets bit 31: a blob is at most 4 GiB - 1 bytes
//! and a page holds at least 1 KiB - `PAGE_HEADER_LEN` payload bytes, so it never
//! takes 2^31 pages. A payload is under 64 KiB, so 16 bits hold any offset inside it;
//! the 15 bits left count up to 32767 pages (32 MiB of 1 KiB pages, 2 GiB of 64 KiB
//! ones): a larger blob is stored whole.

/// Offset of the first page id in an encoded extent.
const FIRST_PAGE_OFFSET: usize = 0;
/// Offset of the page count (and, packed, the byte offset).
const PAGE_COUNT_OFFSET: usize = FIRST_PAGE_OFFSET + 8;
/// Offset of the byte length.
const BYTE_LEN_OFFSET: usize = PAGE_COUNT_OFFSET + 4;

/// Bit 31 of the page-count word: the extent is packed.
const PACKED_FLAG: u32 = 1 << 31;
/// Where a packed extent's page count starts in the page-count word.
const PACKED_COUNT_SHIFT: u32 = 16;
/// A packed extent's byte offset: bits 0..15 of the page-count word.
const PACKED_OFFSET_MASK: u32 = (1 << PACKED_COUNT_SHIFT) - 1;

/// Where a blob lives: `page_count` contiguous pages from `first_page`, holding
/// `byte_len` bytes from byte `offset` of the first page's payload on. Written by
/// `Store::append_extent` (whole: `offset` 0, `packed` false) and
/// `Store::append_packed`; read by `Store::read_extent`.
///
/// ```
/// use flaneur::store::Extent;
/// let e = Extent { first_page: 42, page_count: 3, byte_len: 10_000, ..Extent::default() };
/// assert_eq!(Extent::from_le_bytes(&e.to_le_bytes()), e);
/// let p = Extent { first_page: 7, page_count: 2, byte_len: 5_000, offset: 300, packed: true };
/// assert_eq!(Extent::from_le_bytes(&p.to_le_bytes()), p);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Extent {
    /// The first page of the run.
    pub first_page: u64,
    /// Pages in the run.
    pub page_count: u32,
    /// The blob's length in bytes.
    pub byte_len: u32,
    /// The blob's first byte inside the first page's payload: 0 for a whole extent,
    /// below [`Extent::MAX_PACKED_OFFSET`] + 1 for a packed one.
    pub offset: u32,
    /// Whether the blob may share its first and last pages with other packed blobs of
    /// its kind (and its last page may hold more than its end).
    pub packed: bool,
}

impl Extent {
    /// Bytes taken by an encoded extent.
    pub const ENCODED_LEN: usize = BYTE_LEN_OFFSET + 4;

    /// The most pages a packed extent may span (15 bits); a longer blob is stored whole.
    pub const MAX_PACKED_PAGES: u32 = (PACKED_FLAG >> PACKED_COUNT_SHIFT) - 1;

    /// The largest byte offset a packed extent can record (16 bits): more than any
    /// page's payload.
    pub const MAX_PACKED_OFFSET: u32 = PACKED_OFFSET_MASK;

    /// The 16-byte little-endian encoding. A packed extent's page count and offset must
    /// fit their bits ([`Extent::MAX_PACKED_PAGES`], [`Extent::MAX_PACKED_OFFSET`]), as
    /// every packed extent the store writes does; bits beyond them are dropped.
    pub fn to_le_bytes(&self) -> [u8; Extent::ENCODED_LEN] {
        let count_word = if self.packed {
            debug_assert!(self.page_count <= Extent::MAX_PACKED_PAGES);
            debug_assert!(self.offset <= Extent::MAX_PACKED_OFFSET);
            PACKED_FLAG
                | (self.page_count & Extent::MAX_PACKED_PAGES) << PACKED_COUNT_SHIFT
                | (self.offset & PACKED_OFFSET_MASK)
        } else {
            self.page_count
        };
        let mut b = [0u8; Extent::ENCODED_LEN];
        b[FIRST_PAGE_OFFSET..PAGE_COUNT_OFFSET].copy_from_slice(&self.first_page.to_le_bytes());
        b[PAGE_COUNT_OFFSET..BYTE_LEN_OFFSET].copy_from_slice(&count_word.to_le_bytes());
        b[BYTE_LEN_OFFSET..].copy_from_slice(&self.byte_len.to_le_bytes());
        b
    }

    /// Decodes the 16-byte little-endian encoding.
    pub fn from_le_bytes(b: &[u8; Extent::ENCODED_LEN]) -> Extent {
        let mut first = [0u8; 8];
        let mut count = [0u8; 4];
        let mut len = [0u8; 4];
        first.copy_from_slice(&b[FIRST_PAGE_OFFSET..PAGE_COUNT_OFFSET]);
        count.copy_from_slice(&b[PAGE_COUNT_OFFSET..BYTE_LEN_OFFSET]);
        len.copy_from_slice(&b[BYTE_LEN_OFFSET..]);
        let count_word = u32::from_le_bytes(count);
        let packed = count_word & PACKED_FLAG != 0;
        let (page_count, offset) = if packed {
            (
                (count_word & !PACKED_FLAG) >> PACKED_COUNT_SHIFT,
                count_word & PACKED_OFFSET_MASK,
            )
        } else {
            (count_word, 0)
        };
        Extent {
            first_page: u64::from_le_bytes(first),
            page_count,
            byte_len: u32::from_le_bytes(len),
            offset,
            packed,
        }
    }

    /// Whether the blob is empty (no pages).
    pub fn is_empty(&self) -> bool {
        self.byte_len == 0
    }

    /// The page after the extent's last page.
    pub fn end_page(&self) -> u64 {
        self.first_page.saturating_add(u64::from(self.page_count))
    }

    /// The page that holds byte `at` of the blob, with `payload_size` bytes per page.
    /// For a whole extent this is `first_page + at / payload_size`; a packed one counts
    /// from its offset.
    pub fn page_of(&self, at: u64, payload_size: usize) -> u64 {
        let abs = u64::from(self.offset).saturating_add(at);
        self.first_page
            .saturating_add(abs / payload_size.max(1) as u64)
    }

    /// What is wrong with the extent's shape with `payload_size` bytes per page, if
    /// anything: a whole extent must start at byte 0 and take the pages its length
    /// needs; a packed one must hold a byte, start inside its first page's payload and
    /// span the pages its offset and length need. Where the pages lie is not checked.
    pub fn shape_problem(&self, payload_size: usize) -> Option<String> {
        let (byte_len, offset) = (self.byte_len as usize, self.offset as usize);
        let claims = self.page_count;
        if !self.packed {
            let need = Extent::pages_for(byte_len, payload_size);
            if offset != 0 {
                return Some(format!(
                    "a whole extent of {byte_len} bytes starts at byte {offset} of its first page"
                ));
            }
            return (need != claims as usize).then(|| {
                format!(
                    "extent of {byte_len} bytes needs {need} pages of {payload_size} payload \
                     bytes, it claims {claims}"
                )
            });
        }
        if offset >= payload_size {
            return Some(format!(
                "packed extent of {byte_len} bytes starts at byte {offset}, past the \
                 {payload_size} payload bytes of its first page"
            ));
        }
        if byte_len == 0 {
            return Some("a packed extent of 0 bytes".to_string());
        }
        let need = Extent::pages_spanned(offset, byte_len, payload_size);
        (need != claims as usize).then(|| {
            format!(
                "packed extent of {byte_len} bytes at byte {offset} needs {need} pages of \
                 {payload_size} payload bytes, it claims {claims}"
            )
        })
    }

    /// How many pages a blob of `byte_len` bytes takes with `payload_size` bytes per page.
    pub fn pages_for(byte_len: usize, payload_size: usize) -> usize {
        byte_len.div_ceil(payload_size.max(1))
    }

    /// How many pages a blob of `byte_len` bytes spans when it starts at byte `offset`
    /// of its first page's payload (a packed extent): 0 for an empty blob.
    pub fn pages_spanned(offset: usize, byte_len: usize, payload_size: usize) -> usize {
        if byte_len == 0 {
            return 0;
        }
        offset
            .saturating_add(byte_len)
            .div_ceil(payload_size.max(1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codec() {
        let e = Extent {
            first_page: 0x0102_0304_0506_0708,
            page_count: 0x0a0b_0c0d,
            byte_len: 7,
            ..Extent::default()
        };
        let b = e.to_le_bytes();
        assert_eq!(b.len(), 16);
        assert_eq!(b[0], 0x08);
        assert_eq!(b[8], 0x0d);
        assert_eq!(b[12], 7);
        assert_eq!(Extent::from_le_bytes(&b), e);
    }

    #[test]
    fn whole_extent_encodes_as_in_version_1() {
        // The bytes a version-1 file holds for 3 pages from page 42, 10,000 bytes.
        let v1: [u8; 16] = [42, 0, 0, 0, 0, 0, 0, 0, 3, 0, 0, 0, 0x10, 0x27, 0, 0];
        let e = Extent::from_le_bytes(&v1);
        assert_eq!(
            e,
            Extent {
                first_page: 42,
                page_count: 3,
                byte_len: 10_000,
                offset: 0,
                packed: false
            }
        );
        assert_eq!(e.to_le_bytes(), v1);
        // The largest page count a version-1 file can hold decodes as a count.
        let mut most = v1;
        most[8..12].copy_from_slice(&(PACKED_FLAG - 1).to_le_bytes());
        let e = Extent::from_le_bytes(&most);
        assert!(!e.packed);
        assert_eq!(e.page_count, PACKED_FLAG - 1);
        assert_eq!(e.to_le_bytes(), most);
    }

    #[test]
    fn packed_codec() {
        let e = Extent {
            first_page: 9,
            page_count: Extent::MAX_PACKED_PAGES,
            byte_len: 123,
            offset: Extent::MAX_PACKED_OFFSET,
            packed: true,
        };
        let b = e.to_le_bytes();
        assert_eq!(u32::from_le_bytes(b[8..12].try_into().unwrap()), u32::MAX);
        assert_eq!(Extent::from_le_bytes(&b), e);
        // A packed extent at offset 0 stays packed.
        let e = Extent {
            offset: 0,
            page_count: 1,
            ..e
        };
        let b = e.to_le_bytes();
        assert_eq!(&b[8..12], &[0, 0, 1, 0x80]);
        assert_eq!(Extent::from_le_bytes(&b), e);
    }

    #[test]
    fn pages_for() {
        assert_eq!(Extent::pages_for(0, 100), 0);
        assert_eq!(Extent::pages_for(1, 100), 1);
        assert_eq!(Extent::pages_for(100, 100), 1);
        assert_eq!(Extent::pages_for(101, 100), 2);
        assert_eq!(Extent::pages_spanned(0, 0, 100), 0);
        assert_eq!(Extent::pages_spanned(99, 1, 100), 1);
        assert_eq!(Extent::pages_spanned(99, 2, 100), 2);
        assert_eq!(Extent::pages_spanned(50, 150, 100), 2);
        assert_eq!(Extent::pages_spanned(50, 151, 100), 3);
    }

    #[test]
    fn page_of() {
        let whole = Extent {
            first_page: 10,
            page_count: 3,
            byte_len: 250,
            ..Extent::default()
        };
        assert_eq!(whole.page_of(0, 100), 10);
        assert_eq!(whole.page_of(199, 100), 11);
        let packed = Extent {
            offset: 60,
            packed: true,
            ..whole
        };
        assert_eq!(packed.page_of(0, 100), 10);
        assert_eq!(packed.page_of(40, 100), 11);
        assert_eq!(packed.page_of(249, 100), 13);
    }
}
