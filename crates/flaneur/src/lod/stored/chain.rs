//! An object's chain of discrete levels of detail as flat bytes, for one extent of the
//! database: the levels [`ProgressiveMesh::levels`](crate::lod::ProgressiveMesh::levels) cuts,
//! without the full-detail mesh (level 0), which the database already holds as the
//! object's mesh extent.
//!
//! Levels are numbered as `flaneur lod` numbers its files: 0 is the original, each
//! higher number coarser. They are stored **coarsest first**, behind a directory, so
//! that the coarse levels a distant object needs sit in the extent's first page with the
//! directory: reading level n costs the directory's page(s) and that level's pages,
//! never the finer levels' (`Store::read_extent_range`).
//!
//! ```text
//! offset        width  field
//! ------------  -----  ------------------------------------------------------------
//!            0      4  magic            b"FLCH"
//!            4      4  version          u32, CHAIN_VERSION
//!            8      8  object id        u64
//!           16      4  full triangles   u32, level 0's (the object's mesh extent)
//!           20      4  levels           u32, n >= 1: levels 1..=n are stored
//!           24    24n  directory        one entry per level, coarsest (level n) first:
//!                        +0   4  triangles  u32, strictly fewer than the next finer
//!                        +4   4  vertices   u32
//!                        +8   4  error      f32, metres, never below the next finer's
//!                        +12  4  offset     u32, of the level's bytes in the chain
//!                        +16  4  length     u32
//!                        +20  4  crc32      of the level's bytes
//!     24 + 24n      4  crc32            of every byte before it
//!     28 + 24n      …  level bytes      coarsest first, back to back, each a mesh in
//!                                       the database's mesh codec (`scene::MeshCodec`:
//!                                       raw floats in a file of format version 1,
//!                                       meshoptimizer's buffers in version 2)
//! ```
//!
//! **Version 2** (format version 2, `scene::MeshCodec::Meshopt`) stores the levels as
//! one blob of meshoptimizer's buffers (`scene::mesh_codec::geometry`) after the
//! directory: the levels share one vertex buffer, coarsest first, each adding a chunk of
//! vertices and its index buffer. An entry's offset and length are the level's own bytes
//! in the blob (the coarsest's take in the blob's header, so that a checksum covers
//! every byte), and its vertices all those it reads; reading level n takes the chain's
//! bytes from the end of the directory to the end of level n, the coarser levels' with
//! them (the directory says which). The full mesh is not in the blob: sharing its
//! vertices too made the full meshes 86 % larger on the 3,000-object city.
//!
//! The directory carries its own checksum and each level its own, so a reader checks
//! exactly the bytes it read. Reading names the first failure — too short, magic,
//! version, counts against the length, checksum, then content (offsets back to back to
//! the end, triangles and errors ordered, the level's mesh against its entry) — as an
//! `Error::Invalid`, never a panic, whatever the bytes.

use crate::error::{Error, Result};
use crate::lod::pm::Level;
use crate::scene::{
    decode_level_v2, decode_mesh, encode_levels_v2, encode_mesh, Dictionaries, DictionaryUse,
    Framing, Mesh, MeshCodec,
};
use crate::store::framing::{
    self as bytes, crc_matches, f32_at, push_crc, u32_at, u64_at, CRC_LEN,
};

/// The first four bytes of an encoded chain.
pub const CHAIN_MAGIC: [u8; 4] = *b"FLCH";
/// The encoding version whose levels are meshes of their own (format version 1).
pub const CHAIN_VERSION: u32 = 1;
/// The encoding version whose levels share one vertex buffer (format version 2).
pub const CHAIN_VERSION_SHARED: u32 = 2;

const MAGIC_OFFSET: usize = 0;
const VERSION_OFFSET: usize = MAGIC_OFFSET + CHAIN_MAGIC.len();
const OBJECT_OFFSET: usize = VERSION_OFFSET + 4;
const FULL_TRIANGLES_OFFSET: usize = OBJECT_OFFSET + 8;
const LEVELS_OFFSET: usize = FULL_TRIANGLES_OFFSET + 4;
/// Bytes before the directory: enough to learn how long the directory is.
pub const CHAIN_HEADER_LEN: usize = LEVELS_OFFSET + 4;

