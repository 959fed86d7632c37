// The scene file: how a generated city travels from `citygen` to `flaneur build`. A
// million-object city is ~20 GB, so it is written and read as a stream (never held
// whole), normals are quantised to keep it small, and every record carries its own
// checksum, so a torn or rotted file is reported with the object where it goes wrong
// rather than turning into wrong geometry downstream. The writer is `writer`'s.
//
// Layout (little-endian throughout):
//
//   header (16 bytes)
//   +0   magic         [u8; 8]   b"FLNSCENE"
//   +8   version       u32       1
//   +12  reserved      u32       0
//
//   records, one per object, ids strictly increasing
//   +0   id            u64
//   +8   kind          u8        ObjectKind::as_u8
//   +9   flags         u8        bit 0: indices are u16 (vertex count <= 65536)
//   +10  vertex count  u32       V
//   +14  index count   u32       I (a multiple of 3)
//   +18  positions     f32 × 3 × V
//   ..   normals       i8 × 3 × V    snorm8: round(n × 127); renormalised on read
//   ..   indices       (u16 | u32) × I
//   ..   crc32         u32       of every byte of the record before it
//
//   trailer (24 bytes), the last bytes of the file
//   +0   magic         [u8; 8]   b"FLNSEND\0"
//   +8   object count  u64
//   +16  chain crc32   u32       of the header bytes, then each record's crc32 in order
//   +20  trailer crc32 u32       of the 20 trailer bytes before it
//
// A cut anywhere removes or damages the trailer; the reader finds it missing on open and
// walks the record heads to name the object where the file ends. A flipped byte fails a
// record's crc (or a count's sanity check, before anything is allocated), the trailer's
// crc, or the header's magic/version. A dropped or reordered record fails the chain crc.

use std::fs::File;
use std::io::{BufReader, ErrorKind, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

mod writer;

pub use writer::{quantize_snorm8, SceneWriter};

use crate::error::SceneError;
use crate::mesh::Mesh;
use crate::object::{ObjectKind, SceneObject};

/// Magic at the start of every scene file.
pub const SCENE_MAGIC: [u8; 8] = *b"FLNSCENE";
/// The format version this build writes and reads.
pub const SCENE_VERSION: u32 = 1;
/// Magic at the start of the trailer.
pub const TRAILER_MAGIC: [u8; 8] = *b"FLNSEND\0";

const HEADER_MAGIC_OFFSET: usize = 0;
const HEADER_VERSION_OFFSET: usize = HEADER_MAGIC_OFFSET + 8;
const HEADER_RESERVED_OFFSET: usize = HEADER_VERSION_OFFSET + 4;
/// Bytes in the header.
pub const HEADER_LEN: usize = HEADER_RESERVED_OFFSET + 4;

const RECORD_ID_OFFSET: usize = 0;
const RECORD_KIND_OFFSET: usize = RECORD_ID_OFFSET + 8;
const RECORD_FLAGS_OFFSET: usize = RECORD_KIND_OFFSET + 1;
const RECORD_VERTICES_OFFSET: usize = RECORD_FLAGS_OFFSET + 1;
const RECORD_INDICES_OFFSET: usize = RECORD_VERTICES_OFFSET + 4;
/// Bytes in a record's fixed head, before the positions.
const RECORD_HEAD_LEN: usize = RECORD_INDICES_OFFSET + 4;
const POSITION_LEN: usize = 12;
const NORMAL_LEN: usize = 3;
const CRC_LEN: usize = 4;
const FLAG_U16_INDICES: u8 = 1;

const TRAILER_MAGIC_OFFSET: usize = 0;
const TRAILER_COUNT_OFFSET: usize = TRAILER_MAGIC_OFFSET + 8;
const TRAILER_CHAIN_OFFSET: usize = TRAILER_COUNT_OFFSET + 8;
const TRAILER_CRC_OFFSET: usize = TRAILER_CHAIN_OFFSET + 4;
/// Bytes in the trailer.
pub const TRAILER_LEN: usize = TRAILER_CRC_OFFSET + 4;

/// Most vertices one record may hold (a sanity limit checked before allocating).
pub const MAX_VERTICES: u32 = 16 << 20;
/// Most indices one record may hold (three per triangle).
pub const MAX_INDICES: u32 = 3 * (16 << 20);

/// What a finished scene holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct SceneSummary {
    /// Objects written.
    pub objects: u64,
    /// Triangles over all objects.
    pub triangles: u64,
    /// Size of the file in bytes.
    pub bytes: u64,
}

