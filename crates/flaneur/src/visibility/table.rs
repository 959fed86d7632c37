//! The visibility table's bytes: the viewcell grid, how the visibility was computed,
//! a directory of the walkable cells, and each cell's potentially visible set with the
//! degree of visibility of every object in it. One extent of `visibility` pages, named
//! by the header's `viewcells` segment (a = first page, b = byte length, c = pages).
//!
//! ```text
//! head:
//! offset  width  field
//! ------  -----  ------------------------------------------------------------
//!      0      4  magic            b"FLVS"
//!      4      4  version          u32, TABLE_VERSION
//!      8      4  cells            u32, n: walkable cells, each with a record
//!     12      4  rows             u32
//!     16      4  columns          u32
//!     20     12  origin           f32 × 3: the grid's lower corner (x, ground, z)
//!     32      4  cell size        f32, metres
//!     36      8  eye range        f32 × 2, metres above the ground
//!     44      4  resolution       u32, N: pixels per cube-face side for the DoV
//!     48      4  DoV_s            f32, the DoV given to visible zero-DoV objects
//!     52      4  sample spacing   f32, metres: the conservative test's widest patch
//!     56      4  occluder radius  f32, metres
//!     60      4  horizon bins     u32
//!     64      4  reserved         u32, 0
//!     68      8  seconds          f64, the precomputation's wall-clock time
//!     76      8  rays             u64, rays cast for the DoV
//!     84      8  entries          u64, objects over all PVSs
//!     92      8  objects          u64, objects in the scene it was computed for
//!    100      8  DoV seconds      f64, the part of `seconds` spent casting DoV rays
//!    108    20n  directory        per cell, ids ascending: id u32, offset u64 (of its
//!                                 record, from the table's start), length u32, count u32
//! 108+20n     4  crc32            of the head's bytes before it
//!
//! record (one per cell):
//!      0      -  object ids       ascending, LEB128: the first id, then differences
//!      -     2c  DoVs             u16 each, DoV × 65535 rounded, at least 1
//!      -      4  crc32            of the record's bytes before it
//! ```
//!
//! DoVs are kept as u16: a step of 1/65535 of the sphere is far below what the cube
//! faces resolve (a 256² face pixel is 1/400,000 of it at best, but a DoV is summed over
//! many), and every object in a PVS keeps a non-zero DoV.

use crate::error::{Error, Result};
use crate::store::framing::{
    self as bytes, f32_at, push_crc, push_varint, read_varint, u32_at, u64_at, CRC_LEN,
};

use super::cells::ViewcellGrid;
use super::conservative::SampleOptions;
use glam::Vec3;

/// The header segment that names the visibility table.
pub const VISIBILITY_SEGMENT: &str = "viewcells";
/// The first four bytes of the table.
pub const TABLE_MAGIC: [u8; 4] = *b"FLVS";
/// The table version this build writes and reads.
pub const TABLE_VERSION: u32 = 3;
/// Bytes of the head before the directory.
pub const HEAD_FIXED: usize = 108;
const DIR_ENTRY: usize = 20;

/// How the visibility was computed, and what it cost.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct VisibilitySettings {
    /// Pixels per side of a cube face (N).
    pub resolution: u32,
    /// The DoV given to objects in a PVS that no sample ray met.
    pub dov_s: f32,
    /// How the conservative test sampled each cell.
    #[serde(skip)]
    pub samples: SampleOptions,
    /// Angular bins of the occlusion horizons.
    pub bins: u32,
}

/// What the precomputation measured, stored with it.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct VisibilityStats {
    /// Wall-clock seconds of the whole precomputation.
    pub seconds: f64,
    /// Of those, the seconds spent casting the DoV's rays.
    pub dov_seconds: f64,
    /// Rays cast for the DoV.
    pub rays: u64,
    /// Objects over all PVSs.
    pub entries: u64,
    /// Objects in the scene it was computed for.
    pub objects: u64,
}

/// Where one cell's record lies in the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CellEntry {
    /// The cell's id.
    pub id: u32,
    /// Where its record starts, in bytes from the table's start.
    pub offset: u64,
    /// The record's length in bytes.
    pub len: u32,
    /// Objects in its PVS.
    pub count: u32,
}

