//! Page 0: the file header and its segment table.
//!
//! Page 0 of every database file has this layout, little-endian, `page_size` bytes:
//!
//! ```text
//! offset        width  field
//! ------------  -----  ----------------------------------------------------------
//!            0      8  magic           b"FLANEUR\0"
//!            8      4  version         u32, OLDEST_FORMAT_VERSION..=FORMAT_VERSION
//!           12      4  page size       u32, a power of two in 1 KiB..=64 KiB
//!           16      8  page count      u64, pages in the file, page 0 included
//!           24      4  segment count   u32, n
//!           28      4  reserved        zero
//!           32   40*n  segment table   n entries:
//!                        +0   16  name  ascii, 1..=15 bytes, NUL-padded to 16
//!                        +16   8  a     u64 } meaning belongs to the segment's
//!                        +24   8  b     u64 } owner (e.g. "rtree": root page,
//!                        +32   8  c     u64 } height, object count)
//!    32 + 40*n      4  crc32           over the whole page with this field skipped
//!    36 + 40*n      …  zero            up to page_size
//! ```
//!
//! The checksum covers every byte of page 0 except itself, zero tail included, so a
//! flipped bit anywhere in the header is caught on open.

use std::fmt;

/// The first eight bytes of every database file.
pub const MAGIC: [u8; 8] = *b"FLANEUR\0";
/// The format version this build writes unless asked for version 1. Version 2 added
/// packed extents (several blobs sharing a page, `extent.rs`) and meshoptimizer-coded
/// meshes (`scene::MeshCodec`); a version-1 reader cannot read them, so a file that may
/// hold them says 2.
pub const FORMAT_VERSION: u32 = 2;
/// The oldest format version this build reads: every file written before version 2.
pub const OLDEST_FORMAT_VERSION: u32 = 1;
/// Smallest page size a database may have.
pub const MIN_PAGE_SIZE: usize = 1024;
/// Largest page size a database may have.
pub const MAX_PAGE_SIZE: usize = 64 * 1024;
/// The page size used unless one is chosen at build.
pub const DEFAULT_PAGE_SIZE: usize = 4096;

pub(crate) const MAGIC_OFFSET: usize = 0;
pub(crate) const VERSION_OFFSET: usize = MAGIC_OFFSET + MAGIC.len();
pub(crate) const PAGE_SIZE_OFFSET: usize = VERSION_OFFSET + 4;
pub(crate) const PAGE_COUNT_OFFSET: usize = PAGE_SIZE_OFFSET + 4;
pub(crate) const SEGMENT_COUNT_OFFSET: usize = PAGE_COUNT_OFFSET + 8;
pub(crate) const RESERVED_OFFSET: usize = SEGMENT_COUNT_OFFSET + 4;
pub(crate) const SEGMENT_TABLE_OFFSET: usize = RESERVED_OFFSET + 4;
/// The fixed part of the header, before the segment table: enough to learn the page
/// size and validate magic and version.
pub(crate) const PREFIX_LEN: usize = SEGMENT_TABLE_OFFSET;

pub(crate) const SEG_NAME_OFFSET: usize = 0;
pub(crate) const SEG_NAME_LEN: usize = 16;
pub(crate) const SEG_A_OFFSET: usize = SEG_NAME_OFFSET + SEG_NAME_LEN;
pub(crate) const SEG_B_OFFSET: usize = SEG_A_OFFSET + 8;
pub(crate) const SEG_C_OFFSET: usize = SEG_B_OFFSET + 8;
/// Bytes per segment table entry.
pub(crate) const SEGMENT_LEN: usize = SEG_C_OFFSET + 8;
/// Longest segment name, in bytes (one byte of the 16 stays NUL).
pub const MAX_SEGMENT_NAME_LEN: usize = SEG_NAME_LEN - 1;
pub(crate) const CRC_LEN: usize = 4;

/// Whether `page_size` is a page size a database may have.
pub fn valid_page_size(page_size: usize) -> bool {
    page_size.is_power_of_two() && (MIN_PAGE_SIZE..=MAX_PAGE_SIZE).contains(&page_size)
}

/// How many segments fit in the header page of a database with this page size.
pub fn max_segments(page_size: usize) -> usize {
    page_size.saturating_sub(SEGMENT_TABLE_OFFSET + CRC_LEN) / SEGMENT_LEN
}

