//! Format version 2's mesh: meshoptimizer's index and vertex codecs over quantised
//! vertices (`quantize`), levels of detail that share one vertex buffer, and an optional
//! zstd frame around each buffer (`squeeze`).
//!
//! **Levels share their vertices.** One blob holds one or more levels of one object,
//! coarsest first. The simplifier's half-edge collapses keep a subset of the vertices at
//! every level, so one vertex buffer serves them all when it is ordered coarsest level
//! first (meshoptimizer's practice for LOD chains): each level adds a *chunk*, the
//! vertices it uses that no coarser level did, encoded on its own because the vertex
//! codec's stream decodes only whole, then its index buffer over every vertex so far.
//! Level `j` is therefore read from the blob's first bytes, up to the end of its index
//! buffer, and never needs a finer level's bytes. An object's full mesh is a blob of one
//! level; its coarse levels are a second blob, in its LOD chain (`lod::stored::chain`):
//! sharing the full mesh's vertices too made the full meshes of the 3,000-object city 86 %
//! larger (the index codec wants vertices in the order a mesh first uses them), and a
//! walk reads the full meshes most.
//!
//! **Codec versions.** Vertex codec version 0 and index codec version 1: those glTF's
//! `EXT_meshopt_compression` carries (its attribute mode takes vertex version 0 only; the
//! vendored library writes version 1 unless told), so that a tileset export can copy a
//! level's buffers unchanged. Version 1's vertex codec is some 5–10 % smaller; the zstd
//! layer more than makes up for it.
//!
//! ```text
//! offset     width  field
//! ---------  -----  -----------------------------------------------------------------
//!         0      4  magic          b"FLG2" (a version-1 mesh starts with its vertex
//!                                  count, which can never be these bytes: 843 M vertices)
//!         4      1  flags          bit 0: every buffer is a zstd frame; bit 1: the
//!                                  face layout (below); bit 2 (with bit 0): the
//!                                  frames use the database's dictionary for full
//!                                  meshes or for coarse levels (`dictionary`)
//!         5      1  reserved       zero
//!         6      2  levels c       u16, >= 1, coarsest first
//!         8     24  box            f32 x 3 min, f32 x 3 max: the quantisation grid
//!        32    28c  level table    per level: vertices it adds u32, their positions'
//!                                  and normals' bytes u32 u32 (meshoptimizer's), the
//!                                  chunk's stored bytes u32, index count u32, index
//!                                  bytes u32 (meshoptimizer's), stored u32
//!  32 + 28c      …  levels         back to back, coarsest first: the chunk (positions ‖
//!                                  normals, one zstd frame when flagged), then the index
//!                                  buffer (one frame when flagged)
//! ```
//!
//! **The face layout** (`faces`), for flat-shaded meshes: a vertex is a position alone,
//! added once however many faces meet there, and the index buffer names positions. A
//! level's "normals" are its exceptions' (the corners whose normal is not their face's),
//! and its chunk ends with one bit a corner marking them, `ceil(index count / 8)` bytes
//! in the order the index codec gives the corners back. A blob takes it when at most one
//! corner in two is an exception: on the 3,000-object city the full meshes fall from 3.81
//! to 2.13 bytes a triangle.
//!
//! Decoding checks every length against the bytes before it allocates, every index
//! against the vertices, and refuses whatever the codecs refuse: never a panic, whatever
//! the bytes.

use std::borrow::Cow;

use rustc_hash::FxHashMap;

use super::dictionary::{Dictionaries, Use};
use super::faces;
use super::quantize::{dequantize_normals, quantize_normal, Grid, QNormal, QPosition};
use super::squeeze::Framing;
use crate::scene::Mesh;

