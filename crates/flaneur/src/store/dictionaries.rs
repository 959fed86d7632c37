//! Where a file keeps the zstd dictionaries its geometry frames are compressed with
//! (`scene::Dictionaries`): one extent of `meta` pages, named by the header's `zdict`
//! segment (a = first page, b = byte length, c = the zstd level the frames were
//! compressed at, which an `insert` keeps to). Read once, at the first frame that needs
//! them, and shared by every thread of the handle.
//!
//! ```text
//! offset   width  field
//! -------  -----  ---------------------------------------------------------------
//!       0      4  magic          b"FLZD"
//!       4      4  version        u32, DICTIONARIES_VERSION
//!       8      4  meshes         u32, bytes of the full meshes' dictionary (0: none)
//!      12      4  levels         u32, bytes of the coarse levels' dictionary (0: none)
//!      16      …  the two dictionaries, back to back, as zstd trained them
//!       …      4  crc32          of every byte before it
//! ```

use super::framing::{self as bytes, crc_matches, push_crc, u32_at, CRC_LEN};
use super::{PageKind, Segment, Store};
use crate::error::{Error, Result};
use crate::scene::Dictionaries;

/// The header segment that names the dictionaries' extent.
pub const DICTIONARIES_SEGMENT: &str = "zdict";
const MAGIC: [u8; 4] = *b"FLZD";
const DICTIONARIES_VERSION: u32 = 1;
const HEAD_LEN: usize = 16;

/// The dictionaries as their extent stores them.
fn encode(d: &Dictionaries) -> Vec<u8> {
    let parts = d.parts();
    let mut out = Vec::with_capacity(HEAD_LEN + parts[0].len() + parts[1].len() + CRC_LEN);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&DICTIONARIES_VERSION.to_le_bytes());
    for p in parts {
        out.extend_from_slice(&(p.len() as u32).to_le_bytes());
    }
    for p in parts {
        out.extend_from_slice(p);
    }
    push_crc(&mut out);
    out
}

/// Reads the extent's bytes: magic, version, lengths against the extent, checksum, then
/// each dictionary as zstd's.
fn decode(b: &[u8], level: i32) -> std::result::Result<Dictionaries, String> {
    bytes::at_least(
        b.len(),
        (HEAD_LEN + CRC_LEN) as u64,
        "the header alone takes",
    )?;
    bytes::magic_and_version(b, "the zstd dictionaries", MAGIC, DICTIONARIES_VERSION)?;
    let lens = [u32_at(b, 8) as usize, u32_at(b, 12) as usize];
    let body = lens
        .iter()
        .try_fold(HEAD_LEN, |a, &l| a.checked_add(l))
        .filter(|&end| end.checked_add(CRC_LEN) == Some(b.len()))
        .ok_or_else(|| {
            format!(
                "dictionaries of {} and {} bytes in an extent of {} bytes",
                lens[0],
                lens[1],
                b.len()
            )
        })?;
    crc_matches(u32_at(b, body), &b[..body])?;
    let meshes = b[HEAD_LEN..HEAD_LEN + lens[0]].to_vec();
    let levels = b[HEAD_LEN + lens[0]..body].to_vec();
    Dictionaries::from_parts([meshes, levels], level)
}

impl Store {
    /// The zstd dictionaries the file's geometry frames are compressed with, `None` for a
    /// file without (format version 1, or a city too small to train them on). Read at
    /// the first call (its pages counted as `meta` reads) and kept; a damaged extent is a
    /// `CorruptPage` naming its first page.
    pub fn dictionaries(&self) -> Result<Option<Dictionaries>> {
        if let Some(d) = self.dictionaries.get() {
            return Ok(d.clone());
        }
        let found = self.segment_extent(DICTIONARIES_SEGMENT, |_, c| {
            i32::try_from(c)
                .ok()
                .filter(|l| (1..=22).contains(l))
                .map(|_| ())
                .ok_or_else(|| format!("zstd level {c}"))
        })?;
        let d = match found {
            None => None,
            Some((extent, level)) => {
                let b = self.read_extent(&extent, PageKind::Meta)?;
                Some(decode(&b, level as i32).map_err(|what| Error::CorruptPage {
                    path: self.path().to_path_buf(),
                    page: extent.first_page,
                    what: format!("zstd dictionaries: {what}"),
                })?)
            }
        };
        // Another thread may have read them meanwhile: the same bytes, either is kept.
        Ok(self.dictionaries.get_or_init(|| d).clone())
    }

    /// Appends `d` (compressing at zstd `level`) and names it in the header, for the
    /// frames written after. A store keeps one set: a second is refused.
    pub(crate) fn save_dictionaries(&mut self, d: &Dictionaries, level: i32) -> Result<()> {
        if self.header().segment(DICTIONARIES_SEGMENT).is_some() {
            return Err(Error::Invalid(
                "the database already has its zstd dictionaries".into(),
            ));
        }
        let extent = self.append_extent(PageKind::Meta, &encode(d))?;
        self.set_segment(Segment::new(
            DICTIONARIES_SEGMENT,
            extent.first_page,
            extent.byte_len as u64,
            level as u64,
        ))?;
        // Replaced, not set: a reader of this handle (the LOD writer, at its start) may
        // have cached that there were none.
        self.dictionaries = std::sync::OnceLock::from(Some(d.clone()));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trained() -> Dictionaries {
        let samples: Vec<Vec<u8>> = (0..300)
            .map(|i| {
                let mut v = b"what every buffer repeats, then its own: ".to_vec();
                v.extend((0..300).map(|k| ((i * 13 + k * k) % 241) as u8));
                v
            })
            .collect();
        Dictionaries::train(&samples, &samples, 3)
    }

    #[test]
    fn dictionaries_round_trip_through_their_bytes() {
        let d = trained();
        let b = encode(&d);
        assert_eq!(decode(&b, 3).unwrap().parts(), d.parts());
    }

    #[test]
    fn damaged_dictionaries_are_named() {
        let b = encode(&trained());
        for len in [0, 10, 19, b.len() - 1] {
            assert!(decode(&b[..len], 3).is_err(), "{len}");
        }
        let mut bad = b.clone();
        bad[40] ^= 1;
        assert!(decode(&bad, 3).unwrap_err().contains("checksum"));
        let mut longer = b.clone();
        longer.push(0);
        assert!(decode(&longer, 3).is_err());
        let mut huge = b.clone();
        huge[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(decode(&huge, 3).is_err());
    }
}