/// A small named record in the header whose meaning belongs to its owner, e.g.
/// `"rtree"`: `a` = root page, `b` = height, `c` = object count.
///
/// ```
/// use flaneur::store::Segment;
/// let s = Segment::new("rtree", 7, 3, 1000);
/// assert_eq!((s.name.as_str(), s.a, s.b, s.c), ("rtree", 7, 3, 1000));
/// ```
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Segment {
    /// 1..=15 ascii bytes, no NUL.
    pub name: String,
    /// The first of the owner's values (for `"rtree"`, the root page).
    pub a: u64,
    /// The second (for `"rtree"`, the height).
    pub b: u64,
    /// The third (for `"rtree"`, the object count).
    pub c: u64,
}

impl Segment {
    /// A segment named `name` with values `a`, `b`, `c`. The name is checked when the
    /// segment is stored (`Store::set_segment`).
    pub fn new(name: impl Into<String>, a: u64, b: u64, c: u64) -> Segment {
        Segment {
            name: name.into(),
            a,
            b,
            c,
        }
    }

    /// Why this segment's name cannot be stored, if it cannot.
    pub(crate) fn name_problem(&self) -> Option<String> {
        let n = &self.name;
        if n.is_empty() {
            Some("segment name is empty".to_string())
        } else if n.len() > MAX_SEGMENT_NAME_LEN {
            Some(format!(
                "segment name {n:?} is {} bytes; at most {MAX_SEGMENT_NAME_LEN} fit",
                n.len()
            ))
        } else if !n.bytes().all(|b| b.is_ascii() && b != 0) {
            Some(format!(
                "segment name {n:?} must be ascii without NUL bytes"
            ))
        } else {
            None
        }
    }
}

/// The decoded file header (page 0). Read-only to users: the store keeps it current
/// and writes it at `flush`/`finish`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Header {
    pub(crate) version: u32,
    pub(crate) page_size: u32,
    pub(crate) page_count: u64,
    pub(crate) segments: Vec<Segment>,
}

/// Why page 0 could not be decoded.
#[derive(Debug, PartialEq, Eq)]
pub(crate) enum HeaderError {
    /// Not a flaneur database at all (magic, version, page size).
    NotADatabase(String),
    /// A flaneur database whose header page is damaged.
    Corrupt(String),
}

impl fmt::Display for HeaderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            HeaderError::NotADatabase(s) | HeaderError::Corrupt(s) => f.write_str(s),
        }
    }
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    let mut w = [0u8; 4];
    if let Some(s) = b.get(at..at + 4) {
        w.copy_from_slice(s);
    }
    u32::from_le_bytes(w)
}

fn u64_at(b: &[u8], at: usize) -> u64 {
    let mut w = [0u8; 8];
    if let Some(s) = b.get(at..at + 8) {
        w.copy_from_slice(s);
    }
    u64::from_le_bytes(w)
}

fn header_crc(page: &[u8], crc_offset: usize) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(page.get(..crc_offset).unwrap_or(&[]));
    h.update(page.get(crc_offset + CRC_LEN..).unwrap_or(&[]));
    h.finalize()
}

impl super::Store {
    /// Marks the file being written as format `version` (at least
    /// [`OLDEST_FORMAT_VERSION`]): a build that writes nothing version 2 added (raw
    /// meshes, whole-page extents) says 1, so that readers of version 1 read it too.
    pub(crate) fn write_as_version(&mut self, version: u32) -> crate::Result<()> {
        if !(OLDEST_FORMAT_VERSION..=FORMAT_VERSION).contains(&version) {
            return Err(crate::Error::Invalid(format!(
                "format version {version}: this build writes {OLDEST_FORMAT_VERSION}..={FORMAT_VERSION}"
            )));
        }
        self.header.version = version;
        Ok(())
    }
}

impl Header {
    /// A fresh header: one page (itself), no segments.
    pub(crate) fn new(page_size: usize) -> Header {
        Header {
            version: FORMAT_VERSION,
            page_size: page_size as u32,
            page_count: 1,
            segments: Vec::new(),
        }
    }

    /// The format version of the file.
    pub fn version(&self) -> u32 {
        self.version
    }

