//! The progressive mesh's encoding in format version 2: the splits of Zheng 2007 §3.2
//! (Fig. 3.5) with their positions on the object's 16-bit grid and their normals as
//! i8, as the database's full meshes are stored (`scene::mesh_codec`), and every
//! index as a small number a compressor can take: a split's position as steps from
//! v_p's, its adjusted triangles and pivots by their place around v_p, which a reader
//! knows once the splits before it apply (`incidence`). Columns, not records, so that
//! zstd (the layer outside, `lod::stored`) meets like bytes together. Naming places
//! rather than numbers (version 2 of this encoding; no database keeps it): on the
//! first twelve landmarks of the 100,000-object city (smooth meshes, 114,000 triangles
//! on average) that took a progressive mesh in zstd from 10.5 to 5.9 bytes a triangle.
//!
//! It refines to the *quantised* full mesh, the one version 2 draws, in the progressive
//! mesh's own numbering: the maps back to the source's order are not stored (nothing
//! that reads a database needs them), so a decoded mesh's `vertex_map` is the identity
//! and its `triangle_map` lists the filled slots in order.
//!
//! ```text
//! offset  width  field
//! ------  -----  -----------------------------------------------------------------
//!      0      4  magic             b"FLPM"
//!      4      4  version           u32, PM_VERSION_QUANTISED
//!      8      4  base vertices     u32, nv
//!     12      4  base triangles    u32, nt
//!     16      4  splits            u32, s
//!     20     24  grid              f32 × 3 min, f32 × 3 max: the positions' box
//!     44      …  body              varints (LEB128) and bytes, in this order:
//!                  base positions  u16 × nv for x, then y, then z (grid steps)
//!                  base normals    i8 × nv for x, then y, then z (over 127)
//!                  base indices    varint × 3nt
//!                  v_p             varint × s: v_c − 1 − v_p
//!                  v_l, v_r        varint × 2s: 0 when absent; else 1 + the pivot's
//!                                  place among v_p's neighbours (`incidence`), when
//!                                  it is one; else their count + v_c − pivot
//!                  shape           u8 × s: corner of f_l | corner of f_r << 2 |
//!                                  joins_previous << 4
//!                  position        zigzag varint × 3s: v_c's steps − v_p's (the
//!                                  split before's v_c's where it joins it), x y z
//!                  normal          i8 × s for x, then y, then z: v_c's less v_p's,
//!                                  wrapping
//!                  error           f32 × s as four byte planes, low byte first
//!                  adjusted        per split, one bit for each triangle around v_p
//!                                  once the splits before it apply, ascending by
//!                                  slot, set when it moves to v_c: ⌈n / 8⌉ bytes,
//!                                  least significant bit first, the rest clear
//!      …      4  crc32             of every byte before it
//! ```
//!
//! Reading checks the header, the checksum, that the body is read through exactly and
//! every value fits its field, then each split as version 1 does
//! (`checked::check_split`), naming the first failure as an `Error::Invalid`, never a
//! panic, whatever the bytes.

use super::checked::{check_split, PM_MAGIC};
use super::incidence::Incidence;
use super::progressive::ProgressiveMesh;
use super::vsplit::VertexSplit;
use crate::error::{Error, Result};
use crate::scene::mesh_codec::{dequantize_normal, quantize_normal, Grid};
use crate::scene::Mesh;
use crate::store::framing::{self as bytes, f32_at, push_crc, push_varint, u32_at, zigzag, Cursor};

/// The encoding version of a progressive mesh on the 16-bit grid (format version 2).
/// Version 2 named adjusted triangles and pivots by number; no database keeps it.
pub(crate) const PM_VERSION_QUANTISED: u32 = 3;

const NV_OFFSET: usize = 8;
const NT_OFFSET: usize = 12;
const SPLITS_OFFSET: usize = 16;
const GRID_OFFSET: usize = 20;
const BODY_OFFSET: usize = GRID_OFFSET + 24;
const JOINS: u8 = 1 << 4;

