//! The visibility precomputation split across processes: shard K of N computes the
//! cells of its run of bands (`flaneur build --visibility --shard K/N`) into a shard
//! file, and a merge joins every shard's cells into the database's table
//! (`flaneur merge`), the same table a one-process build stores.
//!
//! Each shard gets a contiguous run of the walkable cells (in id order, row by row),
//! as many cells each as can be, computed in bands of rows as a whole build computes
//! them, so that neighbouring cells still share their corners' DoVs within a shard. A shard records what it was computed from: a fingerprint of the
//! objects (ids and meshes) and the visibility settings, which the merge checks against
//! its own input, so that shards of another city or other settings are refused. It also
//! records the coarse LOD levels its DoVs drew far objects through, or none (`--no-lod`),
//! which the merge checks against the LODs it stores, as a whole build draws through
//! those: shards of one kind merged into a build of the other would give DoVs no whole
//! build gives. A shard of another version is refused (computing it again is the way).
//!
//! ```text
//! offset  width  field
//! ------  -----  ----------------------------------------------------------------
//!      0      4  magic         b"FLVS"
//!      4      4  version       u32, SHARD_VERSION
//!      8      4  shard         u32, K (0-based)
//!     12      4  shards        u32, N
//!     16      8  fingerprint   u64, of the objects and the settings
//!     24      4  cell size     f32, metres
//!     28      8  eye           f32 × 2, metres
//!     36      4  resolution    u32, N of the cube faces
//!     40      8  samples       f32 × 2: spacing, radius
//!     48      8  walkable      u64, walkable cells of the whole grid
//!     56      8  occluders     u64, objects with an occluder box
//!     64      8  rays          u64, cast by this shard
//!     72      8  seconds       f64, this shard's wall clock
//!     80      8  DoV seconds   f64, of which casting rays
//!     88      4  LOD ratio     f32, of the coarse levels far objects' DoVs were drawn
//!                              through; 0: none, full meshes only (`--no-lod`)
//!     92      4  LOD floor     u32, the levels' fewest triangles; 0 with no levels
//!     96      4  cells         u32, m: this shard's cells
//!    100      …  m × (id u32, objects u32, bytes u32, the table's record of the cell)
//!      …      4  crc32         of everything before it
//! ```

use std::path::Path;
use std::time::Instant;

use super::precompute::{
    bands, compute, grid_and_walkable, prepare, settings, whole_build_rays, Precomputed,
};
use super::table::{decode_record, encode_record, CellPvs, VisibilityStats};
use super::{CubicProjection, DovMethod, SampleOptions, VisibilityOptions};
use crate::error::{Error, Result};
use crate::scene::Mesh;
use crate::store::framing::{f32_at, f64_at, push_crc, u32_at, u64_at, CRC_LEN};

const MAGIC: [u8; 4] = *b"FLVS";
/// 2: the LOD levels the DoVs drew recorded (version 1 did not say).
const SHARD_VERSION: u32 = 2;
const HEAD_LEN: usize = 100;

/// One shard of N: `index` in `0..count`, written `K/N` (`--shard 0/4` … `3/4`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// Which shard, from 0.
    pub index: u32,
    /// How many shards in all.
    pub count: u32,
}

impl std::str::FromStr for Shard {
    type Err = String;

    /// `K/N`, with `K` from 0 to `N − 1` (as a Kubernetes Indexed Job's
    /// `JOB_COMPLETION_INDEX` counts; a Slurm array from 1 subtracts one).
    fn from_str(s: &str) -> std::result::Result<Shard, String> {
        let bad =
            || format!("'{s}': a shard is K/N, with K from 0 to N - 1 (0/4 is the first of 4)");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            k.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        let shard = Shard { index, count };
        shard.check()?;
        Ok(shard)
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    fn check(&self) -> std::result::Result<(), String> {
        if self.count == 0 || self.index >= self.count {
            return Err(format!(
                "shard {}/{}: K must be below N, from 0 (0/4 is the first of 4)",
                self.index, self.count
            ));
        }
        Ok(())
    }
}

/// The coarse LOD levels a shard's DoVs drew far objects through: the settings of the
/// build's LOD options that shape them, which a merge's must match.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShardLod {
    /// Triangles of each level over the next finer one's (the LOD options' `ratio`).
    pub ratio: f32,
    /// A chain stops at this many triangles (their `min_triangles`).
    pub min_triangles: u32,
}