/// The head of a table: everything but the records.
#[derive(Clone, Debug, PartialEq)]
pub struct TableHead {
    /// The viewcell grid.
    pub grid: ViewcellGrid,
    /// How the visibility was computed.
    pub settings: VisibilitySettings,
    /// What the computation measured.
    pub stats: VisibilityStats,
    /// Walkable cells, ids ascending.
    pub cells: Vec<CellEntry>,
}

impl TableHead {
    /// The head's length in bytes for `cells` cells.
    pub fn len_for(cells: usize) -> usize {
        HEAD_FIXED + DIR_ENTRY * cells + CRC_LEN
    }

    /// The directory entry of cell `id`, if it is walkable.
    pub fn cell(&self, id: u32) -> Option<&CellEntry> {
        self.cells
            .binary_search_by_key(&id, |c| c.id)
            .ok()
            .map(|i| &self.cells[i])
    }
}

/// One cell's PVS: object ids ascending, and the DoV of each.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CellPvs {
    /// Object ids, ascending.
    pub ids: Vec<u64>,
    /// The DoV of each object, in the order of `ids`.
    pub dov: Vec<f32>,
}

fn corrupt(what: impl std::fmt::Display) -> Error {
    Error::Invalid(format!("visibility table: {what}"))
}

/// A cell's record. The ids must ascend and pair with DoVs in (0, 1].
pub fn encode_record(pvs: &CellPvs) -> Result<Vec<u8>> {
    if pvs.ids.len() != pvs.dov.len() {
        return Err(Error::Invalid(format!(
            "a PVS of {} ids has {} DoVs",
            pvs.ids.len(),
            pvs.dov.len()
        )));
    }
    let mut b = Vec::with_capacity(pvs.ids.len() * 4 + CRC_LEN);
    let mut last = None;
    for &id in &pvs.ids {
        let delta = match last {
            None => id,
            Some(l) if id > l => id - l,
            Some(l) => {
                return Err(Error::Invalid(format!(
                    "PVS ids must ascend: {id} follows {l}"
                )))
            }
        };
        push_varint(&mut b, delta);
        last = Some(id);
    }
    for &d in &pvs.dov {
        if !(d > 0.0 && d <= 1.0) {
            return Err(Error::Invalid(format!("a DoV of {d} is not in (0, 1]")));
        }
        let q = (d * 65535.0).round().clamp(1.0, 65535.0) as u16;
        b.extend_from_slice(&q.to_le_bytes());
    }
    push_crc(&mut b);
    Ok(b)
}

/// Decodes a record of `count` objects.
pub fn decode_record(b: &[u8], count: u32) -> Result<CellPvs> {
    let count = count as usize;
    if b.len() < CRC_LEN + 3 * count {
        return Err(corrupt(format!(
            "a record of {count} objects takes at least {} bytes, it has {}",
            CRC_LEN + 3 * count,
            b.len()
        )));
    }
    bytes::checksum(b, b.len() - CRC_LEN).map_err(|w| corrupt(format!("record {w}")))?;
    let body = &b[..b.len() - CRC_LEN];
    let mut at = 0;
    let mut ids: Vec<u64> = Vec::with_capacity(count);
    for k in 0..count {
        let d = read_varint(body, &mut at)
            .ok_or_else(|| corrupt(format!("object {k} of {count}: bad id")))?;
        let id = match ids.last() {
            None => d,
            Some(&l) if d > 0 => l.checked_add(d).ok_or_else(|| {
                corrupt(format!("object {k}: id {l} + {d} is past the largest id"))
            })?,
            Some(_) => return Err(corrupt(format!("object {k}: ids do not ascend"))),
        };
        ids.push(id);
    }
    if body.len() - at != 2 * count {
        return Err(corrupt(format!(
            "{count} DoVs take {} bytes, the record has {} left",
            2 * count,
            body.len() - at
        )));
    }
    let dov = body[at..]
        .chunks_exact(2)
        .map(|q| u16::from_le_bytes([q[0], q[1]]) as f32 / 65535.0)
        .collect::<Vec<f32>>();
    if let Some(k) = dov.iter().position(|&d| d == 0.0) {
        return Err(corrupt(format!("object {} has a DoV of 0", ids[k])));
    }
    Ok(CellPvs { ids, dov })
}