fn corrupt(what: String) -> Error {
    Error::Invalid(format!("progressive mesh bytes (quantised): {what}"))
}

impl ProgressiveMesh {
    /// The progressive mesh in format version 2's encoding (layout in this module's
    /// source), for [`from_bytes`](ProgressiveMesh::from_bytes): positions on the
    /// 16-bit grid of the mesh's box, normals as i8, the maps left out. An
    /// `Error::Invalid` when a count does not fit 32 bits or the box spans more than an
    /// f32 holds.
    ///
    /// ```
    /// use flaneur::lod::ProgressiveMesh;
    /// let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
    /// let small = pm.to_quantised_bytes()?;
    /// assert!(small.len() * 2 < pm.to_bytes()?.len());
    /// let back = ProgressiveMesh::from_bytes(&small)?;
    /// assert_eq!(back.splits.len(), pm.splits.len());
    /// # Ok::<(), flaneur::Error>(())
    /// ```
    pub fn to_quantised_bytes(&self) -> Result<Vec<u8>> {
        let (nv, nt, s) = (
            self.base.positions.len(),
            self.base.triangle_count(),
            self.splits.len(),
        );
        if (nv + s) as u64 >= u32::MAX as u64 || (nt + 2 * s) as u64 >= u32::MAX as u64 {
            return Err(Error::Invalid(format!(
                "progressive mesh: {nv} base vertices, {nt} base triangles and {s} splits \
                 do not fit 32 bits"
            )));
        }
        // Every position the mesh ever holds: the full mesh's box.
        let positions = self
            .base
            .positions
            .iter()
            .chain(self.splits.iter().map(|s| &s.position));
        let grid = Grid::around_points(positions.copied());
        if !grid.is_valid() {
            return Err(Error::Invalid(format!(
                "progressive mesh: its box {:?}..{:?} spans more than an f32 holds",
                grid.min, grid.max
            )));
        }
        let mut b = Vec::with_capacity(BODY_OFFSET + 16 * s + 8 * nv + 6 * nt);
        b.extend_from_slice(&PM_MAGIC);
        for v in [PM_VERSION_QUANTISED, nv as u32, nt as u32, s as u32] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for c in grid.min.iter().chain(&grid.max) {
            b.extend_from_slice(&c.to_le_bytes());
        }
        // Every vertex's steps, for the splits' positions relative to v_p's.
        let mut steps: Vec<[u16; 4]> = Vec::with_capacity(nv + s);
        steps.extend(self.base.positions.iter().map(|&p| grid.quantize(p)));
        let base_normals: Vec<[i8; 4]> = self
            .base
            .normals
            .iter()
            .map(|&n| quantize_normal(n))
            .collect();
        for k in 0..3 {
            b.extend(steps.iter().flat_map(|q| q[k].to_le_bytes()));
        }
        for k in 0..3 {
            b.extend(base_normals.iter().map(|n| n[k] as u8));
        }

        for &i in &self.base.indices {
            push_varint(&mut b, i as u64);
        }
        for (i, sp) in self.splits.iter().enumerate() {
            push_varint(&mut b, (nv + i - 1 - sp.v_p as usize) as u64);
        }
        let (pivots, adjusted) = self.by_places()?;
        for code in pivots {
            push_varint(&mut b, code);
        }
        b.extend(self.splits.iter().map(|sp| {
            sp.corners[0] | sp.corners[1] << 2 | if sp.joins_previous { JOINS } else { 0 }
        }));
        for sp in &self.splits {
            // A run's splits share v_c's position: each after the first repeats it.
            let from = match sp.joins_previous {
                true => steps[steps.len() - 1],
                false => steps[sp.v_p as usize],
            };
            let q = grid.quantize(sp.position);
            for k in 0..3 {
                push_varint(&mut b, zigzag(q[k] as i64 - from[k] as i64));
            }
            steps.push(q);
        }
        // A split's normal as the change from v_p's: neighbours on a smooth surface
        // differ by a step or two, which zstd then takes.
        let mut all_normals = base_normals;
        all_normals.extend(self.splits.iter().map(|sp| quantize_normal(sp.normal)));
        let turns: Vec<[u8; 3]> = self
            .splits
            .iter()
            .enumerate()
            .map(|(i, sp)| {
                let (n, from) = (all_normals[nv + i], all_normals[sp.v_p as usize]);
                std::array::from_fn(|k| (n[k] as u8).wrapping_sub(from[k] as u8))
            })
            .collect();
        for k in 0..3 {
            b.extend(turns.iter().map(|t| t[k]));
        }
        for k in 0..4 {
            b.extend(self.splits.iter().map(|sp| sp.error.to_le_bytes()[k]));
        }
        b.extend_from_slice(&adjusted);
        push_crc(&mut b);
        Ok(b)
    }