const ENTRY_TRIANGLES: usize = 0;
const ENTRY_VERTICES: usize = ENTRY_TRIANGLES + 4;
const ENTRY_ERROR: usize = ENTRY_VERTICES + 4;
const ENTRY_OFFSET: usize = ENTRY_ERROR + 4;
const ENTRY_LENGTH: usize = ENTRY_OFFSET + 4;
const ENTRY_CRC: usize = ENTRY_LENGTH + 4;
const ENTRY_LEN: usize = ENTRY_CRC + 4;

/// One level of detail of a stored object, as [`Database::lod_levels`] lists it.
///
/// [`Database::lod_levels`]: crate::Database::lod_levels
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct LevelInfo {
    /// 0 is the full-detail mesh; each higher level is coarser.
    pub level: usize,
    /// Triangles of the level's mesh.
    pub triangles: u32,
    /// The largest error of the collapses that made it from the original, in metres
    /// (0 for level 0).
    pub error: f32,
}

/// A stored level's directory entry.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Entry {
    triangles: u32,
    vertices: u32,
    error: f32,
    offset: u32,
    length: u32,
    crc: u32,
}

/// The header and directory of an encoded chain: what a reader needs to find and check
/// one level's bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainDirectory {
    /// The object the chain belongs to.
    pub object: u64,
    /// Triangles of level 0, the object's full mesh.
    pub full_triangles: u32,
    /// Stored levels, coarsest first (storage order).
    entries: Vec<Entry>,
    /// The encoding version.
    version: u32,
}

fn corrupt(what: String) -> Error {
    Error::Invalid(format!("LOD chain bytes: {what}"))
}

/// Whether `levels` (finest first) are coarser one after the other, from the full mesh's
/// `full_triangles`: triangles falling, errors finite and rising.
fn check_coarser(full_triangles: usize, levels: &[Level]) -> std::result::Result<(), String> {
    let full = u32::try_from(full_triangles).map_err(|_| format!("{full_triangles} triangles"))?;
    let mut finer = (full, 0.0f32);
    for (i, l) in levels.iter().enumerate() {
        let t = l.mesh.triangle_count() as u32;
        if t >= finer.0 || !l.error.is_finite() || l.error < finer.1 {
            return Err(format!(
                "level {} ({t} triangles, error {}) is not coarser than the level before \
                 ({} triangles, error {})",
                i + 1,
                l.error,
                finer.0,
                finer.1
            ));
        }
        finer = (t, l.error);
    }
    Ok(())
}

/// A chain of version 2: the directory, then the levels as one blob sharing one vertex
/// buffer, coarsest first.
fn encode_shared(
    object: u64,
    full_triangles: usize,
    levels: &[Level],
    framing: Framing,
) -> std::result::Result<Vec<u8>, String> {
    let coarsest_first: Vec<&Mesh> = levels.iter().rev().map(|l| &l.mesh).collect();
    let (blob, spans) = encode_levels_v2(&coarsest_first, framing)?;
    // The coarsest level's bytes take in the blob's header and level table, so that every
    // byte after the directory is under some level's checksum.
    let places: Vec<(usize, usize, usize)> = spans
        .iter()
        .enumerate()
        .map(|(k, s)| (if k == 0 { 0 } else { s.start }, s.end, s.vertices))
        .collect();
    write_chain(
        object,
        full_triangles,
        CHAIN_VERSION_SHARED,
        levels,
        &places,
        &blob,
    )
}

/// A chain of `version`: its header, one directory entry per level of `levels` (finest
/// first, stored coarsest first), where `places[k]` says where the k-th coarsest level's
/// bytes lie in `body` (start, end) and how many vertices it reads, the directory's
/// checksum, then `body`.
fn write_chain(
    object: u64,
    full_triangles: usize,
    version: u32,
    levels: &[Level],
    places: &[(usize, usize, usize)],
    body: &[u8],
) -> std::result::Result<Vec<u8>, String> {
    let head = directory_len(levels.len() as u64) as usize;
    let total = (head + body.len()) as u64;
    if total > u32::MAX as u64 {
        return Err(format!("{total} bytes are over the 4 GiB an extent holds"));
    }
    let mut b = Vec::with_capacity(total as usize);
    b.extend_from_slice(&CHAIN_MAGIC);
    b.extend_from_slice(&version.to_le_bytes());
    b.extend_from_slice(&object.to_le_bytes());
    b.extend_from_slice(&(full_triangles as u32).to_le_bytes());
    b.extend_from_slice(&(levels.len() as u32).to_le_bytes());
    for (l, &(start, end, vertices)) in levels.iter().rev().zip(places) {
        for field in [
            l.mesh.triangle_count() as u32,
            vertices as u32,
            l.error.to_bits(),
            (head + start) as u32,
            (end - start) as u32,
            crc32fast::hash(&body[start..end]),
        ] {
            b.extend_from_slice(&field.to_le_bytes());
        }
    }
    push_crc(&mut b);
    b.extend_from_slice(body);
    Ok(b)
}

