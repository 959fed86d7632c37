//! The progressive mesh as flat bytes, for an extent of the database: the base mesh, the
//! vertex splits in the implicit-index form of Zheng 2007 §3.2 (Fig. 3.5: v_c, f_l and
//! f_r are not stored, a split's place gives them; a missing pivot is written −1, that
//! is `u32::MAX`) and the renumbering maps. Little-endian, versioned, checksummed.
//! Positions, normals and errors are stored as full f32, so that the decoded mesh is
//! the encoded one bit for bit and refines back to the original exactly.
//!
//! ```text
//! offset              width  field
//! ------------------  -----  ---------------------------------------------------------
//!                  0      4  magic             b"FLPM"
//!                  4      4  version           u32, PM_VERSION
//!                  8      4  base vertices     u32, nv
//!                 12      4  base triangles    u32, nt
//!                 16      4  splits            u32, s
//!                 20      4  adjusted          u32, a: adjusted triangles, all splits
//!                 24      4  vertex map        u32, v = nv + s (the original's vertices)
//!                 28      4  triangle map      u32, t (the original's triangles)
//!                 32   12nv  base positions    f32 × 3
//!                         …  base normals      f32 × 3 per base vertex (12nv)
//!                         …  base indices      u32 × 3 per base triangle (12nt)
//!                         …  splits            48 bytes each:
//!                              +0   4  v_p         u32
//!                              +4  12  position    f32 × 3 (v_c's)
//!                              +16 12  normal      f32 × 3
//!                              +28  4  v_l         u32, u32::MAX when absent
//!                              +32  4  v_r         u32, u32::MAX when absent
//!                              +36  2  corners     u8 × 2 (of f_l, of f_r)
//!                              +38  1  flags       bit 0: joins_previous
//!                              +39  1  reserved    zero
//!                              +40  4  error       f32, metres
//!                              +44  4  adjusted    u32: this split's adjusted
//!                                                  triangles end here in the list
//!                         …  adjusted list     u32 × a
//!                         …  vertex map        u32 × v
//!                         …  triangle map      u32 × t
//!                         …  crc32             of every byte before it
//! ```
//!
//! Reading checks, in order, and names the first failure: length against the fixed
//! header, magic, version, length against the counts, checksum, then the content — the
//! base mesh valid; every split names only vertices and triangle slots that exist before
//! it, its adjusted triangles ascending, corners below 3, a finite error, no run
//! starting at split 0; the vertex map a permutation of the vertices; the triangle map
//! one-to-one onto the triangle slots that are filled when every split is applied. Bytes
//! that pass are a progressive mesh that `PmCursor` and `SelectiveMesh` walk without an
//! index check failing (those check every operator anyway; this names the damage early).

use super::checked::{check_split, PM_MAGIC};
use super::progressive::ProgressiveMesh;
use super::vsplit::VertexSplit;
use crate::error::{Error, Result};
use crate::scene::Mesh;
use crate::store::framing::{self as bytes, f32_at, push_crc, u32_at, CRC_LEN};

/// The encoding version this build writes and reads.
pub const PM_VERSION: u32 = 1;

const MAGIC_OFFSET: usize = 0;
const VERSION_OFFSET: usize = MAGIC_OFFSET + PM_MAGIC.len();
const BASE_VERTICES_OFFSET: usize = VERSION_OFFSET + 4;
const BASE_TRIANGLES_OFFSET: usize = BASE_VERTICES_OFFSET + 4;
const SPLITS_OFFSET: usize = BASE_TRIANGLES_OFFSET + 4;
const ADJUSTED_OFFSET: usize = SPLITS_OFFSET + 4;
const VERTEX_MAP_OFFSET: usize = ADJUSTED_OFFSET + 4;
const TRIANGLE_MAP_OFFSET: usize = VERTEX_MAP_OFFSET + 4;
const HEADER_LEN: usize = TRIANGLE_MAP_OFFSET + 4;

const SPLIT_V_P: usize = 0;
const SPLIT_POSITION: usize = SPLIT_V_P + 4;
const SPLIT_NORMAL: usize = SPLIT_POSITION + 12;
const SPLIT_V_L: usize = SPLIT_NORMAL + 12;
const SPLIT_V_R: usize = SPLIT_V_L + 4;
const SPLIT_CORNERS: usize = SPLIT_V_R + 4;
const SPLIT_FLAGS: usize = SPLIT_CORNERS + 2;
const SPLIT_RESERVED: usize = SPLIT_FLAGS + 1;
const SPLIT_ERROR: usize = SPLIT_RESERVED + 1;
const SPLIT_ADJUSTED_END: usize = SPLIT_ERROR + 4;
const SPLIT_LEN: usize = SPLIT_ADJUSTED_END + 4;
const FLAG_JOINS_PREVIOUS: u8 = 1;
const NO_PIVOT: u32 = u32::MAX;