    /// The pivots' codes (two a split) and the adjusted triangles' bits, worked out
    /// while the splits apply in order. An `Error::Invalid` when a split is illegal
    /// where it stands.
    fn by_places(&self) -> Result<(Vec<u64>, Vec<u8>)> {
        let nv = self.base.positions.len();
        let mut inc = Incidence::new(&self.base, self.splits.len())?;
        let (mut codes, mut bits): (Vec<u64>, Vec<u8>) =
            (Vec::with_capacity(2 * self.splits.len()), Vec::new());
        let mut near = Vec::new();
        let invalid =
            |i: usize, what: String| Error::Invalid(format!("progressive mesh: split {i}: {what}"));
        for (i, sp) in self.splits.iter().enumerate() {
            check_split(sp, i, nv, self.base.triangle_count()).map_err(|w| invalid(i, w))?;
            inc.neighbours(sp.v_p, &mut near);
            for pivot in [sp.v_l, sp.v_r] {
                codes.push(match pivot {
                    None => 0,
                    Some(p) => match near.binary_search(&p) {
                        Ok(k) => 1 + k as u64,
                        Err(_) => (near.len() + nv + i - p as usize) as u64,
                    },
                });
            }
            let around = inc.triangles(sp.v_p);
            let start = bits.len();
            bits.resize(start + around.len().div_ceil(8), 0);
            for (k, t) in around.iter().enumerate() {
                if sp.adjusted.binary_search(t).is_ok() {
                    bits[start + k / 8] |= 1 << (k % 8);
                }
            }
            let marked: u32 = bits[start..].iter().map(|b| b.count_ones()).sum();
            if marked as usize != sp.adjusted.len() {
                return Err(invalid(
                    i,
                    format!(
                        "adjusted triangles {:?} are not all around v_p {}",
                        sp.adjusted, sp.v_p
                    ),
                ));
            }
            inc.apply(i, sp)?;
        }
        Ok((codes, bits))
    }
}

/// Reads the bytes [`ProgressiveMesh::to_quantised_bytes`] writes (magic and version
/// already seen by `from_bytes`).
pub(super) fn decode(b: &[u8]) -> Result<ProgressiveMesh> {
    let body = bytes::checked_body(b, BODY_OFFSET).map_err(corrupt)?;
    let count = |at: usize| u32_at(b, at) as usize;
    let (nv, nt, s) = (count(NV_OFFSET), count(NT_OFFSET), count(SPLITS_OFFSET));
    if (nv + s) as u64 >= u32::MAX as u64 || (nt + 2 * s) as u64 >= u32::MAX as u64 {
        return Err(corrupt(format!(
            "{nv} base vertices, {nt} base triangles and {s} splits pass 32-bit indices"
        )));
    }
    // Each base vertex takes 9 bytes, each base triangle 3 and each split 12 at least:
    // counts that promise more than the body holds are refused before anything is
    // allocated for them.
    let least = 9 * nv as u64 + 3 * nt as u64 + 12 * s as u64;
    bytes::at_least(body.len(), least, "its counts take at least").map_err(corrupt)?;
    let grid = Grid {
        min: std::array::from_fn(|k| f32_at(b, GRID_OFFSET + 4 * k)),
        max: std::array::from_fn(|k| f32_at(b, GRID_OFFSET + 12 + 4 * k)),
    };
    if !grid.is_valid() || (0..3).any(|k| !(grid.min[k] <= grid.max[k])) {
        return Err(corrupt(format!(
            "grid {:?}..{:?} is not a box",
            grid.min, grid.max
        )));
    }
    read_body(&mut Cursor::new(body), &grid, nv, nt, s).map_err(corrupt)
}