/// The cells one shard computed, and what they were computed from.
#[derive(Clone, Debug, PartialEq)]
pub struct ShardCells {
    /// Which shard of how many.
    pub shard: Shard,
    /// Of the objects and the visibility settings ([`fingerprint`]).
    pub fingerprint: u64,
    /// The settings it was computed with.
    pub options: VisibilityOptions,
    /// The coarse levels its DoVs drew far objects through, `None` for full meshes.
    pub lod: Option<ShardLod>,
    /// Walkable cells of the whole grid.
    pub walkable: u64,
    /// Objects with an occluder box (the whole city's).
    pub occluders: u64,
    /// Rays this shard cast (a merge stores what a whole build casts: see
    /// `whole_build_rays`).
    pub rays: u64,
    /// Wall-clock seconds of this shard.
    pub seconds: f64,
    /// Of those, the seconds spent casting the DoV's rays.
    pub dov_seconds: f64,
    /// Its cells with their PVSs, ids ascending.
    pub cells: Vec<(u32, CellPvs)>,
}

/// A fingerprint of `objects` (ids and meshes, in the order given) and the settings
/// that shape visibility: two CRC-32s with different starts, one u64.
pub fn fingerprint(objects: &[(u64, Mesh)], opts: &VisibilityOptions) -> u64 {
    let mut halves = [
        crc32fast::Hasher::new(),
        crc32fast::Hasher::new_with_initial(0x5eed),
    ];
    for h in &mut halves {
        h.update(&settings_bytes(opts));
        for (id, m) in objects {
            h.update(&id.to_le_bytes());
            h.update(&(m.positions.len() as u64).to_le_bytes());
            for p in &m.positions {
                for c in p {
                    h.update(&c.to_le_bytes());
                }
            }
            for i in &m.indices {
                h.update(&i.to_le_bytes());
            }
        }
    }
    let [a, b] = halves.map(|h| h.finalize());
    (u64::from(a) << 32) | u64::from(b)
}

/// The settings as the shard file stores them (offsets 24..48).
fn settings_bytes(o: &VisibilityOptions) -> Vec<u8> {
    let mut b = Vec::with_capacity(24);
    for f in [o.cell_size, o.eye[0], o.eye[1]] {
        b.extend(f.to_le_bytes());
    }
    b.extend(o.resolution.to_le_bytes());
    for f in [o.samples.spacing, o.samples.radius] {
        b.extend(f.to_le_bytes());
    }
    b
}

/// The cells of `walkable` shard `shard` computes: the `index`-th of `count` runs of as
/// nearly equal length as can be.
fn my_cells<T>(walkable: &[T], shard: Shard) -> &[T] {
    let n = walkable.len() as u128;
    let at = |k: u32| (n * k as u128 / shard.count as u128) as usize;
    &walkable[at(shard.index)..at(shard.index + 1)]
}