/// Where the variable sections begin (u64: counts read from damaged bytes must not
/// overflow before the length check rejects them).
struct Sections {
    positions: u64,
    normals: u64,
    indices: u64,
    splits: u64,
    adjusted: u64,
    vertex_map: u64,
    triangle_map: u64,
    crc: u64,
    total: u64,
}

impl Sections {
    fn new(nv: u64, nt: u64, s: u64, a: u64, v: u64, t: u64) -> Sections {
        let positions = HEADER_LEN as u64;
        let normals = positions + 12 * nv;
        let indices = normals + 12 * nv;
        let splits = indices + 12 * nt;
        let adjusted = splits + SPLIT_LEN as u64 * s;
        let vertex_map = adjusted + 4 * a;
        let triangle_map = vertex_map + 4 * v;
        let crc = triangle_map + 4 * t;
        Sections {
            positions,
            normals,
            indices,
            splits,
            adjusted,
            vertex_map,
            triangle_map,
            crc,
            total: crc + CRC_LEN as u64,
        }
    }

    fn of(pm: &ProgressiveMesh) -> Sections {
        Sections::new(
            pm.base.positions.len() as u64,
            pm.base.triangle_count() as u64,
            pm.splits.len() as u64,
            pm.splits.iter().map(|s| s.adjusted.len() as u64).sum(),
            pm.vertex_map.len() as u64,
            pm.triangle_map.len() as u64,
        )
    }
}

fn corrupt(what: String) -> Error {
    Error::Invalid(format!("progressive mesh bytes: {what}"))
}

fn vec3_at(b: &[u8], at: usize) -> [f32; 3] {
    [f32_at(b, at), f32_at(b, at + 4), f32_at(b, at + 8)]
}

fn put_vec3(b: &mut Vec<u8>, v: &[f32; 3]) {
    for c in v {
        b.extend_from_slice(&c.to_le_bytes());
    }
}

impl ProgressiveMesh {
    /// The number of bytes [`to_bytes`](ProgressiveMesh::to_bytes) writes.
    pub fn encoded_len(&self) -> usize {
        Sections::of(self).total as usize
    }