/// Bytes of the header and directory of a chain of `levels` levels, checksum included
/// (u64: a count read from damaged bytes must not overflow).
fn directory_len(levels: u64) -> u64 {
    (CHAIN_HEADER_LEN + CRC_LEN) as u64 + ENTRY_LEN as u64 * levels
}

/// Encodes the levels of one object coarser than its full mesh. `levels` are finest
/// first, as [`ProgressiveMesh::levels`](crate::lod::ProgressiveMesh::levels) returns them
/// after level 0 (`levels[0]` is level 1). An `Error::Invalid` when there is no level,
/// when they are not strictly coarser one after the other (triangles) or their errors
/// decrease coarse-ward, or when the chain would pass 4 GiB.
#[cfg(test)]
pub fn encode_chain(object: u64, full_triangles: usize, levels: &[Level]) -> Result<Vec<u8>> {
    encode_chain_with(object, full_triangles, levels, MeshCodec::Raw, None)
}

/// [`encode_chain`] with each level in `codec`, its zstd frames compressed with `dict`'s
/// dictionary for coarse levels when there is one.
pub(crate) fn encode_chain_with(
    object: u64,
    full_triangles: usize,
    levels: &[Level],
    codec: MeshCodec,
    dict: Option<&Dictionaries>,
) -> Result<Vec<u8>> {
    let refuse = |what: String| Error::Invalid(format!("LOD chain of object {object}: {what}"));
    if levels.is_empty() {
        return Err(refuse("no level to store".into()));
    }
    check_coarser(full_triangles, levels).map_err(refuse)?;
    if let MeshCodec::Meshopt { zstd } = codec {
        let framing = Framing::of(zstd, dict, DictionaryUse::Levels);
        return encode_shared(object, full_triangles, levels, framing).map_err(refuse);
    }
    // Version 1: each level a mesh of its own, back to back.
    let mut body = Vec::new();
    let mut places = Vec::with_capacity(levels.len());
    for l in levels.iter().rev() {
        let start = body.len();
        body.extend_from_slice(&encode_mesh(&l.mesh));
        places.push((start, body.len(), l.mesh.positions.len()));
    }
    write_chain(
        object,
        full_triangles,
        CHAIN_VERSION,
        levels,
        &places,
        &body,
    )
    .map_err(refuse)
}

/// The encoding version of the chain that starts with `prefix`, after its magic.
fn version_of(prefix: &[u8]) -> Result<u32> {
    bytes::at_least(
        prefix.len(),
        CHAIN_HEADER_LEN as u64,
        "the header alone takes",
    )
    .map_err(corrupt)?;
    let version = u32_at(prefix, VERSION_OFFSET);
    let known = if version == CHAIN_VERSION_SHARED {
        CHAIN_VERSION_SHARED
    } else {
        CHAIN_VERSION
    };
    bytes::magic_and_version(prefix, "a LOD chain", CHAIN_MAGIC, known).map_err(corrupt)?;
    Ok(version)
}

impl ChainDirectory {
    /// Bytes before the directory, which say how long it is.
    pub const HEADER_LEN: usize = CHAIN_HEADER_LEN;

    /// How many bytes from the start of a chain hold its header and directory, read from
    /// its first [`CHAIN_HEADER_LEN`] bytes (or more) — the length a reader asks the
    /// store for before it decodes the directory.
    pub fn len_from_prefix(prefix: &[u8]) -> Result<usize> {
        version_of(prefix)?;
        let levels = u32_at(prefix, LEVELS_OFFSET);
        Ok(directory_len(levels as u64).min(usize::MAX as u64) as usize)
    }