/// A progressive mesh's base as its bytes give it: the mesh, and its positions on the
/// grid and normals as stored, which the splits' deltas start from.
type Base = (Mesh, Vec<[u16; 4]>, Vec<[u8; 3]>);

/// The base mesh of `nv` vertices and `nt` triangles from `c`, its positions with room
/// for the `s` splits' to follow.
fn read_base(
    c: &mut Cursor,
    grid: &Grid,
    nv: usize,
    nt: usize,
    s: usize,
) -> std::result::Result<Base, String> {
    let mut steps: Vec<[u16; 4]> = Vec::with_capacity(nv + s);
    let xyz = c.planes::<3>(2 * nv, "base positions")?;
    for v in 0..nv {
        // Plane k holds nv u16s: its bytes are rows 2v and 2v + 1 of the byte planes.
        let at = |k: usize| u16::from_le_bytes([xyz[2 * v][k], xyz[2 * v + 1][k]]);
        steps.push([at(0), at(1), at(2), 0]);
    }
    let stored_normals = c.planes::<3>(nv, "base normals")?;
    let base_normals: Vec<[f32; 3]> = stored_normals
        .iter()
        .map(|&n| dequantize_normal([n[0] as i8, n[1] as i8, n[2] as i8, 0]))
        .collect();
    let mut indices = Vec::with_capacity(3 * nt);
    for _ in 0..3 * nt {
        indices.push(c.u32("base indices")?);
    }
    let base = Mesh {
        positions: steps.iter().map(|&q| grid.dequantize(q)).collect(),
        normals: base_normals,
        indices,
    };
    base.validate().map_err(|w| format!("base mesh: {w}"))?;
    Ok((base, steps, stored_normals))
}