    /// The progressive mesh as little-endian bytes (layout in this module's source),
    /// for [`from_bytes`](ProgressiveMesh::from_bytes). An `Error::Invalid` when a
    /// count does not fit the format's 32 bits.
    ///
    /// ```
    /// use flaneur::lod::ProgressiveMesh;
    /// let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
    /// let bytes = pm.to_bytes()?;
    /// assert_eq!(ProgressiveMesh::from_bytes(&bytes)?, pm);
    /// # Ok::<(), flaneur::Error>(())
    /// ```
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
        let sec = Sections::of(self);
        let adjusted: u64 = self.splits.iter().map(|s| s.adjusted.len() as u64).sum();
        let counts = [
            self.base.positions.len() as u64,
            self.base.triangle_count() as u64,
            self.splits.len() as u64,
            adjusted,
            self.vertex_map.len() as u64,
            self.triangle_map.len() as u64,
        ];
        if counts.iter().any(|&c| c >= u32::MAX as u64) {
            return Err(Error::Invalid(format!(
                "progressive mesh: counts {counts:?} do not fit 32 bits"
            )));
        }
        let mut b = Vec::with_capacity(sec.total as usize);
        b.extend_from_slice(&PM_MAGIC);
        b.extend_from_slice(&PM_VERSION.to_le_bytes());
        for c in counts {
            b.extend_from_slice(&(c as u32).to_le_bytes());
        }
        for p in &self.base.positions {
            put_vec3(&mut b, p);
        }
        for n in &self.base.normals {
            put_vec3(&mut b, n);
        }
        for i in &self.base.indices {
            b.extend_from_slice(&i.to_le_bytes());
        }
        let mut adjusted_end = 0u32;
        for s in &self.splits {
            adjusted_end += s.adjusted.len() as u32;
            b.extend_from_slice(&s.v_p.to_le_bytes());
            put_vec3(&mut b, &s.position);
            put_vec3(&mut b, &s.normal);
            b.extend_from_slice(&s.v_l.unwrap_or(NO_PIVOT).to_le_bytes());
            b.extend_from_slice(&s.v_r.unwrap_or(NO_PIVOT).to_le_bytes());
            b.extend_from_slice(&s.corners);
            b.push(if s.joins_previous {
                FLAG_JOINS_PREVIOUS
            } else {
                0
            });
            b.push(0);
            b.extend_from_slice(&s.error.to_le_bytes());
            b.extend_from_slice(&adjusted_end.to_le_bytes());
        }
        for v in self
            .splits
            .iter()
            .flat_map(|s| &s.adjusted)
            .chain(&self.vertex_map)
            .chain(&self.triangle_map)
        {
            b.extend_from_slice(&v.to_le_bytes());
        }
        push_crc(&mut b);
        debug_assert_eq!(b.len() as u64, sec.total);
        Ok(b)
    }

    /// Reads a progressive mesh written by [`to_bytes`](ProgressiveMesh::to_bytes) or
    /// [`to_quantised_bytes`](ProgressiveMesh::to_quantised_bytes). An
    /// `Error::Invalid` that says what is wrong — too short, not a progressive mesh,
    /// another version, a checksum mismatch, or content no progressive mesh can have —
    /// never a panic, whatever the bytes.
    pub fn from_bytes(b: &[u8]) -> Result<ProgressiveMesh> {
        if b.len() >= 8 && b[..4] == PM_MAGIC && u32_at(b, 4) == super::PM_VERSION_QUANTISED {
            return super::compact::decode(b);
        }
        bytes::header(b, HEADER_LEN, "a progressive mesh", PM_MAGIC, PM_VERSION)
            .map_err(corrupt)?;
        let count = |at: usize| u32_at(b, at) as usize;
        let (nv, nt, s, a, v, t) = (
            count(BASE_VERTICES_OFFSET),
            count(BASE_TRIANGLES_OFFSET),
            count(SPLITS_OFFSET),
            count(ADJUSTED_OFFSET),
            count(VERTEX_MAP_OFFSET),
            count(TRIANGLE_MAP_OFFSET),
        );
        let sec = Sections::new(nv as u64, nt as u64, s as u64, a as u64, v as u64, t as u64);
        bytes::exactly(b.len(), sec.total, "its counts take").map_err(corrupt)?;
        bytes::checksum(b, sec.crc as usize).map_err(corrupt)?;
        // Slots run to nv + s vertices and nt + 2s triangles: both must fit 32 bits.
        if (nv + s) as u64 >= u32::MAX as u64 || (nt + 2 * s) as u64 >= u32::MAX as u64 {
            return Err(corrupt(format!(
                "{nv} base vertices, {nt} base triangles and {s} splits pass 32-bit indices"
            )));
        }

        let base = Mesh {
            positions: (0..nv)
                .map(|i| vec3_at(b, at(sec.positions, i, 12)))
                .collect(),
            normals: (0..nv)
                .map(|i| vec3_at(b, at(sec.normals, i, 12)))
                .collect(),
            indices: (0..3 * nt)
                .map(|i| u32_at(b, at(sec.indices, i, 4)))
                .collect(),
        };
        base.validate()
            .map_err(|w| corrupt(format!("base mesh: {w}")))?;

        let (splits, filled) = read_splits(b, &sec, (nv, nt, s, a))?;
        let vertex_map = read_vertex_map(b, &sec, v, nv + s)?;
        let triangle_map = read_triangle_map(b, &sec, t, filled, nt, &splits)?;
        Ok(ProgressiveMesh {
            base,
            splits,
            vertex_map,
            triangle_map,
        })
    }
}

/// Where item `i` of `width` bytes lies in the section starting at `section`.
fn at(section: u64, i: usize, width: usize) -> usize {
    section as usize + i * width
}

