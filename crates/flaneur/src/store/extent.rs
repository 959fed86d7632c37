//! Extents: a blob stored as a run of contiguous pages of one kind.
//!
//! Each page of an extent is an ordinary data page (own header and checksum, see
//! `page.rs`); every page but the last is full, the last holds the remainder. A
//! reference to an extent is 16 bytes, little-endian:
//!
//! ```text
//! offset  width  field
//! ------  -----  ---------------------------------------------
//!      0      8  first page  u64
//!      8      4  page count  u32 (0 for an empty blob)
//!     12      4  byte length u32, the blob's length
//! ```

/// Offset of the first page id in an encoded extent.
const FIRST_PAGE_OFFSET: usize = 0;
/// Offset of the page count.
const PAGE_COUNT_OFFSET: usize = FIRST_PAGE_OFFSET + 8;
/// Offset of the byte length.
const BYTE_LEN_OFFSET: usize = PAGE_COUNT_OFFSET + 4;

/// Where a blob lives: `page_count` contiguous pages from `first_page`, holding
/// `byte_len` bytes. Written by `Store::append_extent`, read by `Store::read_extent`.
///
/// ```
/// use flaneur::store::Extent;
/// let e = Extent { first_page: 42, page_count: 3, byte_len: 10_000 };
/// assert_eq!(Extent::from_le_bytes(&e.to_le_bytes()), e);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Extent {
    /// The first page of the run.
    pub first_page: u64,
    /// Pages in the run.
    pub page_count: u32,
    /// The blob's length in bytes.
    pub byte_len: u32,
}

impl Extent {
    /// Bytes taken by an encoded extent.
    pub const ENCODED_LEN: usize = BYTE_LEN_OFFSET + 4;

    /// The 16-byte little-endian encoding.
    pub fn to_le_bytes(&self) -> [u8; Extent::ENCODED_LEN] {
        let mut b = [0u8; Extent::ENCODED_LEN];
        b[FIRST_PAGE_OFFSET..PAGE_COUNT_OFFSET].copy_from_slice(&self.first_page.to_le_bytes());
        b[PAGE_COUNT_OFFSET..BYTE_LEN_OFFSET].copy_from_slice(&self.page_count.to_le_bytes());
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
        Extent {
            first_page: u64::from_le_bytes(first),
            page_count: u32::from_le_bytes(count),
            byte_len: u32::from_le_bytes(len),
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

    /// How many pages a blob of `byte_len` bytes takes with `payload_size` bytes per page.
    pub fn pages_for(byte_len: usize, payload_size: usize) -> usize {
        byte_len.div_ceil(payload_size.max(1))
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
        };
        let b = e.to_le_bytes();
        assert_eq!(b.len(), 16);
        assert_eq!(b[0], 0x08);
        assert_eq!(b[8], 0x0d);
        assert_eq!(b[12], 7);
        assert_eq!(Extent::from_le_bytes(&b), e);
    }

    #[test]
    fn pages_for() {
        assert_eq!(Extent::pages_for(0, 100), 0);
        assert_eq!(Extent::pages_for(1, 100), 1);
        assert_eq!(Extent::pages_for(100, 100), 1);
        assert_eq!(Extent::pages_for(101, 100), 2);
    }
}