/// The first four bytes of a version-2 mesh.
pub(crate) const MAGIC: [u8; 4] = *b"FLG2";
const FLAG_ZSTD: u8 = 1;
const FLAG_FACES: u8 = 2;
/// Set beside `FLAG_ZSTD`: the frames were compressed with the database's dictionary
/// (`dictionary`) for the blob's use, full mesh or coarse levels.
const FLAG_DICTIONARY: u8 = 4;
const FLAGS_OFFSET: usize = 4;
const LEVELS_OFFSET: usize = 6;
const BOX_OFFSET: usize = 8;
const TABLE_OFFSET: usize = BOX_OFFSET + 24;
const LEVEL_ENTRY_LEN: usize = 28;
/// The vertex codec version `EXT_meshopt_compression` decodes.
const VERTEX_CODEC_VERSION: i32 = 0;
/// Bytes of one vertex in the two streams.
const POSITION_STRIDE: usize = std::mem::size_of::<QPosition>();
const NORMAL_STRIDE: usize = std::mem::size_of::<QNormal>();
/// How much larger than its stored bytes a buffer may claim to expand: well above what
/// the codecs reach on real meshes, and a bound on what damaged bytes make a reader
/// allocate.
const MAX_EXPANSION: usize = 1024;
const SLACK: usize = 64 << 10;

/// Whether `bytes` start as a version-2 mesh.
pub(crate) fn is_geometry(bytes: &[u8]) -> bool {
    bytes.starts_with(&MAGIC)
}

/// Bytes of the header and level table of a blob of `levels` levels.
pub(crate) fn head_len(levels: usize) -> usize {
    TABLE_OFFSET + LEVEL_ENTRY_LEN * levels
}

/// One level as a blob stores it: where its bytes (chunk and index buffer) lie, and how
/// many vertices and indices it reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct LevelSpan {
    /// Its bytes in the blob, `start..end`.
    pub start: usize,
    pub end: usize,
    /// The vertices it reads: its own and every coarser level's.
    pub vertices: usize,
    /// Its index count.
    pub indices: usize,
}

/// Encodes `levels` (coarsest first, each a subset of the next finer's vertices, as the
/// simplifier's are; a vertex that is not simply joins the chunk of the first level that
/// uses it) as one blob, its buffers stored as `framing` says. Returns the blob and where each level
/// lies in it.
///
/// Flat-shaded levels (at most one corner in two whose normal is not its face's) take the
/// face layout (`faces`), the rest the vertex layout.
pub(crate) fn encode_levels(
    levels: &[&Mesh],
    framing: Framing,
) -> Result<(Vec<u8>, Vec<LevelSpan>), String> {
    let encoded = encode_levels_as(levels, framing)?;
    // zstd can shrink a very regular buffer (a fine grid's index buffer, with a
    // dictionary) further than the reader lets any buffer claim to expand
    // (`MAX_EXPANSION`, its guard against damaged lengths). Such a blob is stored
    // unframed, a little larger, rather than written for no reader to read.
    let (dict, which) = match framing {
        Framing::Plain => return Ok(encoded),
        Framing::Zstd(_) => (None, Use::Meshes),
        Framing::Dictionary(d, which) => (Some(d), which),
    };
    match Head::read(&encoded.0, dict, which) {
        Ok(_) => Ok(encoded),
        Err(_) => encode_levels_as(levels, Framing::Plain),
    }
}