/// The vertex splits, each checked against the base mesh of `nv` vertices and `nt`
/// triangles, their `a` adjusted triangles run through in order; returns them and the
/// triangle slots they fill with the base's.
fn read_splits(
    b: &[u8],
    sec: &Sections,
    (nv, nt, s, a): (usize, usize, usize, usize),
) -> Result<(Vec<VertexSplit>, usize)> {
    let mut splits = Vec::with_capacity(s);
    let mut adjusted_start = 0usize;
    let mut filled = nt; // triangle slots filled with every split applied
    for i in 0..s {
        let o = at(sec.splits, i, SPLIT_LEN);
        let bad = |what: String| corrupt(format!("split {i}: {what}"));
        let pivot = |at: usize| match u32_at(b, o + at) {
            NO_PIVOT => None,
            p => Some(p),
        };
        let flags = b[o + SPLIT_FLAGS];
        if flags & !FLAG_JOINS_PREVIOUS != 0 || b[o + SPLIT_RESERVED] != 0 {
            return Err(bad(format!("unknown flags {flags:#04x}")));
        }
        let adjusted_end = u32_at(b, o + SPLIT_ADJUSTED_END) as usize;
        if adjusted_end < adjusted_start || adjusted_end > a {
            return Err(bad(format!(
                "its adjusted triangles end at {adjusted_end} (after {adjusted_start}, \
                 at most {a})"
            )));
        }
        let split = VertexSplit {
            v_p: u32_at(b, o + SPLIT_V_P),
            position: vec3_at(b, o + SPLIT_POSITION),
            normal: vec3_at(b, o + SPLIT_NORMAL),
            v_l: pivot(SPLIT_V_L),
            v_r: pivot(SPLIT_V_R),
            adjusted: (adjusted_start..adjusted_end)
                .map(|k| u32_at(b, at(sec.adjusted, k, 4)))
                .collect(),
            corners: [b[o + SPLIT_CORNERS], b[o + SPLIT_CORNERS + 1]],
            error: f32_at(b, o + SPLIT_ERROR),
            joins_previous: flags & FLAG_JOINS_PREVIOUS != 0,
        };
        check_split(&split, i, nv, nt).map_err(bad)?;
        adjusted_start = adjusted_end;
        filled += split.added_triangles();
        splits.push(split);
    }
    if adjusted_start != a {
        return Err(corrupt(format!(
            "the splits' adjusted triangles end at {adjusted_start}, the header says {a}"
        )));
    }
    Ok((splits, filled))
}

/// The vertex map of `v` entries, which must be `expected` (the base's vertices and the
/// splits'), each original vertex to a slot of its own.
fn read_vertex_map(b: &[u8], sec: &Sections, v: usize, expected: usize) -> Result<Vec<u32>> {
    if v != expected {
        return Err(corrupt(format!(
            "the vertex map has {v} entries, the base and splits make {expected}"
        )));
    }
    let vertex_map: Vec<u32> = (0..v)
        .map(|i| u32_at(b, at(sec.vertex_map, i, 4)))
        .collect();
    let mut seen = vec![false; v];
    for (i, &n) in vertex_map.iter().enumerate() {
        match seen.get_mut(n as usize) {
            Some(s) if !*s => *s = true,
            _ => {
                return Err(corrupt(format!(
                    "vertex map: original vertex {i} maps to {n}, out of range or taken"
                )))
            }
        }
    }
    Ok(vertex_map)
}