fn le_u32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}

fn le_u64(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}

fn header_bytes() -> [u8; HEADER_LEN] {
    let mut h = [0u8; HEADER_LEN];
    h[HEADER_MAGIC_OFFSET..HEADER_VERSION_OFFSET].copy_from_slice(&SCENE_MAGIC);
    h[HEADER_VERSION_OFFSET..HEADER_RESERVED_OFFSET].copy_from_slice(&SCENE_VERSION.to_le_bytes());
    h
}

/// The parsed fixed head of a record.
struct RecordHead {
    id: u64,
    kind: u8,
    flags: u8,
    vertices: u32,
    indices: u32,
}

impl RecordHead {
    fn parse(b: &[u8]) -> RecordHead {
        RecordHead {
            id: le_u64(b, RECORD_ID_OFFSET),
            kind: b[RECORD_KIND_OFFSET],
            flags: b[RECORD_FLAGS_OFFSET],
            vertices: le_u32(b, RECORD_VERTICES_OFFSET),
            indices: le_u32(b, RECORD_INDICES_OFFSET),
        }
    }

    fn index_width(&self) -> usize {
        if self.flags & FLAG_U16_INDICES != 0 {
            2
        } else {
            4
        }
    }

    /// The record's full length in bytes, head and crc included.
    fn len(&self) -> u64 {
        RECORD_HEAD_LEN as u64
            + self.vertices as u64 * (POSITION_LEN + NORMAL_LEN) as u64
            + self.indices as u64 * self.index_width() as u64
            + CRC_LEN as u64
    }

    /// The checks that need no payload: what a corrupt head would otherwise allocate.
    fn check(&self, room: u64) -> Result<(), String> {
        if ObjectKind::from_u8(self.kind).is_none() {
            return Err(format!("unknown kind byte {}", self.kind));
        }
        if self.flags & !FLAG_U16_INDICES != 0 {
            return Err(format!("unknown flags {:#04x}", self.flags));
        }
        if self.vertices > MAX_VERTICES {
            return Err(format!(
                "vertex count {} is over the limit {MAX_VERTICES}",
                self.vertices
            ));
        }
        if self.indices > MAX_INDICES || !self.indices.is_multiple_of(3) {
            return Err(format!(
                "index count {} is not a sane triangle list",
                self.indices
            ));
        }
        if self.index_width() == 2 && self.vertices > 1 << 16 {
            return Err(format!(
                "16-bit indices cannot address {} vertices",
                self.vertices
            ));
        }
        if self.len() > room {
            return Err(format!(
                "its counts ({} vertices, {} indices) need {} bytes, but only {room} remain before the trailer",
                self.vertices,
                self.indices,
                self.len()
            ));
        }
        Ok(())
    }
}

/// Streams the objects of a scene file, verifying each as it goes.
///
/// ```
/// use flaneur_scene::{bunny, ObjectKind, SceneObject, SceneReader, SceneWriter};
/// let dir = tempfile::tempdir()?;
/// let path = dir.path().join("city.scene");
/// let mut writer = SceneWriter::create(&path)?;
/// for id in 0..3 {
///     writer.write(&SceneObject { id, kind: ObjectKind::Bunny, mesh: bunny() })?;
/// }
/// writer.finish()?;
///
/// let reader = SceneReader::open(&path)?;
/// assert_eq!(reader.object_count(), 3);
/// let mut triangles = 0;
/// for object in reader {
///     triangles += object?.mesh.triangle_count();
/// }
/// assert_eq!(triangles, 3 * 3674);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct SceneReader {
    path: PathBuf,
    input: BufReader<File>,
    count: u64,
    expected_chain: u32,
    chain: crc32fast::Hasher,
    /// Index of the next record, and its byte offset.
    next: u64,
    pos: u64,
    /// Offset of the trailer: where records end.
    records_end: u64,
    last_id: Option<u64>,
    buf: Vec<u8>,
    done: bool,
}