/// [`encode_levels`] in `framing`, whatever the reader makes of it.
fn encode_levels_as(
    levels: &[&Mesh],
    framing: Framing,
) -> Result<(Vec<u8>, Vec<LevelSpan>), String> {
    if levels.is_empty() || levels.len() > u16::MAX as usize {
        return Err(format!("{} levels in one blob", levels.len()));
    }
    for m in levels {
        m.validate()?;
    }
    let grid = Grid::around(levels.iter().copied());
    if !grid.is_valid() {
        return Err(format!(
            "its box {:?}..{:?} spans more than an f32 holds: no 16-bit grid covers it",
            grid.min, grid.max
        ));
    }
    let corners: Vec<Vec<Corner>> = levels.iter().map(|m| cached_corners(m, &grid)).collect();
    let (exceptions, all): (usize, usize) = corners
        .iter()
        .map(|c| (faces::count_exceptions(&grid, c), c.len()))
        .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    let by_faces = faces::suits(exceptions, all);
    let encoded = if by_faces {
        encode_by_faces(&grid, &corners, framing)?
    } else {
        encode_by_vertices(&corners, framing)?
    };
    let head = head_len(levels.len());
    let mut table = Vec::with_capacity(levels.len() * LEVEL_ENTRY_LEN);
    let mut body = Vec::new();
    let mut spans = Vec::with_capacity(levels.len());
    for e in &encoded {
        for field in [
            e.added,
            e.positions,
            e.normals,
            e.chunk.len(),
            e.index_count,
            e.index_bytes,
            e.indices.len(),
        ] {
            table.extend_from_slice(&u32_of(field)?.to_le_bytes());
        }
        let start = head + body.len();
        body.extend_from_slice(&e.chunk);
        body.extend_from_slice(&e.indices);
        spans.push(LevelSpan {
            start,
            end: head + body.len(),
            vertices: e.vertices,
            indices: e.index_count,
        });
    }
    let mut out = Vec::with_capacity(head + body.len());
    out.extend_from_slice(&MAGIC);
    let mut flags = match framing {
        Framing::Plain => 0,
        Framing::Zstd(_) => FLAG_ZSTD,
        Framing::Dictionary(..) => FLAG_ZSTD | FLAG_DICTIONARY,
    };
    if by_faces {
        flags |= FLAG_FACES;
    }
    out.push(flags);
    out.push(0);
    out.extend_from_slice(&(levels.len() as u16).to_le_bytes());
    for c in grid.min.iter().chain(&grid.max) {
        out.extend_from_slice(&c.to_le_bytes());
    }
    out.extend_from_slice(&table);
    out.extend_from_slice(&body);
    u32_of(out.len())?;
    Ok((out, spans))
}

/// A triangle corner as stored: its quantised position and normal.
type Corner = (QPosition, QNormal);

/// A mesh's corners, triangles in meshoptimizer's vertex-cache order.
fn cached_corners(m: &Mesh, grid: &Grid) -> Vec<Corner> {
    meshopt::optimize_vertex_cache(&m.indices, m.positions.len())
        .into_iter()
        .map(|i| {
            let i = i as usize;
            (grid.quantize(m.positions[i]), quantize_normal(m.normals[i]))
        })
        .collect()
}

/// One level's bytes before they go in the blob.
struct EncodedLevel {
    /// Vertices (vertex layout) or positions (face layout) it adds.
    added: usize,
    /// meshoptimizer's bytes of the added positions, and of the added normals (vertex
    /// layout) or the level's exceptions (face layout).
    positions: usize,
    normals: usize,
    /// The stored chunk: positions ‖ normals (‖ the exception bits, face layout).
    chunk: Vec<u8>,
    index_count: usize,
    index_bytes: usize,
    /// The stored index buffer.
    indices: Vec<u8>,
    /// The vertices the level decodes to.
    vertices: usize,
}

/// The vertex layout: each distinct (position, normal) a vertex, in first-use order.
fn encode_by_vertices(
    levels: &[Vec<Corner>],
    framing: Framing,
) -> Result<Vec<EncodedLevel>, String> {
    let mut ids: FxHashMap<Corner, u32> = FxHashMap::default();
    let (mut positions, mut normals) = (Vec::new(), Vec::new());
    let mut out = Vec::with_capacity(levels.len());
    for corners in levels {
        let first_new = positions.len();
        let indices: Vec<u32> = corners
            .iter()
            .map(|&key| {
                *ids.entry(key).or_insert_with(|| {
                    positions.push(key.0);
                    normals.push(key.1);
                    (positions.len() - 1) as u32
                })
            })
            .collect();
        let p = encode_stream(&positions[first_new..])?;
        let n = encode_stream(&normals[first_new..])?;
        let (positions_len, normals_len) = (p.len(), n.len());
        let mut raw = p;
        raw.extend_from_slice(&n);
        let index_buffer = encode_indices(&indices, positions.len())?;
        out.push(EncodedLevel {
            added: positions.len() - first_new,
            positions: positions_len,
            normals: normals_len,
            chunk: framing.squeeze(&raw)?,
            index_count: indices.len(),
            index_bytes: index_buffer.len(),
            indices: framing.squeeze(&index_buffer)?,
            vertices: positions.len(),
        });
    }
    Ok(out)
}