    /// Decodes and checks the header and directory of a chain of `total_len` bytes from
    /// its first bytes (`prefix`, at least [`ChainDirectory::len_from_prefix`] of them).
    pub fn decode(prefix: &[u8], total_len: usize) -> Result<ChainDirectory> {
        let head = ChainDirectory::len_from_prefix(prefix)?;
        let n = u32_at(prefix, LEVELS_OFFSET) as usize;
        bytes::at_least(
            total_len,
            head as u64,
            format_args!("a directory of {n} levels takes"),
        )
        .map_err(corrupt)?;
        if prefix.len() < head {
            return Err(corrupt(format!(
                "truncated: {} bytes read, a directory of {n} levels takes {head}",
                prefix.len()
            )));
        }
        bytes::checksum(prefix, head - CRC_LEN).map_err(|w| corrupt(format!("directory {w}")))?;
        if n == 0 {
            return Err(corrupt("a chain of no levels".into()));
        }
        let object = u64_at(prefix, OBJECT_OFFSET);
        let full_triangles = u32_at(prefix, FULL_TRIANGLES_OFFSET);
        let version = version_of(prefix)?;
        let mut entries = Vec::with_capacity(n);
        let mut next_offset = head as u64;
        for j in 0..n {
            let at = CHAIN_HEADER_LEN + ENTRY_LEN * j;
            let e = Entry {
                triangles: u32_at(prefix, at + ENTRY_TRIANGLES),
                vertices: u32_at(prefix, at + ENTRY_VERTICES),
                error: f32_at(prefix, at + ENTRY_ERROR),
                offset: u32_at(prefix, at + ENTRY_OFFSET),
                length: u32_at(prefix, at + ENTRY_LENGTH),
                crc: u32_at(prefix, at + ENTRY_CRC),
            };
            let level = n - j;
            if e.offset as u64 != next_offset {
                return Err(corrupt(format!(
                    "level {level} starts at byte {}, expected {next_offset}",
                    e.offset
                )));
            }
            next_offset += e.length as u64;
            if !(e.error >= 0.0 && e.error.is_finite()) {
                return Err(corrupt(format!("level {level} has error {}", e.error)));
            }
            if let Some(coarser) = entries.last() {
                let coarser: &Entry = coarser;
                if e.triangles <= coarser.triangles || e.error > coarser.error {
                    return Err(corrupt(format!(
                        "level {level} ({} triangles, error {}) is not finer than level {} \
                         ({} triangles, error {})",
                        e.triangles,
                        e.error,
                        level + 1,
                        coarser.triangles,
                        coarser.error
                    )));
                }
            }
            entries.push(e);
        }
        if next_offset != total_len as u64 {
            return Err(corrupt(format!(
                "the levels end at byte {next_offset}, the chain is {total_len} bytes"
            )));
        }
        let finest = entries[n - 1].triangles;
        if finest >= full_triangles {
            return Err(corrupt(format!(
                "level 1 has {finest} triangles, the full mesh {full_triangles}"
            )));
        }
        Ok(ChainDirectory {
            object,
            full_triangles,
            entries,
            version,
        })
    }

    /// Rewrites the checksums of the chain `b`: each level's in the directory (where
    /// the level's bytes lie inside `b`), then the directory's own, when `b` holds the
    /// directory. Damaged bytes that pass the checksums, so that a fuzz target reaches
    /// the content checks.
    pub(crate) fn reseal(b: &mut [u8]) {
        let Ok(head) = ChainDirectory::len_from_prefix(b) else {
            return;
        };
        if head > b.len() {
            return;
        }
        let n = u32_at(b, LEVELS_OFFSET) as usize;
        for j in 0..n {
            let at = CHAIN_HEADER_LEN + ENTRY_LEN * j;
            let (offset, length) = (
                u32_at(b, at + ENTRY_OFFSET) as usize,
                u32_at(b, at + ENTRY_LENGTH) as usize,
            );
            if let Some(level) = offset
                .checked_add(length)
                .and_then(|end| b.get(offset..end))
            {
                let crc = crc32fast::hash(level);
                b[at + ENTRY_CRC..at + ENTRY_LEN].copy_from_slice(&crc.to_le_bytes());
            }
        }
        bytes::reseal(&mut b[..head]);
    }

    /// The coarsest level whose bytes a reader of `level` holds: `level` itself in version
    /// 1, every coarser one in version 2.
    fn level_count_read(&self, level: usize) -> usize {
        match self.version {
            CHAIN_VERSION => level,
            _ => self.entries.len(),
        }
    }