/// Computes shard `shard` of the visibility of `objects`, far objects drawn through
/// their coarser `levels` as a whole build draws them (one entry per object, or empty
/// for none), which `lod` made (recorded in the shard: `None` exactly when `levels` is
/// empty); `progress` is told this shard's cells done and its cells in all.
pub fn precompute_shard(
    objects: &[(u64, Mesh)],
    levels: &[Vec<(Mesh, f32)>],
    lod: Option<ShardLod>,
    opts: &VisibilityOptions,
    shard: Shard,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<ShardCells> {
    shard.check().map_err(Error::Invalid)?;
    if !objects.is_empty() && levels.is_empty() != lod.is_none() {
        return Err(Error::Invalid(format!(
            "a shard's levels ({} objects' worth) and the LOD settings recorded for them \
             ({lod:?}) disagree",
            levels.len()
        )));
    }
    let started = Instant::now();
    let prep = prepare(objects, levels, opts)?;
    let bands = bands(my_cells(&prep.walkable, shard));
    let made = compute(&prep, objects, opts, &bands, progress)?;
    Ok(ShardCells {
        shard,
        fingerprint: fingerprint(objects, opts),
        options: *opts,
        lod,
        walkable: prep.walkable.len() as u64,
        occluders: prep.occluders as u64,
        rays: made.rays,
        seconds: started.elapsed().as_secs_f64(),
        dov_seconds: made.dov_seconds,
        cells: made.cells,
    })
}

/// The visibility of `objects` from every shard of one precomputation: the table a
/// whole build makes, its rays counted as that build casts them; its seconds are the
/// shards' summed.
/// Refused, naming the shard, unless the shards are all N of one split, computed from
/// these objects under one set of settings, covering every walkable cell once.
pub(crate) fn merge_shards(objects: &[(u64, Mesh)], shards: &[ShardCells]) -> Result<Precomputed> {
    let first = shards
        .first()
        .ok_or_else(|| Error::Invalid("no shard to merge".into()))?;
    let opts = first.options;
    opts.validate()?;
    let n = first.shard.count;
    let mut seen = vec![false; n as usize];
    let print = fingerprint(objects, &opts);
    for s in shards {
        let name = format!("shard {}", s.shard);
        if s.shard.count != n {
            return Err(Error::Invalid(format!(
                "{name} is of another split than shard {}",
                first.shard
            )));
        }
        if s.options != opts {
            return Err(Error::Invalid(format!(
                "{name} was computed with other visibility settings than shard {}",
                first.shard
            )));
        }
        if s.fingerprint != print {
            return Err(Error::Invalid(format!(
                "{name} was computed from other objects (or settings) than this build's"
            )));
        }
        if std::mem::replace(&mut seen[s.shard.index as usize], true) {
            return Err(Error::Invalid(format!("{name} is given twice")));
        }
    }
    if let Some(k) = seen.iter().position(|s| !s) {
        return Err(Error::Invalid(format!("shard {k}/{n} is missing")));
    }
    let (grid, walkable) = grid_and_walkable(objects, &opts)?;
    let mut cells: Vec<(u32, CellPvs)> = shards
        .iter()
        .flat_map(|s| s.cells.iter().cloned())
        .collect();
    cells.sort_unstable_by_key(|c| c.0);
    let ids: Vec<u32> = walkable.iter().map(|c| c.id).collect();
    if cells.len() != ids.len() || cells.iter().zip(&ids).any(|(c, id)| c.0 != *id) {
        return Err(Error::Invalid(format!(
            "the shards hold {} cells, the grid has {} walkable cells: not the same cells",
            cells.len(),
            ids.len()
        )));
    }
    let projection = CubicProjection::new(opts.resolution)?;
    Ok(Precomputed {
        settings: settings(&opts, projection.zero_dov_floor()),
        stats: VisibilityStats {
            seconds: shards.iter().map(|s| s.seconds).sum(),
            dov_seconds: shards.iter().map(|s| s.dov_seconds).sum(),
            rays: whole_build_rays(&walkable, &projection),
            entries: cells.iter().map(|(_, p)| p.ids.len() as u64).sum(),
            objects: objects.len() as u64,
        },
        grid,
        cells,
        occluders: first.occluders as usize,
    })
}

impl ShardCells {
    /// The shard file's bytes.
    pub fn encode(&self) -> Result<Vec<u8>> {
        let mut b = Vec::new();
        b.extend(MAGIC);
        for v in [SHARD_VERSION, self.shard.index, self.shard.count] {
            b.extend(v.to_le_bytes());
        }
        b.extend(self.fingerprint.to_le_bytes());
        b.extend(settings_bytes(&self.options));
        for v in [self.walkable, self.occluders, self.rays] {
            b.extend(v.to_le_bytes());
        }
        b.extend(self.seconds.to_le_bytes());
        b.extend(self.dov_seconds.to_le_bytes());
        let (ratio, floor) = self.lod.map_or((0.0, 0), |l| (l.ratio, l.min_triangles));
        b.extend(ratio.to_le_bytes());
        b.extend(floor.to_le_bytes());
        b.extend((self.cells.len() as u32).to_le_bytes());
        debug_assert_eq!(b.len(), HEAD_LEN);
        for (id, pvs) in &self.cells {
            let r = encode_record(pvs)?;
            b.extend(id.to_le_bytes());
            b.extend((pvs.ids.len() as u32).to_le_bytes());
            b.extend((r.len() as u32).to_le_bytes());
            b.extend(r);
        }
        push_crc(&mut b);
        Ok(b)
    }

    /// Reads a shard file's bytes, every part checked; the error says what is wrong.
    pub fn decode(b: &[u8]) -> std::result::Result<ShardCells, String> {
        if b.len() < HEAD_LEN + CRC_LEN || b[..4] != MAGIC {
            return Err("not a flaneur visibility shard (no FLVS head)".into());
        }
        let version = u32_at(b, 4);
        if version != SHARD_VERSION {
            return Err(format!(
                "shard version {version}, this flaneur reads version {SHARD_VERSION} only \
                 (version 1 did not record the LOD levels its DoVs drew): compute the shards \
                 again with this flaneur"
            ));
        }
        let body = b.len() - CRC_LEN;
        crate::store::framing::checksum(b, body)?;
        let shard = Shard {
            index: u32_at(b, 8),
            count: u32_at(b, 12),
        };
        shard.check()?;
        let options = VisibilityOptions {
            cell_size: f32_at(b, 24),
            eye: [f32_at(b, 28), f32_at(b, 32)],
            resolution: u32_at(b, 36),
            samples: SampleOptions {
                spacing: f32_at(b, 40),
                radius: f32_at(b, 44),
            },
            dov: DovMethod::default(),
        };
        options.validate().map_err(|e| e.to_string())?;
        let lod = match (f32_at(b, 88), u32_at(b, 92)) {
            (ratio, 0) if ratio == 0.0 => None,
            (ratio, min_triangles) if ratio > 0.0 && ratio < 1.0 => Some(ShardLod {
                ratio,
                min_triangles,
            }),
            (ratio, floor) => {
                return Err(format!(
                    "LOD ratio {ratio} with a floor of {floor} triangles: not levels a build makes"
                ))
            }
        };
        let count = u32_at(b, 96) as usize;
        let mut cells = Vec::with_capacity(count.min(body / 12));
        let mut at = HEAD_LEN;
        for k in 0..count {
            if body - at < 12 {
                return Err(format!("cell {k} of {count} lies past the file's end"));
            }
            let (id, objects, len) = (u32_at(b, at), u32_at(b, at + 4), u32_at(b, at + 8) as usize);
            at += 12;
            if body - at < len {
                return Err(format!(
                    "cell {id}'s record of {len} bytes lies past the file's end"
                ));
            }
            let pvs =
                decode_record(&b[at..at + len], objects).map_err(|e| format!("cell {id}: {e}"))?;
            if cells.last().is_some_and(|(last, _)| *last >= id) {
                return Err(format!(
                    "cell ids must ascend: {id} follows {}",
                    cells.last().unwrap().0
                ));
            }
            cells.push((id, pvs));
            at += len;
        }
        if at != body {
            return Err(format!("{} bytes after the last cell", body - at));
        }
        Ok(ShardCells {
            shard,
            fingerprint: u64_at(b, 16),
            options,
            lod,
            walkable: u64_at(b, 48),
            occluders: u64_at(b, 56),
            rays: u64_at(b, 64),
            seconds: f64_at(b, 72),
            dov_seconds: f64_at(b, 80),
            cells,
        })
    }

    /// Checks that this shard's DoVs drew far objects as a build storing the levels
    /// `merge` describes (`None`: none) draws them, so that a merge storing them gives the
    /// whole build's DoVs; the error names the shard and what differs.
    pub fn check_lod(&self, merge: Option<ShardLod>) -> std::result::Result<(), String> {
        let name = format!("shard {}", self.shard);
        let levels = |l: ShardLod| {
            format!(
                "coarse LOD levels (ratio {}, down to {} triangles)",
                l.ratio, l.min_triangles
            )
        };
        if self.lod == merge {
            return Ok(());
        }
        Err(match (self.lod, merge) {
            (None, _) => format!(
                "{name} drew its DoVs on full meshes (computed with --no-lod), but this merge \
                 stores LODs, which a whole build draws far objects through: merge with \
                 --no-lod, or compute the shards again without it"
            ),
            (Some(mine), None) => format!(
                "{name} drew far objects' DoVs through {}, but this merge stores none \
                 (--no-lod): merge without --no-lod, or compute the shards again with it",
                levels(mine)
            ),
            (Some(mine), Some(merge)) => format!(
                "{name} drew far objects' DoVs through {}, but this merge stores {}: merge \
                 with the shards' LOD settings",
                levels(mine),
                levels(merge)
            ),
        })
    }

    /// Writes the shard file at `path` (through a temporary beside it, renamed into
    /// place, so that a shard killed mid-write leaves no file a merge would take).
    pub fn write(&self, path: &Path) -> Result<()> {
        crate::store::write_file_atomically(path, &self.encode()?)
    }

    /// Reads the shard file at `path`.
    pub fn read(path: &Path) -> Result<ShardCells> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        ShardCells::decode(&bytes).map_err(|what| Error::BadInput {
            path: path.to_path_buf(),
            what,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_are_k_of_n_from_zero() {
        assert_eq!("2/4".parse::<Shard>(), Ok(Shard { index: 2, count: 4 }));
        for bad in ["4/4", "1", "a/b", "0/0", "-1/4"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }

    #[test]
    fn shards_take_runs_of_cells_as_equal_as_can_be() {
        let cells: Vec<u32> = (0..10).collect();
        let runs: Vec<&[u32]> = (0..4)
            .map(|index| my_cells(&cells, Shard { index, count: 4 }))
            .collect();
        assert_eq!(runs, vec![&[0, 1][..], &[2, 3, 4], &[5, 6], &[7, 8, 9]]);
        assert!(
            my_cells(&cells[..2], Shard { index: 0, count: 4 }).is_empty(),
            "more shards than cells"
        );
    }
}