/// The face layout: positions once, normals from faces. A blob of one level (a full
/// mesh, or a chain of one coarse level) keeps its triangles in the vertex cache's order
/// over its vertices, where a full mesh's faces stay together; the levels of a longer
/// chain are laid out in the cache's order over their positions (on the 3,000-object
/// city, 1.92 against 2.10 bytes a triangle of full meshes, 3.59 against 3.97 at the
/// first level). Laying out each level both ways
/// and keeping the smaller cost 12 % more build time and made the full meshes larger
/// (1.77 bytes a triangle against 1.61): the dictionaries, trained on a mix of the two
/// layouts, then suit neither.
fn encode_by_faces(
    grid: &Grid,
    levels: &[Vec<Corner>],
    framing: Framing,
) -> Result<Vec<EncodedLevel>, String> {
    let mut shared = faces::SharedPositions::default();
    let mut out: Vec<EncodedLevel> = Vec::with_capacity(levels.len());
    let full_mesh = levels.len() == 1;
    for corners in levels {
        let by_positions;
        let order = if full_mesh {
            corners
        } else {
            by_positions = faces::position_cache_order(corners);
            &by_positions
        };
        out.push(encode_face_level(
            &shared.lay_out(grid, order),
            shared.len(),
            framing,
        )?);
    }
    Ok(out)
}

fn encode_face_level(
    level: &faces::FaceLevel,
    positions: usize,
    framing: Framing,
) -> Result<EncodedLevel, String> {
    let index_buffer = encode_indices(&level.indices, positions)?;
    let stored_order = meshopt::decode_index_buffer(&index_buffer, level.indices.len())
        .map_err(|e| format!("meshoptimizer's index codec read back: {e:?}"))?;
    let exceptions = level.exceptions(&stored_order)?;
    let p = encode_stream(&level.added)?;
    let n = encode_stream(&exceptions.normals)?;
    let (positions_len, normals_len) = (p.len(), n.len());
    let mut raw = p;
    raw.extend_from_slice(&n);
    raw.extend_from_slice(&exceptions.bits);
    Ok(EncodedLevel {
        added: level.added.len(),
        positions: positions_len,
        normals: normals_len,
        chunk: framing.squeeze(&raw)?,
        index_count: level.indices.len(),
        index_bytes: index_buffer.len(),
        indices: framing.squeeze(&index_buffer)?,
        vertices: level.vertices,
    })
}

fn encode_indices(indices: &[u32], vertices: usize) -> Result<Vec<u8>, String> {
    meshopt::encode_index_buffer(indices, vertices)
        .map_err(|e| format!("meshoptimizer's index codec: {e:?}"))
}

/// Encodes one mesh as a blob of one level.
pub(crate) fn encode(mesh: &Mesh, framing: Framing) -> Result<Vec<u8>, String> {
    Ok(encode_levels(&[mesh], framing)?.0)
}

fn u32_of(n: usize) -> Result<u32, String> {
    u32::try_from(n).map_err(|_| format!("{n} is over the 4 GiB a mesh extent holds"))
}

fn encode_stream<T>(vertices: &[T]) -> Result<Vec<u8>, String> {
    if vertices.is_empty() {
        return Ok(Vec::new());
    }
    meshopt::encode_vertex_buffer_level(vertices, 2, Some(VERTEX_CODEC_VERSION))
        .map_err(|e| format!("meshoptimizer's vertex codec: {e:?}"))
}

/// A blob's header and level table, checked against each other.
struct Head<'d> {
    /// How its buffers are stored.
    framing: Framing<'d>,
    /// The face layout (`faces`): positions once, normals from faces.
    by_faces: bool,
    grid: Grid,
    levels: Vec<Level>,
}

#[derive(Clone, Copy)]
struct Level {
    vertices: usize,
    positions: usize,
    normals: usize,
    stored: usize,
    index_count: usize,
    index_bytes: usize,
    index_stored: usize,
    /// Where its chunk starts in the blob; its index buffer follows.
    at: usize,
}