    /// The page size of the file, in bytes.
    pub fn page_size(&self) -> usize {
        self.page_size as usize
    }

    /// Pages in the file, header page included.
    pub fn page_count(&self) -> u64 {
        self.page_count
    }

    /// All segments, in the order they were first set.
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// The segment named `name`, if any.
    pub fn segment(&self, name: &str) -> Option<&Segment> {
        self.segments.iter().find(|s| s.name == name)
    }

    /// How many segments fit in this header.
    pub fn max_segments(&self) -> usize {
        max_segments(self.page_size())
    }

    /// Inserts `seg` or replaces the segment of the same name.
    pub(crate) fn set_segment(&mut self, seg: Segment) -> Result<(), String> {
        if let Some(why) = seg.name_problem() {
            return Err(why);
        }
        if let Some(s) = self.segments.iter_mut().find(|s| s.name == seg.name) {
            *s = seg;
            return Ok(());
        }
        let max = self.max_segments();
        if self.segments.len() >= max {
            return Err(format!(
                "segment table full: {max} segments fit in a {}-byte header page; cannot add {:?}",
                self.page_size, seg.name
            ));
        }
        self.segments.push(seg);
        Ok(())
    }

    /// Encodes the header into `page` (exactly one page long).
    pub(crate) fn encode(&self, page: &mut [u8]) {
        page.fill(0);
        page[MAGIC_OFFSET..VERSION_OFFSET].copy_from_slice(&MAGIC);
        page[VERSION_OFFSET..PAGE_SIZE_OFFSET].copy_from_slice(&self.version.to_le_bytes());
        page[PAGE_SIZE_OFFSET..PAGE_COUNT_OFFSET].copy_from_slice(&self.page_size.to_le_bytes());
        page[PAGE_COUNT_OFFSET..SEGMENT_COUNT_OFFSET]
            .copy_from_slice(&self.page_count.to_le_bytes());
        page[SEGMENT_COUNT_OFFSET..RESERVED_OFFSET]
            .copy_from_slice(&(self.segments.len() as u32).to_le_bytes());
        for (i, s) in self.segments.iter().enumerate() {
            let e = &mut page[SEGMENT_TABLE_OFFSET + i * SEGMENT_LEN..][..SEGMENT_LEN];
            e[SEG_NAME_OFFSET..SEG_NAME_OFFSET + s.name.len()].copy_from_slice(s.name.as_bytes());
            e[SEG_A_OFFSET..SEG_B_OFFSET].copy_from_slice(&s.a.to_le_bytes());
            e[SEG_B_OFFSET..SEG_C_OFFSET].copy_from_slice(&s.b.to_le_bytes());
            e[SEG_C_OFFSET..SEGMENT_LEN].copy_from_slice(&s.c.to_le_bytes());
        }
        let crc_offset = SEGMENT_TABLE_OFFSET + self.segments.len() * SEGMENT_LEN;
        let crc = header_crc(page, crc_offset);
        page[crc_offset..crc_offset + CRC_LEN].copy_from_slice(&crc.to_le_bytes());
    }

    /// Checks the fixed prefix (magic, version, page size) of a file that starts with
    /// `prefix` (the file's first bytes, possibly fewer than `PREFIX_LEN`) and returns
    /// the page size. `Ok(None)`: the bytes seen so far are right but too few.
    pub(crate) fn check_prefix(prefix: &[u8]) -> Result<Option<usize>, HeaderError> {
        if prefix.is_empty() {
            return Err(HeaderError::NotADatabase("the file is empty".to_string()));
        }
        let m = prefix.len().min(MAGIC.len());
        if prefix[..m] != MAGIC[..m] {
            return Err(HeaderError::NotADatabase(format!(
                "bad magic {:02x?} (expected {:02x?} \"FLANEUR\\0\")",
                &prefix[..m],
                &MAGIC[..m]
            )));
        }
        if prefix.len() < PREFIX_LEN {
            return Ok(None);
        }
        let version = u32_at(prefix, VERSION_OFFSET);
        if !(OLDEST_FORMAT_VERSION..=FORMAT_VERSION).contains(&version) {
            return Err(HeaderError::NotADatabase(format!(
                "format version {version}; this build reads versions \
                 {OLDEST_FORMAT_VERSION}..={FORMAT_VERSION}"
            )));
        }
        let page_size = u32_at(prefix, PAGE_SIZE_OFFSET) as usize;
        if !valid_page_size(page_size) {
            return Err(HeaderError::NotADatabase(format!(
                "bad page size {page_size} (a power of two in {MIN_PAGE_SIZE}..={MAX_PAGE_SIZE})"
            )));
        }
        Ok(Some(page_size))
    }