impl SceneReader {
    /// Opens a scene file: checks the header and reads the trailer (from the end of the
    /// file). A file without a sound trailer is rejected here: as
    /// [`Truncated`](SceneError::Truncated), naming the object where it ends, or as
    /// [`Corrupt`](SceneError::Corrupt) when the trailer is there but damaged.
    pub fn open(path: &Path) -> Result<Self, SceneError> {
        let io = |e| SceneError::io(path, e);
        let file = File::open(path).map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        let mut input = BufReader::with_capacity(1 << 20, file);
        let mut header = [0u8; HEADER_LEN];
        let got = read_up_to(&mut input, &mut header).map_err(io)?;
        if header[..got.min(8)] != SCENE_MAGIC[..got.min(8)] {
            return Err(SceneError::NotAScene {
                path: path.to_path_buf(),
                what: format!(
                    "it starts with {:?}, not {:?}",
                    String::from_utf8_lossy(&header[..got.min(8)]),
                    "FLNSCENE"
                ),
            });
        }
        if got < HEADER_LEN {
            return Err(SceneError::Truncated {
                path: path.to_path_buf(),
                what: format!("it is {len} bytes, shorter than the {HEADER_LEN}-byte header (before object 0)"),
            });
        }
        let version = le_u32(&header, HEADER_VERSION_OFFSET);
        if version != SCENE_VERSION {
            return Err(SceneError::NotAScene {
                path: path.to_path_buf(),
                what: format!("format version {version}; this build reads version {SCENE_VERSION}"),
            });
        }
        let reserved = le_u32(&header, HEADER_RESERVED_OFFSET);
        if reserved != 0 {
            return Err(SceneError::NotAScene {
                path: path.to_path_buf(),
                what: format!("reserved header field is {reserved:#x}, not 0"),
            });
        }
        let mut reader = SceneReader {
            path: path.to_path_buf(),
            input,
            count: 0,
            expected_chain: 0,
            chain: crc32fast::Hasher::new(),
            next: 0,
            pos: HEADER_LEN as u64,
            records_end: 0,
            last_id: None,
            buf: Vec::new(),
            done: false,
        };
        reader.chain.update(&header);
        match reader.read_trailer(len)? {
            Some((count, chain)) => {
                reader.count = count;
                reader.expected_chain = chain;
                reader.records_end = len - TRAILER_LEN as u64;
                Ok(reader)
            }
            None => Err(reader.diagnose_missing_trailer(len)),
        }
    }

    /// The number of objects in the file, from its trailer.
    pub fn object_count(&self) -> u64 {
        self.count
    }

    /// The trailer's (count, chain crc), `None` when there is no trailer at all, or an
    /// error when its magic is there but the rest is damaged.
    fn read_trailer(&mut self, len: u64) -> Result<Option<(u64, u32)>, SceneError> {
        if len < (HEADER_LEN + TRAILER_LEN) as u64 {
            return Ok(None);
        }
        let mut t = [0u8; TRAILER_LEN];
        let io = |e| SceneError::io(&self.path, e);
        self.input
            .seek(SeekFrom::Start(len - TRAILER_LEN as u64))
            .map_err(io)?;
        self.input.read_exact(&mut t).map_err(io)?;
        self.input
            .seek(SeekFrom::Start(HEADER_LEN as u64))
            .map_err(io)?;
        if t[TRAILER_MAGIC_OFFSET..TRAILER_COUNT_OFFSET] != TRAILER_MAGIC {
            return Ok(None);
        }
        let count = le_u64(&t, TRAILER_COUNT_OFFSET);
        if crc32fast::hash(&t[..TRAILER_CRC_OFFSET]) != le_u32(&t, TRAILER_CRC_OFFSET) {
            return Err(SceneError::Corrupt {
                path: self.path.clone(),
                object: count,
                what: "the trailer after the last object fails its checksum".into(),
            });
        }
        Ok(Some((count, le_u32(&t, TRAILER_CHAIN_OFFSET))))
    }