/// The whole table: the head, then the records in id order.
pub fn encode_table(
    grid: &ViewcellGrid,
    settings: &VisibilitySettings,
    stats: &VisibilityStats,
    cells: &[(u32, CellPvs)],
) -> Result<Vec<u8>> {
    let head_len = TableHead::len_for(cells.len());
    let mut records = Vec::new();
    let mut dir = Vec::with_capacity(cells.len());
    for (k, (id, pvs)) in cells.iter().enumerate() {
        if k > 0 && cells[k - 1].0 >= *id {
            return Err(Error::Invalid(format!(
                "cell ids must ascend: {id} follows {}",
                cells[k - 1].0
            )));
        }
        let r = encode_record(pvs)?;
        dir.push(CellEntry {
            id: *id,
            offset: (head_len + records.len()) as u64,
            len: r.len() as u32,
            count: pvs.ids.len() as u32,
        });
        records.extend_from_slice(&r);
    }
    let mut b = Vec::with_capacity(head_len + records.len());
    b.extend_from_slice(&TABLE_MAGIC);
    for v in [
        TABLE_VERSION,
        cells.len() as u32,
        grid.rows(),
        grid.columns(),
    ] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    for f in [
        grid.origin.x,
        grid.origin.y,
        grid.origin.z,
        grid.size,
        grid.eye[0],
        grid.eye[1],
    ] {
        b.extend_from_slice(&f.to_le_bytes());
    }
    b.extend_from_slice(&settings.resolution.to_le_bytes());
    b.extend_from_slice(&settings.dov_s.to_le_bytes());
    b.extend_from_slice(&settings.samples.spacing.to_le_bytes());
    b.extend_from_slice(&settings.samples.radius.to_le_bytes());
    b.extend_from_slice(&settings.bins.to_le_bytes());
    b.extend_from_slice(&0u32.to_le_bytes());
    b.extend_from_slice(&stats.seconds.to_le_bytes());
    for v in [stats.rays, stats.entries, stats.objects] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    b.extend_from_slice(&stats.dov_seconds.to_le_bytes());
    debug_assert_eq!(b.len(), HEAD_FIXED);
    for c in &dir {
        b.extend_from_slice(&c.id.to_le_bytes());
        b.extend_from_slice(&c.offset.to_le_bytes());
        b.extend_from_slice(&c.len.to_le_bytes());
        b.extend_from_slice(&c.count.to_le_bytes());
    }
    push_crc(&mut b);
    b.extend_from_slice(&records);
    Ok(b)
}

/// How many cells the fixed head `b` (at least [`HEAD_FIXED`] bytes) says there are,
/// after checking its magic and version.
pub fn cell_count(b: &[u8]) -> Result<usize> {
    bytes::header(
        b,
        HEAD_FIXED,
        "a visibility table",
        TABLE_MAGIC,
        TABLE_VERSION,
    )
    .map_err(corrupt)?;
    Ok(u32_at(b, 8) as usize)
}

