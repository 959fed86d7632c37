//! The optional zstd layer outside meshoptimizer's buffers. meshoptimizer's codecs leave
//! byte patterns a general-purpose compressor finds (its own documentation pairs them with
//! one, and glTF pipelines serve them gzipped); zstd decodes at GB/s. Each buffer a reader
//! may want alone — a chunk of vertices, an index buffer — is its own frame, so that a
//! coarse level still reads only its own bytes.

use std::borrow::Cow;
use std::cell::RefCell;

use super::dictionary::{Dictionaries, Use};

/// How a blob's buffers are stored.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Framing<'a> {
    /// As meshoptimizer wrote them.
    Plain,
    /// Each a zstd frame of its own, at this level.
    Zstd(i32),
    /// Each a zstd frame compressed with one of the database's dictionaries.
    Dictionary(&'a Dictionaries, Use),
}

impl<'a> Framing<'a> {
    /// zstd at `zstd` when asked, with the dictionary of `which` when `dict` has it.
    pub(crate) fn of(zstd: Option<i32>, dict: Option<&'a Dictionaries>, which: Use) -> Framing<'a> {
        match (zstd, dict) {
            (None, _) => Framing::Plain,
            (Some(_), Some(d)) if d.has(which) => Framing::Dictionary(d, which),
            (Some(level), _) => Framing::Zstd(level),
        }
    }

    pub(crate) fn squeeze(&self, raw: &[u8]) -> Result<Vec<u8>, String> {
        match self {
            Framing::Plain => Ok(raw.to_vec()),
            Framing::Zstd(level) => squeeze(raw, Some(*level)),
            Framing::Dictionary(d, which) => d.compress(*which, raw),
        }
    }

    /// The inverse of [`Framing::squeeze`], to exactly `raw_len` bytes.
    pub(crate) fn expand<'b>(
        &self,
        stored: &'b [u8],
        raw_len: usize,
    ) -> Result<Cow<'b, [u8]>, String> {
        match self {
            Framing::Plain => expand(stored, raw_len, false),
            Framing::Zstd(_) => expand(stored, raw_len, true),
            Framing::Dictionary(d, which) => d.expand(*which, stored, raw_len).map(Cow::Owned),
        }
    }
}

/// Compresses `raw` at `level` (zstd's 1..=22), or returns it as it is when `level` is
/// `None`.
pub(crate) fn squeeze(raw: &[u8], level: Option<i32>) -> Result<Vec<u8>, String> {
    match level {
        None => Ok(raw.to_vec()),
        Some(l) => zstd::bulk::compress(raw, l).map_err(|e| format!("zstd: {e}")),
    }
}

/// The inverse of [`squeeze`]: `stored` holds exactly `raw_len` bytes once expanded
/// (borrowed as they are when not compressed). The caller bounds `raw_len` before it
/// asks, so that a damaged length cannot ask for gigabytes.
pub(crate) fn expand(stored: &[u8], raw_len: usize, zstd: bool) -> Result<Cow<'_, [u8]>, String> {
    if !zstd {
        if stored.len() != raw_len {
            return Err(format!("{} bytes stored, {raw_len} expected", stored.len()));
        }
        return Ok(Cow::Borrowed(stored));
    }
    // One decompression context a thread, kept: making one costs more than expanding a
    // small mesh's buffer.
    thread_local! {
        static DECOMPRESSOR: RefCell<Option<zstd::bulk::Decompressor<'static>>> =
            const { RefCell::new(None) };
    }
    let raw = DECOMPRESSOR.with(|d| {
        let mut d = d.borrow_mut();
        if d.is_none() {
            *d = Some(zstd::bulk::Decompressor::new().map_err(|e| format!("zstd: {e}"))?);
        }
        let d = d.as_mut().expect("made above");
        d.decompress(stored, raw_len).map_err(|e| {
            format!(
                "a zstd frame of {} bytes does not expand: {e}",
                stored.len()
            )
        })
    })?;
    if raw.len() != raw_len {
        return Err(format!(
            "a zstd frame expands to {} bytes, {raw_len} expected",
            raw.len()
        ));
    }
    Ok(Cow::Owned(raw))
}

/// The first four bytes of every zstd frame.
const ZSTD_MAGIC: [u8; 4] = [0x28, 0xb5, 0x2f, 0xfd];

/// Whether `bytes` start a zstd frame: format version 2 stores a large object's
/// progressive mesh and DAG as one, their own codecs' bytes inside.
pub(crate) fn is_frame(bytes: &[u8]) -> bool {
    bytes.starts_with(&ZSTD_MAGIC)
}

/// Expands a zstd frame that records its content size, at most `max` bytes.
pub(crate) fn expand_frame(stored: &[u8], max: usize) -> Result<Vec<u8>, String> {
    let size = match zstd::zstd_safe::get_frame_content_size(stored) {
        Ok(Some(size)) => size,
        Ok(None) => return Err("a zstd frame that does not say how long it expands".into()),
        Err(_) => return Err(format!("{} bytes are no zstd frame", stored.len())),
    };
    if size > max as u64 {
        return Err(format!("a zstd frame expands to {size} bytes, over {max}"));
    }
    expand(stored, size as usize, true).map(Cow::into_owned)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_refuses_damage() {
        let raw: Vec<u8> = (0..5000u32).map(|i| (i % 7) as u8).collect();
        let small = squeeze(&raw, Some(3)).unwrap();
        assert!(small.len() < raw.len() / 10);
        assert_eq!(expand(&small, raw.len(), true).unwrap(), raw);
        assert!(expand(&small, raw.len() - 1, true).is_err());
        assert!(expand(&small[..small.len() - 3], raw.len(), true).is_err());
        assert!(expand(&raw[..100], 100, true).is_err());
        assert_eq!(squeeze(&raw, None).unwrap(), raw);
        assert!(expand(&raw, raw.len() + 1, false).is_err());
        assert!(is_frame(&small) && !is_frame(&raw));
        assert_eq!(expand_frame(&small, raw.len()).unwrap(), raw);
        assert!(expand_frame(&small, raw.len() - 1).is_err());
        assert!(expand_frame(&raw, 1 << 20).is_err());
    }
}