/// The body after the header: the base mesh, then the splits, each checked and applied
/// as it is read, and nothing after them.
fn read_body(
    c: &mut Cursor,
    grid: &Grid,
    nv: usize,
    nt: usize,
    s: usize,
) -> std::result::Result<ProgressiveMesh, String> {
    let (base, mut steps, mut stored_normals) = read_base(c, grid, nv, nt, s)?;
    let normal_of = |n: [u8; 3]| dequantize_normal([n[0] as i8, n[1] as i8, n[2] as i8, 0]);

    let back = |i: usize, d: u64| -> std::result::Result<u32, String> {
        (nv + i)
            .checked_sub(d as usize)
            .map(|v| v as u32)
            .ok_or_else(|| format!("split {i}: it names a vertex {d} before its own"))
    };
    let mut v_p = Vec::with_capacity(s);
    for i in 0..s {
        let d = c.varint(u32::MAX as u64, "v_p")? + 1;
        v_p.push(back(i, d)?);
    }
    let mut pivots = Vec::with_capacity(s);
    for _ in 0..s {
        pivots.push([c.varint(u64::MAX, "pivots")?, c.varint(u64::MAX, "pivots")?]);
    }
    let shapes = c.take(s, "shapes")?;
    if let Some(i) = shapes.iter().position(|&f| f & !(JOINS | 0x0f) != 0) {
        return Err(format!("split {i}: unknown flags {:#04x}", shapes[i]));
    }
    if shapes.first().is_some_and(|&f| f & JOINS != 0) {
        return Err("split 0: the first split joins no split before it".into());
    }
    let mut positions = Vec::with_capacity(s);
    for (i, &p) in v_p.iter().enumerate() {
        let from = match shapes[i] & JOINS != 0 {
            true => steps[steps.len() - 1],
            false => steps[p as usize],
        };
        let mut q = [0u16; 4];
        for k in 0..3 {
            let d = c.i32("positions")?;
            q[k] = u16::try_from(from[k] as i32 + d)
                .map_err(|_| format!("split {i}: its position leaves the grid"))?;
        }
        steps.push(q);
        positions.push(grid.dequantize(q));
    }
    for (i, turn) in c.planes::<3>(s, "normals")?.into_iter().enumerate() {
        let from = stored_normals[v_p[i] as usize];
        stored_normals.push(std::array::from_fn(|k| turn[k].wrapping_add(from[k])));
    }
    let errors = c.planes::<4>(s, "errors")?;
    // The adjusted triangles and pivots name places around v_p: the splits apply as
    // they are read, each checked as `SelectiveMesh::split` checks it.
    let mut inc = Incidence::new(&base, s).map_err(|e| e.to_string())?;
    let mut near = Vec::new();
    let mut splits = Vec::with_capacity(s);
    for i in 0..s {
        inc.neighbours(v_p[i], &mut near);
        let mut pair = [None; 2];
        for (p, &code) in pair.iter_mut().zip(&pivots[i]) {
            *p = match code {
                0 => None,
                k if k <= near.len() as u64 => Some(near[k as usize - 1]),
                k => Some(back(i, k - near.len() as u64)?),
            };
        }
        let around = inc.triangles(v_p[i]);
        let marks = c.take(around.len().div_ceil(8), "adjusted triangles")?;
        if around.len() % 8 != 0 && marks.last().is_some_and(|&b| b >> (around.len() % 8) != 0) {
            return Err(format!(
                "split {i}: adjusted bits past v_p's {} triangles",
                around.len()
            ));
        }
        let adjusted = around
            .iter()
            .enumerate()
            .filter(|(k, _)| marks[k / 8] >> (k % 8) & 1 != 0)
            .map(|(_, &t)| t)
            .collect();
        let shape = shapes[i];
        let [v_l, v_r] = pair;
        let split = VertexSplit {
            v_p: v_p[i],
            position: positions[i],
            normal: normal_of(stored_normals[nv + i]),
            v_l,
            v_r,
            adjusted,
            corners: [shape & 3, shape >> 2 & 3],
            error: f32::from_le_bytes(errors[i]),
            joins_previous: shape & JOINS != 0,
        };
        check_split(&split, i, nv, nt).map_err(|w| format!("split {i}: {w}"))?;
        inc.apply(i, &split).map_err(|e| e.to_string())?;
        splits.push(split);
    }
    if c.left() != 0 {
        return Err(format!("{} trailing bytes after the splits", c.left()));
    }
    let vertex_map = (0..(nv + s) as u32).collect();
    let triangle_map = (0..nt as u32)
        .chain(splits.iter().enumerate().flat_map(|(i, sp)| {
            let f_l = (nt + 2 * i) as u32;
            [sp.v_l.map(|_| f_l), sp.v_r.map(|_| f_l + 1)]
                .into_iter()
                .flatten()
        }))
        .collect();
    Ok(ProgressiveMesh {
        base,
        splits,
        vertex_map,
        triangle_map,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::fixtures::{building, check_full_mesh, grid};
    use crate::store::framing::{mangled, refuses_every_damage, reseal, CRC_LEN};

    /// `mesh` as version 2 draws it: each position on its box's grid, each normal i8.
    fn quantised(mesh: &Mesh) -> Mesh {
        let g = Grid::around([mesh]);
        Mesh {
            positions: mesh
                .positions
                .iter()
                .map(|&p| g.dequantize(g.quantize(p)))
                .collect(),
            normals: mesh
                .normals
                .iter()
                .map(|&n| dequantize_normal(quantize_normal(n)))
                .collect(),
            indices: mesh.indices.clone(),
        }
    }

    #[test]
    fn refines_to_the_quantised_mesh_in_a_fraction_of_the_bytes() {
        for mesh in [crate::scene::bunny(), building(), grid(6)] {
            let pm = ProgressiveMesh::build(&mesh).unwrap();
            let small = pm.to_quantised_bytes().unwrap();
            let back = ProgressiveMesh::from_bytes(&small).unwrap();
            assert_eq!(back.splits.len(), pm.splits.len());
            for (a, b) in back.splits.iter().zip(&pm.splits) {
                assert_eq!(
                    (a.v_p, a.v_l, a.v_r, a.corners),
                    (b.v_p, b.v_l, b.v_r, b.corners)
                );
                assert_eq!(
                    (&a.adjusted, a.joins_previous),
                    (&b.adjusted, b.joins_previous)
                );
                assert_eq!(a.error.to_bits(), b.error.to_bits());
            }
            let full = back.cursor_at(back.splits.len()).unwrap();
            check_full_mesh(&quantised(&mesh), &pm, full.mesh());
            let raw = pm.to_bytes().unwrap();
            assert!(
                2 * small.len() < raw.len(),
                "{} against {}",
                small.len(),
                raw.len()
            );
        }
    }

    #[test]
    fn every_truncation_and_every_flipped_byte_is_an_error() {
        let pm = ProgressiveMesh::build(&building()).unwrap();
        refuses_every_damage(
            &pm.to_quantised_bytes().unwrap(),
            ProgressiveMesh::from_bytes,
        );
    }

    /// Where the columns of `pm`'s quantised bytes start: the varints are measured
    /// by writing them again.
    struct Columns {
        base_indices: usize,
        v_p: usize,
        pivots: usize,
        shapes: usize,
        errors: usize,
        adjusted: usize,
    }

    fn columns(pm: &ProgressiveMesh) -> Columns {
        let (nv, s) = (pm.base.positions.len(), pm.splits.len());
        let (pivots, adjusted) = pm.by_places().unwrap();
        let v_p: Vec<u64> = (pm.splits.iter().enumerate())
            .map(|(i, sp)| (nv + i - 1 - sp.v_p as usize) as u64)
            .collect();
        let base_indices = BODY_OFFSET + 9 * nv;
        let at_v_p = base_indices + varints_len(pm.base.indices.iter().map(|&i| i as u64));
        let at_pivots = at_v_p + varints_len(v_p);
        let total = pm.to_quantised_bytes().unwrap().len();
        let at_adjusted = total - CRC_LEN - adjusted.len();
        Columns {
            base_indices,
            v_p: at_v_p,
            pivots: at_pivots,
            shapes: at_pivots + varints_len(pivots),
            errors: at_adjusted - 4 * s,
            adjusted: at_adjusted,
        }
    }

    /// `b` with the varint at `at` replaced by `v`, resealed.
    fn with_varint(b: &[u8], at: usize, v: u64) -> Vec<u8> {
        let mut end = at;
        crate::store::framing::read_varint(b, &mut end).unwrap();
        let mut out = b[..at].to_vec();
        push_varint(&mut out, v);
        out.extend_from_slice(&b[end..]);
        reseal(&mut out);
        out
    }

    #[test]
    fn resealed_bad_content_is_named() {
        // The writer refuses an illegal split; these bytes are damaged by hand past it,
        // each column where it lies, and resealed.
        let pm = ProgressiveMesh::build(&building()).unwrap();
        let good = pm.to_quantised_bytes().unwrap();
        let col = columns(&pm);
        let named = |b: &[u8]| ProgressiveMesh::from_bytes(b).unwrap_err().to_string();
        let patched = |at: usize, edit: &dyn Fn(&mut u8)| {
            let mut b = good.clone();
            edit(&mut b[at]);
            reseal(&mut b);
            named(&b)
        };
        let nv = pm.base.positions.len();
        let s = pm.splits.len();
        assert!(named(&with_varint(&good, col.base_indices, 1 << 30)).contains("base mesh"));
        // Split 3's v_l past v_p's neighbours, counted back from v_c to v_p itself.
        let mut inc = Incidence::new(&pm.base, s).unwrap();
        for (i, sp) in pm.splits.iter().take(3).enumerate() {
            inc.apply(i, sp).unwrap();
        }
        let mut near = Vec::new();
        inc.neighbours(pm.splits[3].v_p, &mut near);
        let mut at = col.pivots;
        for _ in 0..6 {
            crate::store::framing::read_varint(&good, &mut at).unwrap();
        }
        let to_v_p = (near.len() + nv + 3 - pm.splits[3].v_p as usize) as u64;
        let err = named(&with_varint(&good, at, to_v_p));
        assert!(err.contains("pivot"), "{err}");
        assert!(patched(col.shapes + 3, &|b| *b |= 3 << 2).contains("corners"));
        assert!(patched(col.shapes, &|b| *b |= JOINS).contains("first split"));
        // The high byte plane of split 3's error: sign and exponent all ones.
        assert!(patched(col.errors + 3 * s + 3, &|b| *b = 0xff).contains("not finite"));
        let err = patched(col.adjusted, &|b| *b = 0xff);
        assert!(
            err.contains("adjusted") || err.contains("triangle"),
            "{err}"
        );
        // A split naming a vertex before every vertex.
        let err = named(&with_varint(&good, col.v_p, 0x7f_ffff));
        assert!(
            err.contains("before its own") || err.contains("v_p"),
            "{err}"
        );
    }

    #[test]
    fn an_illegal_split_is_refused_when_written() {
        let pm = ProgressiveMesh::build(&building()).unwrap();
        let refused = |edit: &dyn Fn(&mut ProgressiveMesh)| {
            let mut pm = pm.clone();
            edit(&mut pm);
            pm.to_quantised_bytes().unwrap_err().to_string()
        };
        assert!(refused(&|p| p.base.indices[0] = 1 << 30).contains("base"));
        assert!(refused(&|p| p.splits[3].v_l = Some(p.splits[3].v_p)).contains("pivot"));
        assert!(refused(&|p| p.splits[3].corners[1] = 3).contains("corners"));
        assert!(refused(&|p| p.splits[0].joins_previous = true).contains("first split"));
        assert!(refused(&|p| p.splits[3].error = f32::NAN).contains("not finite"));
        let adj = pm
            .splits
            .iter()
            .position(|s| !s.adjusted.is_empty())
            .unwrap();
        let slots = pm.base.triangle_count() as u32 + 2 * adj as u32;
        let err = refused(&|p| p.splits[adj].adjusted = vec![slots]);
        assert!(err.contains("ascending below"), "{err}");
        // A triangle that exists but has no corner v_p.
        let elsewhere = (0..pm.base.triangle_count() as u32)
            .find(|t| !pm.base.indices[3 * *t as usize..][..3].contains(&pm.splits[0].v_p))
            .unwrap();
        let err = refused(&|p| p.splits[0].adjusted = vec![elsewhere]);
        assert!(err.contains("around v_p"), "{err}");
    }

    fn varints_len(v: impl IntoIterator<Item = u64>) -> usize {
        let mut b = Vec::new();
        for x in v {
            push_varint(&mut b, x);
        }
        b.len()
    }

    #[test]
    fn random_bytes_never_panic() {
        let good = ProgressiveMesh::build(&grid(4))
            .unwrap()
            .to_quantised_bytes()
            .unwrap();
        let restore = |b: &mut [u8]| {
            b[..4].copy_from_slice(&PM_MAGIC);
            b[4..8].copy_from_slice(&PM_VERSION_QUANTISED.to_le_bytes());
            reseal(b);
        };
        mangled(12, 3000, 300, &good, restore, |b| {
            if let Ok(pm) = ProgressiveMesh::from_bytes(b) {
                if let Ok(mut cursor) = pm.cursor() {
                    while let Ok(true) = cursor.refine() {}
                }
            }
        });
    }
}