impl Level {
    fn end(&self) -> usize {
        self.at + self.stored + self.index_stored
    }

    /// Bytes of its chunk once expanded.
    fn raw(&self, by_faces: bool) -> usize {
        let bits = if by_faces {
            faces::bits_len(self.index_count)
        } else {
            0
        };
        self.positions + self.normals + bits
    }
}

fn u32_at(b: &[u8], at: usize) -> usize {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("four bytes")) as usize
}

impl<'d> Head<'d> {
    /// Reads the header from the blob's first bytes (at least its header and table); a
    /// blob compressed with a dictionary is read with `dict`'s for `which`.
    fn read(bytes: &[u8], dict: Option<&'d Dictionaries>, which: Use) -> Result<Head<'d>, String> {
        if bytes.len() < TABLE_OFFSET || !is_geometry(bytes) {
            return Err(format!(
                "{} bytes do not start a version-2 mesh (magic FLG2 and a {TABLE_OFFSET}-byte header)",
                bytes.len()
            ));
        }
        let flags = bytes[FLAGS_OFFSET];
        if flags & !(FLAG_ZSTD | FLAG_FACES | FLAG_DICTIONARY) != 0
            || flags & (FLAG_ZSTD | FLAG_DICTIONARY) == FLAG_DICTIONARY
            || bytes[FLAGS_OFFSET + 1] != 0
        {
            return Err(format!("unknown flags {flags:#04x}"));
        }
        let framing = match (flags & FLAG_ZSTD != 0, flags & FLAG_DICTIONARY != 0) {
            (false, _) => Framing::Plain,
            (true, false) => Framing::Zstd(0),
            (true, true) => match dict.filter(|d| d.has(which)) {
                Some(d) => Framing::Dictionary(d, which),
                None => {
                    return Err(format!(
                        "compressed with its database's zstd dictionary for {}, which the \
                         reader was not given",
                        match which {
                            Use::Meshes => "full meshes",
                            Use::Levels => "coarse levels",
                        }
                    ))
                }
            },
        };
        let c = u16::from_le_bytes([bytes[LEVELS_OFFSET], bytes[LEVELS_OFFSET + 1]]) as usize;
        if c == 0 {
            return Err("a mesh of no level".into());
        }
        let table_end = head_len(c);
        if bytes.len() < table_end {
            return Err(format!(
                "{} bytes hold no table of {c} levels ({table_end} bytes)",
                bytes.len()
            ));
        }
        let f = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().expect("four bytes"));
        let grid = Grid {
            min: std::array::from_fn(|k| f(BOX_OFFSET + 4 * k)),
            max: std::array::from_fn(|k| f(BOX_OFFSET + 12 + 4 * k)),
        };
        if !grid.is_valid() {
            return Err(format!(
                "its box {:?}..{:?} is not a box",
                grid.min, grid.max
            ));
        }
        let by_faces = flags & FLAG_FACES != 0;
        let mut levels = Vec::with_capacity(c);
        let (mut at, mut vertices) = (table_end, 0usize);
        for k in 0..c {
            let e = TABLE_OFFSET + k * LEVEL_ENTRY_LEN;
            let l = Level {
                vertices: u32_at(bytes, e),
                positions: u32_at(bytes, e + 4),
                normals: u32_at(bytes, e + 8),
                stored: u32_at(bytes, e + 12),
                index_count: u32_at(bytes, e + 16),
                index_bytes: u32_at(bytes, e + 20),
                index_stored: u32_at(bytes, e + 24),
                at,
            };
            // The face layout's normals are its exceptions, counted by its bits.
            let normals_ok = if by_faces {
                l.vertices == 0 || l.positions != 0
            } else {
                l.vertices * NORMAL_STRIDE <= MAX_EXPANSION * l.normals + SLACK
                    && (l.vertices == 0) == (l.positions + l.normals == 0)
            };
            if l.vertices * POSITION_STRIDE > MAX_EXPANSION * l.positions + SLACK
                || !normals_ok
                || l.raw(by_faces) > MAX_EXPANSION * l.stored + SLACK
                || l.index_bytes > MAX_EXPANSION * l.index_stored + SLACK
            {
                return Err(format!(
                    "level {k} claims {} vertices in {} + {} bytes stored in {}, {} index \
                     bytes stored in {}",
                    l.vertices, l.positions, l.normals, l.stored, l.index_bytes, l.index_stored
                ));
            }
            check_index_count(l.index_count, l.index_bytes)?;
            vertices += l.vertices;
            at = l.end();
            levels.push(l);
        }
        if vertices > u32::MAX as usize {
            return Err(format!("{vertices} vertices"));
        }
        Ok(Head {
            framing,
            by_faces,
            grid,
            levels,
        })
    }