    /// Levels stored (level 0 is not): levels `1..=count` can be read.
    pub fn stored_levels(&self) -> usize {
        self.entries.len()
    }

    /// Every level, level 0 (the full mesh, error 0) first.
    pub fn levels(&self) -> Vec<LevelInfo> {
        let full = LevelInfo {
            level: 0,
            triangles: self.full_triangles,
            error: 0.0,
        };
        std::iter::once(full)
            .chain((1..=self.entries.len()).map(|level| {
                let e = self.entry(level);
                LevelInfo {
                    level,
                    triangles: e.triangles,
                    error: e.error,
                }
            }))
            .collect()
    }

    /// The entry of stored level `level` (1..=n).
    fn entry(&self, level: usize) -> &Entry {
        &self.entries[self.entries.len() - level]
    }

    /// Where stored level `level` (1..=`stored_levels`) lies in the chain, as (offset,
    /// length). An `Error::Invalid` for any other level.
    pub fn level_range(&self, level: usize) -> Result<(usize, usize)> {
        if level == 0 || level > self.entries.len() {
            return Err(Error::Invalid(format!(
                "object {} has LOD levels 0..={} (0 is its full mesh), not {level}",
                self.object,
                self.entries.len()
            )));
        }
        let e = self.entry(level);
        Ok((e.offset as usize, e.length as usize))
    }

    /// The chain's bytes `start..end` a reader of stored level `level` needs: the
    /// level's own in version 1; in version 2 everything from the end of the directory
    /// to the level's end (the blob's header and the coarser levels, whose vertices it
    /// shares).
    pub fn read_range(&self, level: usize) -> Result<(usize, usize)> {
        let (offset, length) = self.level_range(level)?;
        let start = match self.version {
            CHAIN_VERSION => offset,
            _ => directory_len(self.entries.len() as u64) as usize,
        };
        Ok((start, offset + length))
    }

    /// Decodes stored level `level` from the bytes [`read_range`] places, and checks
    /// them against the directory: checksums, triangles and vertices.
    ///
    /// [`read_range`]: ChainDirectory::read_range
    ///
    /// A chain compressed with its database's dictionary needs `dict`.
    pub fn decode_level(
        &self,
        level: usize,
        bytes: &[u8],
        dict: Option<&Dictionaries>,
    ) -> Result<Mesh> {
        let (start, end) = self.read_range(level)?;
        let e = self.entry(level);
        if bytes.len() != end - start {
            return Err(corrupt(format!(
                "level {level} is {} bytes, the directory says {}",
                bytes.len(),
                end - start
            )));
        }
        // Every level the bytes hold is checked: a version-2 level reads the coarser ones.
        for l in level..=self.level_count_read(level) {
            let (offset, length) = self.level_range(l)?;
            let own = &bytes[offset - start..offset - start + length];
            crc_matches(self.entry(l).crc, own).map_err(|w| corrupt(format!("level {l} {w}")))?;
        }
        let mesh = match self.version {
            CHAIN_VERSION => decode_mesh(bytes, None),
            _ => decode_level_v2(bytes, self.entries.len() - level, dict),
        }
        .map_err(|w| corrupt(format!("level {level}: {w}")))?;
        if mesh.triangle_count() != e.triangles as usize
            || mesh.positions.len() != e.vertices as usize
        {
            return Err(corrupt(format!(
                "level {level} holds {} triangles and {} vertices, the directory says {} and {}",
                mesh.triangle_count(),
                mesh.positions.len(),
                e.triangles,
                e.vertices
            )));
        }
        Ok(mesh)
    }
}

/// Bytes of the head of the encoded chain `bytes`, stored in pages of `payload` bytes:
/// its header, directory and coarsest level, rounded up to whole pages, or the whole
/// chain where that is no shorter. A build stores the head and the rest apart, so that
/// the heads of neighbouring objects lie side by side (`table`).
pub(crate) fn head_len(bytes: &[u8], payload: usize) -> Result<usize> {
    let dir = ChainDirectory::decode(bytes, bytes.len())?;
    let (offset, length) = dir.level_range(dir.stored_levels())?;
    Ok((offset + length)
        .div_ceil(payload.max(1))
        .saturating_mul(payload)
        .min(bytes.len()))
}