    /// Rewrites the checksum of the header page `page` to that of its bytes, where its
    /// segment count puts it (nothing when the count does not fit the page): damaged
    /// bytes that pass the checksum, so that a fuzz target reaches the content checks.
    pub(crate) fn reseal(page: &mut [u8]) {
        if page.len() < PREFIX_LEN {
            return;
        }
        let count = u32_at(page, SEGMENT_COUNT_OFFSET) as usize;
        if count > max_segments(page.len()) {
            return;
        }
        let crc_offset = SEGMENT_TABLE_OFFSET + count * SEGMENT_LEN;
        let crc = header_crc(page, crc_offset);
        page[crc_offset..crc_offset + CRC_LEN].copy_from_slice(&crc.to_le_bytes());
    }

    /// Decodes and verifies a whole header page (its length is the page size).
    pub(crate) fn decode(page: &[u8]) -> Result<Header, HeaderError> {
        let page_size = match Header::check_prefix(page)? {
            Some(ps) if ps == page.len() => ps,
            Some(ps) => {
                return Err(HeaderError::Corrupt(format!(
                    "header page is {} bytes, its page size says {ps}",
                    page.len()
                )))
            }
            None => return Err(HeaderError::Corrupt("header page too short".to_string())),
        };
        let count = u32_at(page, SEGMENT_COUNT_OFFSET) as usize;
        let max = max_segments(page_size);
        if count > max {
            return Err(HeaderError::Corrupt(format!(
                "segment count {count} exceeds the {max} that fit in the header"
            )));
        }
        let crc_offset = SEGMENT_TABLE_OFFSET + count * SEGMENT_LEN;
        let stored = u32_at(page, crc_offset);
        let actual = header_crc(page, crc_offset);
        if stored != actual {
            return Err(HeaderError::Corrupt(format!(
                "header checksum mismatch (stored {stored:#010x}, computed {actual:#010x})"
            )));
        }
        let page_count = u64_at(page, PAGE_COUNT_OFFSET);
        if page_count == 0 {
            return Err(HeaderError::Corrupt(
                "page count 0 (the header is a page)".to_string(),
            ));
        }
        let mut segments = Vec::with_capacity(count);
        for i in 0..count {
            let at = SEGMENT_TABLE_OFFSET + i * SEGMENT_LEN;
            let e = page.get(at..at + SEGMENT_LEN).unwrap_or(&[]);
            let raw = e
                .get(SEG_NAME_OFFSET..SEG_NAME_OFFSET + SEG_NAME_LEN)
                .unwrap_or(&[]);
            let len = raw.iter().position(|&b| b == 0).unwrap_or(raw.len());
            let bad =
                || HeaderError::Corrupt(format!("segment {i} has a malformed name {raw:02x?}"));
            if raw[len..].iter().any(|&b| b != 0) {
                return Err(bad());
            }
            let name = std::str::from_utf8(&raw[..len])
                .map_err(|_| bad())?
                .to_string();
            let seg = Segment::new(
                name,
                u64_at(e, SEG_A_OFFSET),
                u64_at(e, SEG_B_OFFSET),
                u64_at(e, SEG_C_OFFSET),
            );
            if seg.name_problem().is_some() {
                return Err(bad());
            }
            if segments.iter().any(|s: &Segment| s.name == seg.name) {
                return Err(HeaderError::Corrupt(format!(
                    "segment {:?} appears twice",
                    seg.name
                )));
            }
            segments.push(seg);
        }
        Ok(Header {
            version: u32_at(page, VERSION_OFFSET),
            page_size: page_size as u32,
            page_count,
            segments,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(ps: usize) -> Header {
        let mut h = Header::new(ps);
        h.page_count = 12345;
        h.set_segment(Segment::new("rtree", 1, 2, 3)).unwrap();
        h.set_segment(Segment::new("meshes-lod0", u64::MAX, 0, 9))
            .unwrap();
        h
    }

    #[test]
    fn layout_constants() {
        assert_eq!(PAGE_COUNT_OFFSET, 16);
        assert_eq!(SEGMENT_TABLE_OFFSET, 32);
        assert_eq!(SEGMENT_LEN, 40);
        assert_eq!(max_segments(1024), 24);
        assert_eq!(max_segments(4096), 101);
    }

    #[test]
    fn round_trip() {
        for ps in [1024, 4096, 65536] {
            let h = sample(ps);
            let mut page = vec![0u8; ps];
            h.encode(&mut page);
            assert_eq!(&page[..8], b"FLANEUR\0");
            let d = Header::decode(&page).unwrap();
            assert_eq!(d, h);
            assert_eq!(d.segment("rtree"), Some(&Segment::new("rtree", 1, 2, 3)));
            assert_eq!(d.segment("nope"), None);
        }
    }

    #[test]
    fn any_flipped_byte_is_caught() {
        let h = sample(1024);
        let mut page = vec![0u8; 1024];
        h.encode(&mut page);
        for i in 0..page.len() {
            let mut q = page.clone();
            q[i] ^= 0x04;
            assert!(Header::decode(&q).is_err(), "flip at byte {i} undetected");
        }
    }

    #[test]
    fn replace_and_limits() {
        let mut h = Header::new(1024);
        h.set_segment(Segment::new("x", 1, 1, 1)).unwrap();
        h.set_segment(Segment::new("x", 2, 2, 2)).unwrap();
        assert_eq!(h.segments().len(), 1);
        assert_eq!(h.segment("x").unwrap().a, 2);
        assert!(h
            .set_segment(Segment::new("0123456789abcdef", 0, 0, 0))
            .unwrap_err()
            .contains("at most 15"));
        h.set_segment(Segment::new("0123456789abcde", 0, 0, 0))
            .unwrap();
        assert!(h.set_segment(Segment::new("", 0, 0, 0)).is_err());
        assert!(h.set_segment(Segment::new("a\0b", 0, 0, 0)).is_err());
        assert!(h.set_segment(Segment::new("é", 0, 0, 0)).is_err());
        for i in h.segments().len()..max_segments(1024) {
            h.set_segment(Segment::new(format!("s{i}"), 0, 0, 0))
                .unwrap();
        }
        let e = h.set_segment(Segment::new("onemore", 0, 0, 0)).unwrap_err();
        assert!(e.contains("full"), "{e}");
        // A full table still encodes and decodes.
        let mut page = vec![0u8; 1024];
        h.encode(&mut page);
        assert_eq!(Header::decode(&page).unwrap(), h);
    }

    #[test]
    fn prefix_checks() {
        assert!(matches!(
            Header::check_prefix(b""),
            Err(HeaderError::NotADatabase(_))
        ));
        assert_eq!(Header::check_prefix(b"FLAN"), Ok(None));
        assert!(matches!(
            Header::check_prefix(b"hello world"),
            Err(HeaderError::NotADatabase(_))
        ));
        let mut page = vec![0u8; 1024];
        sample(1024).encode(&mut page);
        assert_eq!(Header::check_prefix(&page[..PREFIX_LEN]), Ok(Some(1024)));
        let mut q = page.clone();
        q[VERSION_OFFSET..PAGE_SIZE_OFFSET].copy_from_slice(&3u32.to_le_bytes());
        let e = Header::check_prefix(&q).unwrap_err().to_string();
        assert!(
            e.contains("version 3") && e.contains("versions 1..=2"),
            "{e}"
        );
        for v in [1u32, 2] {
            q[VERSION_OFFSET..PAGE_SIZE_OFFSET].copy_from_slice(&v.to_le_bytes());
            assert_eq!(Header::check_prefix(&q), Ok(Some(1024)));
        }
        let mut q = page.clone();
        q[PAGE_SIZE_OFFSET..PAGE_COUNT_OFFSET].copy_from_slice(&1000u32.to_le_bytes());
        assert!(Header::check_prefix(&q)
            .unwrap_err()
            .to_string()
            .contains("page size"));
    }
}