    /// Level `j` (0 the coarsest) from `bytes`, which hold it and every coarser level.
    fn level(&self, bytes: &[u8], j: usize) -> Result<Mesh, String> {
        let Some(level) = self.levels.get(j) else {
            return Err(format!("no level {j} of {}", self.levels.len()));
        };
        if bytes.len() < level.end() {
            return Err(format!(
                "level {j} ends at byte {}, past the {} read",
                level.end(),
                bytes.len()
            ));
        }
        if self.by_faces {
            return self.level_by_faces(bytes, j);
        }
        let (mut positions, mut normals) = (Vec::new(), Vec::new());
        for (k, l) in self.levels[..=j].iter().enumerate() {
            if l.vertices == 0 {
                continue;
            }
            let raw = self.chunk(bytes, k)?;
            let p: Vec<QPosition> = meshopt::decode_vertex_buffer(&raw[..l.positions], l.vertices)
                .map_err(|e| format!("level {k}'s positions: {e:?}"))?;
            let n: Vec<QNormal> = meshopt::decode_vertex_buffer(&raw[l.positions..], l.vertices)
                .map_err(|e| format!("level {k}'s normals: {e:?}"))?;
            self.grid.dequantize_into(&p, &mut positions);
            let n = dequantize_normals(&n, |q| [q[0], q[1], q[2]]);
            if normals.is_empty() {
                normals = n;
            } else {
                normals.extend_from_slice(&n);
            }
        }
        let indices = self.indices(bytes, j, positions.len())?;
        Ok(Mesh {
            positions,
            normals,
            indices,
        })
    }

    /// Level `j` of the face layout: every coarser level's positions, then its own
    /// triangles, bits and exceptions joined into vertices.
    fn level_by_faces(&self, bytes: &[u8], j: usize) -> Result<Mesh, String> {
        let mut positions = Vec::new();
        let mut own = Cow::Borrowed(&[][..]);
        for (k, l) in self.levels[..=j].iter().enumerate() {
            let raw = self.chunk(bytes, k)?;
            if l.vertices > 0 {
                let p: Vec<QPosition> =
                    meshopt::decode_vertex_buffer(&raw[..l.positions], l.vertices)
                        .map_err(|e| format!("level {k}'s positions: {e:?}"))?;
                self.grid.dequantize_into(&p, &mut positions);
            }
            if k == j {
                own = raw;
            }
        }
        let level = &self.levels[j];
        let (exceptions, bits) = own[level.positions..].split_at(level.normals);
        let corners = level.index_count;
        if !corners.is_multiple_of(8) && bits.last().is_some_and(|b| b >> (corners % 8) != 0) {
            return Err(format!(
                "level {j}'s exception bits mark corners past its {corners}"
            ));
        }
        let count = faces::exception_count(bits);
        if count * NORMAL_STRIDE > MAX_EXPANSION * exceptions.len() + SLACK
            || (count == 0) != exceptions.is_empty()
        {
            return Err(format!(
                "level {j} marks {count} exceptions, stored in {} bytes",
                exceptions.len()
            ));
        }
        let exceptions: Vec<QNormal> = if count == 0 {
            Vec::new()
        } else {
            meshopt::decode_vertex_buffer(exceptions, count)
                .map_err(|e| format!("level {j}'s exceptions: {e:?}"))?
        };
        let indices = self.indices(bytes, j, positions.len())?;
        let (positions, normals, indices) = faces::assemble(&positions, indices, bits, &exceptions);
        Ok(Mesh {
            positions,
            normals,
            indices,
        })
    }