    /// Walks the record heads (without reading payloads) to say where a file with no
    /// trailer ends.
    fn diagnose_missing_trailer(&mut self, len: u64) -> SceneError {
        let mut pos = HEADER_LEN as u64;
        let mut index = 0u64;
        let mut head = [0u8; RECORD_HEAD_LEN];
        loop {
            let room = len - pos;
            if room == TRAILER_LEN as u64 {
                return SceneError::Corrupt {
                    path: self.path.clone(),
                    object: index,
                    what: "the trailer after the last object has a damaged magic".into(),
                };
            }
            if room == 0 {
                return SceneError::Truncated {
                    path: self.path.clone(),
                    what: format!("it ends before object {index} and has no trailer ({len} bytes)"),
                };
            }
            let cut = || {
                SceneError::Truncated {
                path: self.path.clone(),
                what: format!("it ends inside object {index} (at byte {len}, the object starts at byte {pos})"),
            }
            };
            if room < RECORD_HEAD_LEN as u64 {
                return cut();
            }
            if self.input.read_exact(&mut head).is_err() {
                return cut();
            }
            let h = RecordHead::parse(&head);
            if let Err(what) = h.check(u64::MAX) {
                return SceneError::Corrupt {
                    path: self.path.clone(),
                    object: index,
                    what,
                };
            }
            if h.len() > room {
                return cut();
            }
            let skip = (h.len() - RECORD_HEAD_LEN as u64) as i64;
            if self.input.seek_relative(skip).is_err() {
                return cut();
            }
            pos += h.len();
            index += 1;
        }
    }

    fn corrupt(&self, what: String) -> SceneError {
        SceneError::Corrupt {
            path: self.path.clone(),
            object: self.next,
            what,
        }
    }

    /// `read_exact`, with end of file reported as the current object cut short.
    fn read(&mut self, into: &mut [u8]) -> Result<(), SceneError> {
        self.input.read_exact(into).map_err(|e| {
            if e.kind() == ErrorKind::UnexpectedEof {
                SceneError::Truncated {
                    path: self.path.clone(),
                    what: format!("it ends inside object {}", self.next),
                }
            } else {
                SceneError::io(&self.path, e)
            }
        })
    }

    /// Reads, checks and decodes the next record.
    fn next_record(&mut self) -> Result<SceneObject, SceneError> {
        let mut head_bytes = [0u8; RECORD_HEAD_LEN];
        self.read(&mut head_bytes)?;
        let head = RecordHead::parse(&head_bytes);
        head.check(self.records_end - self.pos)
            .map_err(|w| self.corrupt(w))?;
        let rest = (head.len() - RECORD_HEAD_LEN as u64) as usize;
        let mut buf = std::mem::take(&mut self.buf);
        buf.clear();
        buf.extend_from_slice(&head_bytes);
        buf.resize(RECORD_HEAD_LEN + rest, 0);
        let read = self.read(&mut buf[RECORD_HEAD_LEN..]);
        let result = read.and_then(|()| self.decode(&head, &buf));
        self.buf = buf;
        let object = result?;
        self.pos += head.len();
        self.next += 1;
        Ok(object)
    }

    fn decode(&mut self, head: &RecordHead, buf: &[u8]) -> Result<SceneObject, SceneError> {
        let stored = record_crc(head, buf).map_err(|w| self.corrupt(w))?;
        if let Some(last) = self.last_id {
            if head.id <= last {
                return Err(self.corrupt(format!("id {} does not follow id {last}", head.id)));
            }
        }
        let object = parse_record(head, buf).map_err(|w| self.corrupt(w))?;
        self.chain.update(&stored.to_le_bytes());
        self.last_id = Some(head.id);
        Ok(object)
    }

    /// Where the record [`next`](Iterator::next) reads next starts: with
    /// [`read_at`](Self::read_at), a way back to it.
    pub fn position(&self) -> RecordPos {
        RecordPos {
            index: self.next,
            offset: self.pos,
        }
    }