/// Decodes the head (exactly [`TableHead::len_for`] bytes) of a table of `table_len`
/// bytes, checking what it can: the checksum, the grid, the directory's order and
/// that every record lies inside the table.
pub fn decode_head(b: &[u8], table_len: u64) -> Result<TableHead> {
    let n = cell_count(b)?;
    let len = TableHead::len_for(n);
    bytes::exactly(b.len(), len as u64, "its cells take").map_err(corrupt)?;
    bytes::checksum(b, len - CRC_LEN).map_err(|w| corrupt(format!("head {w}")))?;
    let (rows, columns) = (u32_at(b, 12), u32_at(b, 16));
    let origin = Vec3::new(f32_at(b, 20), f32_at(b, 24), f32_at(b, 28));
    let (size, eye) = (f32_at(b, 32), [f32_at(b, 36), f32_at(b, 40)]);
    // Half a cell short of the grid's far side: origin + columns × size, rounded to
    // f32, may lie past it and round up to one column more.
    let city_max = origin
        + Vec3::new(
            (columns as f32 - 0.5) * size,
            eye[1].max(0.0) + 1.0,
            (rows as f32 - 0.5) * size,
        );
    let city = crate::geom::Aabb {
        min: origin,
        max: city_max,
    };
    let grid = ViewcellGrid::new(&city, size, eye).map_err(|e| corrupt(format!("grid: {e}")))?;
    if (grid.rows(), grid.columns()) != (rows, columns) {
        return Err(corrupt(format!(
            "a grid of {rows} × {columns} cells of {size} m is not consistent"
        )));
    }
    let settings = VisibilitySettings {
        resolution: u32_at(b, 44),
        dov_s: f32_at(b, 48),
        samples: SampleOptions {
            spacing: f32_at(b, 52),
            radius: f32_at(b, 56),
        },
        bins: u32_at(b, 60),
    };
    let stats = VisibilityStats {
        seconds: f64::from_bits(u64_at(b, 68)),
        rays: u64_at(b, 76),
        entries: u64_at(b, 84),
        objects: u64_at(b, 92),
        dov_seconds: f64::from_bits(u64_at(b, 100)),
    };
    let mut cells = Vec::with_capacity(n);
    for k in 0..n {
        let at = HEAD_FIXED + DIR_ENTRY * k;
        let c = CellEntry {
            id: u32_at(b, at),
            offset: u64_at(b, at + 4),
            len: u32_at(b, at + 12),
            count: u32_at(b, at + 16),
        };
        if c.id as usize >= grid.len() {
            return Err(corrupt(format!("cell {} is outside the grid", c.id)));
        }
        if cells.last().is_some_and(|p: &CellEntry| p.id >= c.id) {
            return Err(corrupt(format!("cell ids do not ascend at cell {}", c.id)));
        }
        let end = c.offset.checked_add(c.len as u64);
        if c.offset < len as u64 || end.is_none_or(|e| e > table_len) {
            return Err(corrupt(format!(
                "cell {}'s record ({} bytes at {}) lies outside the table's records",
                c.id, c.len, c.offset
            )));
        }
        cells.push(c);
    }
    Ok(TableHead {
        grid,
        settings,
        stats,
        cells,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Aabb;
    use crate::store::framing::{mangled, reseal};

    #[test]
    fn a_varint_past_64_bits_is_refused_not_cut() {
        let mut max = vec![0xff; 9];
        max.push(0x01);
        assert_eq!(read_varint(&max, &mut 0), Some(u64::MAX));
        let mut over = vec![0xff; 9];
        over.push(0x03);
        assert_eq!(read_varint(&over, &mut 0), None);
        assert_eq!(read_varint(&[0x80; 10], &mut 0), None);
    }

    fn sample() -> (
        ViewcellGrid,
        VisibilitySettings,
        VisibilityStats,
        Vec<(u32, CellPvs)>,
    ) {
        let city = Aabb::new([0.0; 3], [95.0, 40.0, 60.0]).unwrap();
        let grid = ViewcellGrid::new(&city, 20.0, [1.2, 2.0]).unwrap();
        let settings = VisibilitySettings {
            resolution: 64,
            dov_s: 1e-5,
            samples: SampleOptions::default(),
            bins: crate::visibility::horizon::BINS as u32,
        };
        let stats = VisibilityStats {
            seconds: 1.5,
            dov_seconds: 0.75,
            rays: 123_456,
            entries: 5,
            objects: 1000,
        };
        let cells = vec![
            (
                1,
                CellPvs {
                    ids: vec![3, 4, 900],
                    dov: vec![0.5, 1e-5, 1.0],
                },
            ),
            (2, CellPvs::default()),
            (
                14,
                CellPvs {
                    ids: vec![u64::MAX - 1, u64::MAX],
                    dov: vec![0.25, 0.125],
                },
            ),
        ];
        (grid, settings, stats, cells)
    }

    #[test]
    fn every_grid_reads_back_whatever_its_origin_and_size_round_to() {
        // Cities whose far side, origin + columns × size in f32, rounds past the grid: the
        // head once read one such as a column more, and refused its own file.
        let (_, settings, stats, cells) = sample();
        let mut checked = 0;
        for i in 0..400 {
            let origin = -437.17 + i as f32 * 3.331;
            for size in [7.3f32, 20.0, 33.3, 40.0] {
                let far = origin + 17.9 * size;
                let city = Aabb::new([origin, 0.0, origin - 11.1], [far, 40.0, far]).unwrap();
                let grid = ViewcellGrid::new(&city, size, [1.2, 2.0]).unwrap();
                let b = encode_table(&grid, &settings, &stats, &cells).unwrap();
                let n = cell_count(&b[..HEAD_FIXED]).unwrap();
                let head = decode_head(&b[..TableHead::len_for(n)], b.len() as u64).unwrap();
                assert_eq!(head.grid, grid, "origin {origin}, size {size}");
                checked += 1;
            }
        }
        assert_eq!(checked, 1600);
    }

    #[test]
    fn round_trip() {
        let (grid, settings, stats, cells) = sample();
        let b = encode_table(&grid, &settings, &stats, &cells).unwrap();
        let n = cell_count(&b[..HEAD_FIXED]).unwrap();
        let head = decode_head(&b[..TableHead::len_for(n)], b.len() as u64).unwrap();
        assert_eq!(head.grid, grid);
        assert_eq!(head.settings, settings);
        assert_eq!(head.stats, stats);
        assert_eq!(head.cells.len(), 3);
        assert!(head.cell(3).is_none());
        for (id, pvs) in &cells {
            let c = head.cell(*id).unwrap();
            let r = &b[c.offset as usize..(c.offset + c.len as u64) as usize];
            let back = decode_record(r, c.count).unwrap();
            assert_eq!(back.ids, pvs.ids);
            for (a, e) in back.dov.iter().zip(&pvs.dov) {
                assert!((a - e).abs() <= 0.5 / 65535.0 + 1e-7, "{a} {e}");
                assert!(*a > 0.0);
            }
        }
    }

    #[test]
    fn bad_input_is_refused() {
        let bad = |ids: Vec<u64>, dov: Vec<f32>| encode_record(&CellPvs { ids, dov }).is_err();
        assert!(bad(vec![1, 2], vec![0.5]));
        assert!(bad(vec![2, 1], vec![0.5, 0.5]));
        assert!(bad(vec![1, 1], vec![0.5, 0.5]));
        assert!(bad(vec![1], vec![0.0]));
        assert!(bad(vec![1], vec![f32::NAN]));
        assert!(bad(vec![1], vec![1.5]));
        let (grid, settings, stats, mut cells) = sample();
        cells.swap(0, 1);
        assert!(encode_table(&grid, &settings, &stats, &cells).is_err());
    }

    /// An id's difference that carries it past u64::MAX is refused by name (it was an
    /// overflow panic; the fuzz target `visibility_table` found it).
    #[test]
    fn an_id_past_the_largest_is_refused() {
        let mut b = Vec::new();
        push_varint(&mut b, u64::MAX);
        push_varint(&mut b, 1);
        b.extend_from_slice(&[1, 0, 1, 0]);
        push_crc(&mut b);
        let e = decode_record(&b, 2).unwrap_err().to_string();
        assert!(e.contains("past the largest id"), "{e}");
    }

    #[test]
    fn damage_is_found() {
        let (grid, settings, stats, cells) = sample();
        let b = encode_table(&grid, &settings, &stats, &cells).unwrap();
        let head_len = TableHead::len_for(cells.len());
        // Any flipped byte of the head fails its checks.
        for i in 0..head_len {
            let mut m = b[..head_len].to_vec();
            m[i] ^= 0x10;
            assert!(decode_head(&m, b.len() as u64).is_err(), "byte {i}");
        }
        // Random damage, some of it resealed to reach the content checks: never a panic.
        mangled(7, 400, 300, &b[..head_len], reseal, |m| {
            let _ = cell_count(m).and_then(|_| decode_head(m, b.len() as u64));
        });
        let mut wrong = b[..head_len].to_vec();
        wrong[HEAD_FIXED + 4..HEAD_FIXED + 12].copy_from_slice(&(b.len() as u64).to_le_bytes());
        reseal(&mut wrong);
        assert!(
            decode_head(&wrong, b.len() as u64).is_err(),
            "record past the end"
        );
        let c = &decode_head(&b[..head_len], b.len() as u64).unwrap().cells[0];
        let r = b[c.offset as usize..(c.offset + c.len as u64) as usize].to_vec();
        for i in 0..r.len() {
            let mut m = r.clone();
            m[i] ^= 0x01;
            assert!(decode_record(&m, c.count).is_err(), "record byte {i}");
        }
        mangled(8, 400, 64, &r, reseal, |m| {
            let _ = decode_record(m, c.count);
        });
        assert!(decode_record(&r, c.count + 1).is_err());
        assert!(decode_record(&r[..3], c.count).is_err());
    }
}