/// Decodes a whole chain: its directory and every stored level, level 1 first.
pub fn decode_chain(
    bytes: &[u8],
    dict: Option<&Dictionaries>,
) -> Result<(ChainDirectory, Vec<Mesh>)> {
    let dir = ChainDirectory::decode(bytes, bytes.len())?;
    let meshes = (1..=dir.stored_levels())
        .map(|level| {
            let (start, end) = dir.read_range(level)?;
            dir.decode_level(level, &bytes[start..end], dict)
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((dir, meshes))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::fixtures::building;
    use crate::lod::ProgressiveMesh;
    use crate::store::framing::{mangled, reseal};

    fn chain_of(mesh: &Mesh) -> (Vec<Level>, Vec<u8>) {
        let pm = ProgressiveMesh::build(mesh).unwrap();
        let levels = pm.levels(0.5, 20).unwrap();
        let bytes = encode_chain(7, mesh.triangle_count(), &levels[1..]).unwrap();
        (levels, bytes)
    }

    #[test]
    fn round_trips_coarsest_first() {
        let bunny = crate::scene::bunny();
        let (levels, bytes) = chain_of(&bunny);
        assert!(levels.len() >= 5);
        let (dir, meshes) = decode_chain(&bytes, None).unwrap();
        assert_eq!((dir.object, dir.full_triangles), (7, 3674));
        assert_eq!(dir.stored_levels(), levels.len() - 1);
        let infos = dir.levels();
        for (i, level) in levels.iter().enumerate() {
            assert_eq!(infos[i].level, i);
            assert_eq!(infos[i].triangles as usize, level.mesh.triangle_count());
            assert_eq!(infos[i].error, level.error);
            if i > 0 {
                let m = &meshes[i - 1];
                assert_eq!(m.indices, level.mesh.indices);
                assert_eq!(m.positions, level.mesh.positions);
            }
        }
        // The coarsest level comes right after the directory.
        let coarsest = dir.stored_levels();
        let (offset, _) = dir.level_range(coarsest).unwrap();
        assert_eq!(offset, directory_len(coarsest as u64) as usize);
        assert!(dir.level_range(0).is_err());
        assert!(dir.level_range(coarsest + 1).is_err());
    }

    #[test]
    fn the_head_ends_on_the_page_that_ends_the_coarsest_level() {
        let (_, bytes) = chain_of(&crate::scene::bunny());
        let dir = ChainDirectory::decode(&bytes, bytes.len()).unwrap();
        let (offset, length) = dir.level_range(dir.stored_levels()).unwrap();
        let end = offset + length;
        for payload in [64, 1012, end, end + 1, 4084] {
            let head = head_len(&bytes, payload).unwrap();
            assert!(head >= end, "{payload}: the head holds the coarsest level");
            if head < bytes.len() {
                assert_eq!(head % payload, 0, "{payload}: whole pages before a rest");
                assert!(head - end < payload, "{payload}: no page more than needed");
            }
        }
        // A page as long as the chain: one extent, no rest.
        assert_eq!(head_len(&bytes, bytes.len()).unwrap(), bytes.len());
        assert!(head_len(&bytes[..10], 1012).is_err());
    }

    #[test]
    fn refuses_what_is_no_chain() {
        let bunny = crate::scene::bunny();
        let pm = ProgressiveMesh::build(&bunny).unwrap();
        let levels = pm.levels(0.5, 20).unwrap();
        assert!(encode_chain(1, 3674, &[]).is_err());
        // Level 0 itself is not coarser than the full mesh.
        assert!(encode_chain(1, 3674, &levels).is_err());
        let mut swapped = levels[1..].to_vec();
        swapped.swap(0, 1);
        assert!(encode_chain(1, 3674, &swapped).is_err());
    }

    #[test]
    fn every_truncation_and_every_flipped_byte_is_an_error() {
        let (_, bytes) = chain_of(&building());
        for len in 0..bytes.len() {
            assert!(decode_chain(&bytes[..len], None).is_err(), "{len}");
        }
        for at in 0..bytes.len() {
            let mut b = bytes.clone();
            b[at] ^= 0x5a;
            assert!(decode_chain(&b, None).is_err(), "byte {at}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        let e = decode_chain(&longer, None).unwrap_err().to_string();
        assert!(e.contains("end at byte"), "{e}");
    }

    #[test]
    fn faults_are_named() {
        let (_, bytes) = chain_of(&crate::scene::bunny());
        let n = u32_at(&bytes, LEVELS_OFFSET) as usize;
        let head = directory_len(n as u64) as usize;
        let with = |at: usize, v: u32, seal: bool| {
            let mut b = bytes.clone();
            b[at..at + 4].copy_from_slice(&v.to_le_bytes());
            if seal {
                reseal(&mut b[..head]);
            }
            decode_chain(&b, None).unwrap_err().to_string()
        };
        assert!(with(MAGIC_OFFSET, 0, false).contains("magic"));
        assert!(with(VERSION_OFFSET, 3, false).contains("version 3"));
        assert!(with(LEVELS_OFFSET, u32::MAX, false).contains("truncated"));
        assert!(with(OBJECT_OFFSET, 3, false).contains("checksum"));
        let first = CHAIN_HEADER_LEN;
        let second = first + ENTRY_LEN;
        assert!(with(first + ENTRY_OFFSET, 0, true).contains("starts at byte"));
        assert!(with(first + ENTRY_LENGTH, 1, true).contains("starts at byte"));
        assert!(with(second + ENTRY_TRIANGLES, 1, true).contains("not finer"));
        assert!(with(second + ENTRY_ERROR, 1e6f32.to_bits(), true).contains("not finer"));
        assert!(with(first + ENTRY_ERROR, f32::NAN.to_bits(), true).contains("error NaN"));
        assert!(with(FULL_TRIANGLES_OFFSET, 10, true).contains("full mesh"));
        // A level whose bytes rotted, or whose entry lies about its mesh.
        let mut b = bytes.clone();
        b[head + 20] ^= 1;
        let e = decode_chain(&b, None).unwrap_err().to_string();
        assert!(e.contains(&format!("level {n} checksum")), "{e}");
        let e = with(first + ENTRY_VERTICES, 1, true);
        assert!(e.contains("the directory says"), "{e}");
    }

    #[test]
    fn version_2_levels_share_their_vertices_and_read_from_the_directory_on() {
        let bunny = crate::scene::bunny();
        let pm = ProgressiveMesh::build(&bunny).unwrap();
        let levels = pm.levels(0.5, 20).unwrap();
        let codec = MeshCodec::Meshopt { zstd: Some(3) };
        let bytes = encode_chain_with(7, 3674, &levels[1..], codec, None).unwrap();
        let raw = encode_chain(7, 3674, &levels[1..]).unwrap();
        assert!(
            bytes.len() * 3 < raw.len(),
            "{} against {}",
            bytes.len(),
            raw.len()
        );
        let (dir, meshes) = decode_chain(&bytes, None).unwrap();
        assert_eq!(
            dir.levels(),
            ChainDirectory::decode(&raw, raw.len()).unwrap().levels()
        );
        let head = directory_len(dir.stored_levels() as u64) as usize;
        for (i, m) in meshes.iter().enumerate() {
            let level = i + 1;
            assert_eq!(m.triangle_count(), levels[level].mesh.triangle_count());
            // From the directory's end to the level's: the coarser levels, not the finer.
            let (start, end) = dir.read_range(level).unwrap();
            assert_eq!(start, head);
            let (offset, length) = dir.level_range(level).unwrap();
            assert_eq!(end, offset + length);
            if level > 1 {
                assert!(end < dir.read_range(level - 1).unwrap().1);
            }
        }
        for len in 0..bytes.len() {
            assert!(decode_chain(&bytes[..len], None).is_err(), "{len}");
        }
        for at in (0..bytes.len()).step_by(7) {
            let mut b = bytes.clone();
            b[at] ^= 0x5a;
            assert!(decode_chain(&b, None).is_err(), "byte {at}");
        }
    }

    #[test]
    fn random_bytes_never_panic() {
        let (_, good) = chain_of(&building());
        let restore = |b: &mut [u8]| {
            b[..4].copy_from_slice(&CHAIN_MAGIC);
            b[4..8].copy_from_slice(&CHAIN_VERSION.to_le_bytes());
            let n = (u32_at(b, LEVELS_OFFSET) % 8) as u64;
            b[LEVELS_OFFSET..LEVELS_OFFSET + 4].copy_from_slice(&(n as u32).to_le_bytes());
            let head = directory_len(n) as usize;
            if head <= b.len() {
                reseal(&mut b[..head]);
            }
        };
        mangled(9, 2000, 300, &good, restore, |b| {
            let _ = decode_chain(b, None);
        });
    }
}