    /// Reads, checks and decodes the record at `at` (one [`position`](Self::position)
    /// gave) without moving the iteration. A build that writes objects in an order of its
    /// own reads them with this after one pass over the file, the pass that checked the
    /// file's order and its chain of checksums; this checks the record's own checksum and
    /// its mesh, and names the object by its place in the file when they fail.
    ///
    /// ```
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use flaneur_scene::{ObjectKind, SceneObject, SceneReader, SceneWriter};
    /// let dir = tempfile::tempdir()?;
    /// let path = dir.path().join("two.scene");
    /// let mut w = SceneWriter::create(&path)?;
    /// for id in [4, 9] {
    ///     w.write(&SceneObject { id, kind: ObjectKind::House, mesh: flaneur_scene::bunny() })?;
    /// }
    /// w.finish()?;
    /// let mut r = SceneReader::open(&path)?;
    /// let first = r.position();
    /// let ids: Vec<u64> = r.by_ref().map(|o| o.map(|o| o.id)).collect::<Result<_, _>>()?;
    /// assert_eq!(ids, [4, 9]);
    /// assert_eq!(r.read_at(first)?.id, 4); // back to the first record, after the end
    /// # Ok(()) }
    /// ```
    pub fn read_at(&mut self, at: RecordPos) -> Result<SceneObject, SceneError> {
        let corrupt = |what| SceneError::Corrupt {
            path: self.path.clone(),
            object: at.index,
            what,
        };
        if at.offset < HEADER_LEN as u64 || at.offset >= self.records_end {
            return Err(corrupt(format!(
                "no record starts at byte {}: records lie in bytes {HEADER_LEN}..{}",
                at.offset, self.records_end
            )));
        }
        let io = |e| SceneError::io(&self.path, e);
        self.input.seek(SeekFrom::Start(at.offset)).map_err(io)?;
        let mut head_bytes = [0u8; RECORD_HEAD_LEN];
        let read = self.input.read_exact(&mut head_bytes).map_err(io);
        let head = RecordHead::parse(&head_bytes);
        let checked =
            read.and_then(|()| head.check(self.records_end - at.offset).map_err(&corrupt));
        let mut buf = std::mem::take(&mut self.buf);
        let result = checked.and_then(|()| {
            buf.clear();
            buf.extend_from_slice(&head_bytes);
            buf.resize(head.len() as usize, 0);
            self.input
                .read_exact(&mut buf[RECORD_HEAD_LEN..])
                .map_err(io)?;
            record_crc(&head, &buf).map_err(&corrupt)?;
            parse_record(&head, &buf).map_err(corrupt)
        });
        self.buf = buf;
        // Back to where the iteration was, whatever happened above.
        self.input.seek(SeekFrom::Start(self.pos)).map_err(io)?;
        result
    }

    /// The checks after the last record: it ends where the trailer starts, and the chain
    /// of record checksums matches.
    fn finish_check(&mut self) -> Result<(), SceneError> {
        if self.pos != self.records_end {
            return Err(self.corrupt(format!(
                "the trailer says {} objects, but {} bytes of records remain after them",
                self.count,
                self.records_end - self.pos
            )));
        }
        let chain = std::mem::take(&mut self.chain).finalize();
        if chain != self.expected_chain {
            return Err(self.corrupt(
                "the records' checksum chain does not match the trailer (objects dropped, duplicated or reordered)".into(),
            ));
        }
        Ok(())
    }
}

/// Where one record of a scene file starts: its place among the records and its byte
/// offset. [`SceneReader::position`] gives it and [`SceneReader::read_at`] goes back to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RecordPos {
    /// The record's place in the file, from 0.
    pub index: u64,
    /// The byte offset of its first byte.
    pub offset: u64,
}

/// The record's stored checksum, once it matches the bytes before it.
fn record_crc(head: &RecordHead, buf: &[u8]) -> Result<u32, String> {
    let body = buf.len() - CRC_LEN;
    let stored = le_u32(buf, body);
    if crc32fast::hash(&buf[..body]) != stored {
        return Err(format!(
            "record checksum mismatch (id field reads {})",
            head.id
        ));
    }
    Ok(stored)
}

/// The object a checked record holds, its mesh validated.
fn parse_record(head: &RecordHead, buf: &[u8]) -> Result<SceneObject, String> {
    let body = buf.len() - CRC_LEN;
    let v = head.vertices as usize;
    let mut at = RECORD_HEAD_LEN;
    let positions: Vec<[f32; 3]> = buf[at..at + v * POSITION_LEN]
        .chunks_exact(POSITION_LEN)
        .map(|p| {
            let f = |k: usize| f32::from_le_bytes(p[4 * k..4 * k + 4].try_into().expect("4 bytes"));
            [f(0), f(1), f(2)]
        })
        .collect();
    at += v * POSITION_LEN;
    let normals: Vec<[f32; 3]> = buf[at..at + v * NORMAL_LEN]
        .chunks_exact(NORMAL_LEN)
        .map(|n| dequantize_normal([n[0] as i8, n[1] as i8, n[2] as i8]))
        .collect();
    at += v * NORMAL_LEN;
    let indices: Vec<u32> = if head.index_width() == 2 {
        buf[at..body]
            .chunks_exact(2)
            .map(|i| u16::from_le_bytes([i[0], i[1]]) as u32)
            .collect()
    } else {
        buf[at..body]
            .chunks_exact(4)
            .map(|i| u32::from_le_bytes([i[0], i[1], i[2], i[3]]))
            .collect()
    };
    let mesh = Mesh {
        positions,
        normals,
        indices,
    };
    mesh.validate().map_err(|w| format!("invalid mesh: {w}"))?;
    let kind = ObjectKind::from_u8(head.kind).expect("checked in the head");
    Ok(SceneObject {
        id: head.id,
        kind,
        mesh,
    })
}