    /// Level `k`'s chunk, expanded.
    fn chunk<'a>(&self, bytes: &'a [u8], k: usize) -> Result<Cow<'a, [u8]>, String> {
        let l = &self.levels[k];
        self.framing
            .expand(&bytes[l.at..l.at + l.stored], l.raw(self.by_faces))
            .map_err(|w| format!("level {k}'s vertices: {w}"))
    }

    /// Level `j`'s index buffer, each index checked against the `vertices` before it.
    fn indices(&self, bytes: &[u8], j: usize, vertices: usize) -> Result<Vec<u32>, String> {
        let level = &self.levels[j];
        let at = level.at + level.stored;
        let raw = self
            .framing
            .expand(&bytes[at..at + level.index_stored], level.index_bytes)
            .map_err(|w| format!("level {j}'s index buffer: {w}"))?;
        decode_indices(&raw, level.index_count, vertices)
    }
}

fn check_index_count(index_count: usize, index_bytes: usize) -> Result<(), String> {
    // The index codec spends at least half a byte a triangle.
    if !index_count.is_multiple_of(3) || index_count > 8 * index_bytes + 64 {
        return Err(format!(
            "{index_count} indices in an index buffer of {index_bytes} bytes"
        ));
    }
    Ok(())
}

fn decode_indices(buffer: &[u8], count: usize, vertices: usize) -> Result<Vec<u32>, String> {
    if count == 0 {
        return Ok(Vec::new());
    }
    let indices: Vec<u32> = meshopt::decode_index_buffer(buffer, count)
        .map_err(|e| format!("the index buffer does not decode: {e:?}"))?;
    // The largest first, which runs on vectors; the culprit only once there is one.
    let largest = indices.iter().copied().fold(0, u32::max);
    if (largest as usize) < vertices {
        return Ok(indices);
    }
    if let Some((k, i)) = indices
        .iter()
        .enumerate()
        .find(|(_, &i)| i as usize >= vertices)
    {
        return Err(format!(
            "index {i} at position {k} names no vertex (there are {vertices})"
        ));
    }
    Ok(indices)
}

/// Decodes a whole blob's finest level: an object's full mesh (with `dict`'s
/// dictionary for full meshes, when it was compressed with one).
pub(crate) fn decode(bytes: &[u8], dict: Option<&Dictionaries>) -> Result<Mesh, String> {
    let head = Head::read(bytes, dict, Use::Meshes)?;
    let last = head.levels.len() - 1;
    if head.levels[last].end() != bytes.len() {
        return Err(format!(
            "its levels end at byte {}, the mesh is {} bytes",
            head.levels[last].end(),
            bytes.len()
        ));
    }
    head.level(bytes, last)
}

/// Decodes level `j` (0 the coarsest) of a blob from its first bytes, which hold that
/// level and every coarser one (with `dict`'s dictionary for coarse levels, when it was
/// compressed with one).
pub(crate) fn decode_level(
    prefix: &[u8],
    j: usize,
    dict: Option<&Dictionaries>,
) -> Result<Mesh, String> {
    Head::read(prefix, dict, Use::Levels)?.level(prefix, j)
}

/// Whether a version-2 mesh takes the face layout.
#[cfg(test)]
pub(crate) fn by_faces(bytes: &[u8]) -> bool {
    is_geometry(bytes) && bytes.get(FLAGS_OFFSET).is_some_and(|f| f & FLAG_FACES != 0)
}

/// The quantisation grid of a version-2 mesh, from its first bytes: where every vertex it
/// reads back lies.
#[cfg(test)]
pub(crate) fn grid_of(bytes: &[u8]) -> Result<Grid, String> {
    Ok(Head::read(bytes, None, Use::Meshes)?.grid)
}