/// The triangle map of `t` entries, which must be the `filled` slots, each original
/// triangle to a slot the base or a split fills, and no slot twice.
fn read_triangle_map(
    b: &[u8],
    sec: &Sections,
    t: usize,
    filled: usize,
    nt: usize,
    splits: &[VertexSplit],
) -> Result<Vec<u32>> {
    let s = splits.len();
    if t != filled {
        return Err(corrupt(format!(
            "the triangle map has {t} entries, the base and splits fill {filled} slots"
        )));
    }
    let triangle_map: Vec<u32> = (0..t)
        .map(|i| u32_at(b, at(sec.triangle_map, i, 4)))
        .collect();
    let mut seen = vec![false; nt + 2 * s];
    for (i, &slot) in triangle_map.iter().enumerate() {
        let slot = slot as usize;
        let exists = slot < nt || {
            let k = slot.wrapping_sub(nt);
            splits.get(k / 2).is_some_and(|sp: &VertexSplit| {
                if k % 2 == 0 {
                    sp.v_l.is_some()
                } else {
                    sp.v_r.is_some()
                }
            })
        };
        if !exists || std::mem::replace(&mut seen[slot], true) {
            return Err(corrupt(format!(
                "triangle map: original triangle {i} maps to slot {slot}, which is \
                 never filled or taken"
            )));
        }
    }
    Ok(triangle_map)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::fixtures::{building, check_exact, grid};
    use crate::store::framing::{mangled, reseal};

    #[test]
    fn round_trips_and_refines_back_exactly() {
        for mesh in [crate::scene::bunny(), building(), grid(6)] {
            let pm = ProgressiveMesh::build(&mesh).unwrap();
            let bytes = pm.to_bytes().unwrap();
            assert_eq!(bytes.len(), pm.encoded_len());
            assert_eq!(&bytes[..4], b"FLPM");
            let back = ProgressiveMesh::from_bytes(&bytes).unwrap();
            assert_eq!(back, pm);
            check_exact(&mesh, &back);
            let full = back.cursor_at(back.splits.len()).unwrap().to_mesh();
            assert_eq!(full.triangle_count(), mesh.triangle_count());
        }
    }

    #[test]
    fn every_truncation_and_every_flipped_byte_is_an_error() {
        let bytes = ProgressiveMesh::build(&building())
            .unwrap()
            .to_bytes()
            .unwrap();
        for len in 0..bytes.len() {
            let e = ProgressiveMesh::from_bytes(&bytes[..len])
                .unwrap_err()
                .to_string();
            assert!(e.contains("truncated"), "{len}: {e}");
        }
        for at in 0..bytes.len() {
            let mut b = bytes.clone();
            b[at] ^= 0x5a;
            assert!(ProgressiveMesh::from_bytes(&b).is_err(), "byte {at}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(ProgressiveMesh::from_bytes(&longer)
            .unwrap_err()
            .to_string()
            .contains("trailing"));
    }

    #[test]
    fn resealed_bad_content_is_named() {
        // Content faults with a valid checksum: what a buggy writer could produce.
        let pm = ProgressiveMesh::build(&building()).unwrap();
        let bytes = pm.to_bytes().unwrap();
        let sec = Sections::of(&pm);
        let nv = pm.base.positions.len() as u32;
        let split_at = |i: usize| sec.splits as usize + i * SPLIT_LEN;
        let (s0, s3) = (split_at(0), split_at(3));
        let adj_split = pm
            .splits
            .iter()
            .position(|s| !s.adjusted.is_empty())
            .unwrap();
        let u32s: Vec<(usize, u32, &str)> = vec![
            (sec.indices as usize, 1 << 30, "base mesh"),
            (s3 + SPLIT_V_P, nv + 3, "v_p"),
            (s3 + SPLIT_V_L, nv + 3, "pivot"),
            (s3 + SPLIT_ERROR, f32::NAN.to_bits(), "not finite"),
            (s3 + SPLIT_POSITION, f32::INFINITY.to_bits(), "not finite"),
            (s0 + SPLIT_ADJUSTED_END, u32::MAX, "end at"),
            (sec.vertex_map as usize, pm.vertex_map[1], "vertex map"),
            (sec.vertex_map as usize, u32::MAX - 1, "vertex map"),
            (
                sec.triangle_map as usize,
                pm.triangle_map[1],
                "triangle map",
            ),
            (sec.triangle_map as usize, u32::MAX - 1, "triangle map"),
        ];
        for (at, v, expect) in u32s {
            let mut b = bytes.clone();
            b[at..at + 4].copy_from_slice(&v.to_le_bytes());
            reseal(&mut b);
            let err = ProgressiveMesh::from_bytes(&b).unwrap_err().to_string();
            assert!(err.contains(expect), "at {at}: {err}");
        }
        let bytes_at = |at: usize, v: u8| {
            let mut b = bytes.clone();
            b[at] = v;
            reseal(&mut b);
            ProgressiveMesh::from_bytes(&b).unwrap_err().to_string()
        };
        assert!(bytes_at(s3 + SPLIT_CORNERS, 3).contains("corners"));
        assert!(bytes_at(s3 + SPLIT_FLAGS, 2).contains("flags"));
        assert!(bytes_at(s0 + SPLIT_FLAGS, 1).contains("first split"));
        // An adjusted triangle made by the split itself, or later.
        let first_adjusted = sec.adjusted as usize
            + 4 * pm.splits[..adj_split]
                .iter()
                .map(|s| s.adjusted.len())
                .sum::<usize>();
        let slots = (pm.base.triangle_count() + 2 * adj_split) as u32;
        let mut b = bytes.clone();
        b[first_adjusted..first_adjusted + 4].copy_from_slice(&slots.to_le_bytes());
        reseal(&mut b);
        let err = ProgressiveMesh::from_bytes(&b).unwrap_err().to_string();
        assert!(err.contains("ascending below"), "{err}");
    }

    #[test]
    fn random_bytes_never_panic() {
        let good = ProgressiveMesh::build(&grid(4))
            .unwrap()
            .to_bytes()
            .unwrap();
        let restore = |b: &mut [u8]| {
            b[..4].copy_from_slice(&PM_MAGIC);
            b[4..8].copy_from_slice(&PM_VERSION.to_le_bytes());
            reseal(b);
        };
        mangled(11, 3000, 300, &good, restore, |b| {
            if let Ok(pm) = ProgressiveMesh::from_bytes(b) {
                // Whatever passes the checks can be walked without a panic.
                if let Ok(mut cursor) = pm.cursor() {
                    while let Ok(true) = cursor.refine() {}
                }
            }
        });
    }
}