impl Iterator for SceneReader {
    type Item = Result<SceneObject, SceneError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let item = if self.next == self.count {
            self.done = true;
            return self.finish_check().err().map(Err);
        } else {
            self.next_record()
        };
        if item.is_err() {
            self.done = true;
        }
        Some(item)
    }
}

/// snorm8 back to a unit vector. An all-zero triple (never written for a unit normal)
/// decodes to +y rather than to NaN.
pub fn dequantize_normal(q: [i8; 3]) -> [f32; 3] {
    let v = glam::Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32) / 127.0;
    v.try_normalize().unwrap_or(glam::Vec3::Y).to_array()
}

/// `read_exact` that stops quietly at end of file, returning how much it read.
fn read_up_to(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snorm8_round_trip_is_close() {
        for n in [
            [1.0, 0.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.577_35, 0.577_35, -0.577_35],
            [0.6, 0.8, 0.0],
        ] {
            let q = n.map(quantize_snorm8);
            let d = dequantize_normal(q);
            let dot: f32 = (0..3).map(|k| n[k] * d[k]).sum();
            assert!(dot > 0.9995, "{n:?} -> {d:?}");
        }
        assert_eq!(dequantize_normal([0, 0, 0]), [0.0, 1.0, 0.0]);
    }

    #[test]
    fn layout_constants_add_up() {
        assert_eq!(HEADER_LEN, 16);
        assert_eq!(RECORD_HEAD_LEN, 18);
        assert_eq!(TRAILER_LEN, 24);
    }

    /// A scene of three bunnies (ids 10, 11, 12) and where each record starts.
    fn three(dir: &Path) -> (PathBuf, Vec<RecordPos>) {
        let path = dir.join("three.scene");
        let mut w = SceneWriter::create(&path).unwrap();
        for id in 10..13 {
            let mesh = crate::bunny();
            w.write(&SceneObject {
                id,
                kind: ObjectKind::House,
                mesh,
            })
            .unwrap();
        }
        w.finish().unwrap();
        let mut r = SceneReader::open(&path).unwrap();
        let mut at = Vec::new();
        loop {
            at.push(r.position());
            if r.next().transpose().unwrap().is_none() {
                break;
            }
        }
        at.pop();
        (path, at)
    }

    #[test]
    fn read_at_goes_back_to_any_record_and_leaves_the_iteration_where_it_was() {
        let dir = tempfile::tempdir().unwrap();
        let (path, at) = three(dir.path());
        let mut r = SceneReader::open(&path).unwrap();
        assert_eq!(r.next().unwrap().unwrap().id, 10);
        assert_eq!(r.read_at(at[2]).unwrap().id, 12);
        assert_eq!(r.read_at(at[0]).unwrap().id, 10);
        let rest: Vec<u64> = r.map(|o| o.unwrap().id).collect();
        assert_eq!(rest, [11, 12]);
    }

    #[test]
    fn read_at_names_a_damaged_record_and_refuses_an_offset_outside_the_records() {
        let dir = tempfile::tempdir().unwrap();
        let (path, at) = three(dir.path());
        let mut bytes = std::fs::read(&path).unwrap();
        bytes[at[1].offset as usize + RECORD_HEAD_LEN + 5] ^= 0x40;
        std::fs::write(&path, &bytes).unwrap();
        let mut r = SceneReader::open(&path).unwrap();
        assert_eq!(r.read_at(at[2]).unwrap().id, 12);
        match r.read_at(at[1]) {
            Err(SceneError::Corrupt { object, what, .. }) => {
                assert_eq!(object, 1);
                assert!(what.contains("checksum"), "{what}");
            }
            other => panic!("{other:?}"),
        }
        let past = RecordPos {
            index: 3,
            offset: bytes.len() as u64,
        };
        assert!(matches!(
            r.read_at(past),
            Err(SceneError::Corrupt { object: 3, .. })
        ));
        // A position inside a record reads a head that does not add up.
        let inside = RecordPos {
            index: 0,
            offset: at[0].offset + 3,
        };
        assert!(r.read_at(inside).is_err());
    }
}
