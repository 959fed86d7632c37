//! The `pvs-tightness` experiment (ours, for Shou 2002 §5.5.1): each sampled viewcell's
//! conservative PVS against the set of objects that a dense sampling of the cell sees.
//!
//! The dense sampling: 32 viewpoints a cell by default (its 8 corners, the centres of
//! its 4 side faces at mid height, and 20 interior points drawn from a generator seeded
//! by the seed and the cell's id), each casting N × N rays a cube face into the full
//! meshes with the engine's ray-cast [`point_dov`], the reference the build's DoV is
//! held to. An object a ray meets first is seen from the cell; one seen and missing from
//! the PVS is a fault of the conservative test (it must never happen). The PVS over
//! the seen set is how loose the test is: 1 would be exact, at this sampling.
//!
//! The cells are spread evenly over the walkable ones (every k-th in id order). The
//! PVS is the stored one, or, with `recompute`, the one this binary's conservative test
//! gives for the cell, told what the corners' rays saw as the build tells it: the
//! same PVS a build with this binary would store, without the build.

use std::time::Instant;

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::report::Report;
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::geom::Aabb;
use flaneur::scene::Mesh;
use flaneur::visibility::{
    point_dov, ConservativeScene, CubicProjection, RayScene, SampleOptions, TableHead,
};

/// How the experiment samples.
#[derive(Clone, Debug, PartialEq)]
pub struct PvsTightnessConfig {
    /// Cells measured, spread evenly over the walkable ones (all of them when fewer).
    pub cells: usize,
    /// Seeded interior viewpoints a cell, beside its 8 corners and 4 side-face centres.
    pub interior: usize,
    /// Pixels per side of a cube face (N): 6N² rays a viewpoint.
    pub resolution: u32,
    /// Seeds the interior viewpoints.
    pub seed: u64,
    /// Recompute each cell's PVS with this binary's conservative test instead of
    /// reading the stored one (see [`run`]); `Some` sampling overrides the stored
    /// settings.
    pub recompute: Option<Option<SampleOptions>>,
}

impl Default for PvsTightnessConfig {
    fn default() -> Self {
        PvsTightnessConfig {
            cells: 40,
            interior: 20,
            resolution: 256,
            seed: 1,
            recompute: None,
        }
    }
}

/// One cell measured.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CellRow {
    pub cell: u32,
    /// Objects in its PVS.
    pub pvs: usize,
    /// Objects that some viewpoint's rays met first.
    pub seen: usize,
    /// `pvs / seen` (infinite when nothing was seen and the PVS is not empty).
    pub ratio: f64,
    /// Seen objects missing from the PVS, by id: must be none.
    pub missing: Vec<u64>,
    /// Seconds the conservative test took for the cell (recomputed only; else 0).
    pub conservative_seconds: f64,
}

/// What the experiment measured.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PvsTightnessReport {
    pub objects: u64,
    pub walkable_cells: usize,
    pub viewpoints_per_cell: usize,
    pub resolution: u32,
    pub rays: u64,
    /// Where the PVS came from: "stored" or "recomputed".
    pub source: &'static str,
    /// The conservative test's sampling (spacing, radius), as stored or as recomputed.
    pub spacing: f32,
    pub radius: f32,
    /// Recomputed only: the conservative scene's setup (occluders, prisms, indices), its
    /// occluding objects and prisms.
    pub setup_seconds: f64,
    pub occluding_objects: usize,
    pub prisms: usize,
    /// Seconds the dense sampling took.
    pub sampling_seconds: f64,
    pub mean_pvs: f64,
    pub mean_seen: f64,
    /// `mean_pvs / mean_seen`: the figure the goal is set on.
    pub ratio_of_means: f64,
    /// The per-cell ratios' minimum, quartiles and maximum.
    pub ratio_quartiles: [f64; 5],
    /// The conservative test's mean seconds a cell (recomputed only).
    pub conservative_seconds_per_cell: f64,
    pub rows: Vec<CellRow>,
}

impl PvsTightnessReport {
    /// Every seen object missing from its cell's PVS, as (cell, object id).
    pub fn missing(&self) -> Vec<(u32, u64)> {
        self.rows
            .iter()
            .flat_map(|r| r.missing.iter().map(move |&m| (r.cell, m)))
            .collect()
    }
}

/// The viewpoints of `cell`: its 8 corners, the centres of its 4 side faces at mid
/// height, and `interior` points drawn uniformly inside it from `rng`.
pub fn viewpoints(cell: &Aabb, interior: usize, rng: &mut impl Rng) -> Vec<Vec3> {
    let (lo, hi, c) = (cell.min, cell.max, cell.center());
    let mut points: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    points.extend([
        Vec3::new(lo.x, c.y, c.z),
        Vec3::new(hi.x, c.y, c.z),
        Vec3::new(c.x, c.y, lo.z),
        Vec3::new(c.x, c.y, hi.z),
    ]);
    points.extend((0..interior).map(|_| {
        let f = Vec3::new(rng.gen(), rng.gen(), rng.gen());
        lo + f * (hi - lo)
    }));
    points
}

/// `n` of `walkable` (ascending), spread evenly: every k-th, k = len / n; all when
/// there are no more than `n`.
pub fn spread(walkable: &[u32], n: usize) -> Vec<u32> {
    if n >= walkable.len() {
        return walkable.to_vec();
    }
    (0..n).map(|i| walkable[i * walkable.len() / n]).collect()
}

/// The objects (indices into `rays`) that the rays of `projection` from each of
/// `points` meet first, ascending.
pub fn seen_from(
    rays: &RayScene,
    projection: &CubicProjection,
    points: &[Vec3],
) -> Result<Vec<u32>> {
    let mut seen = vec![false; rays.object_count()];
    for p in points {
        for (o, _) in point_dov(rays, projection, p.to_array())?.objects {
            seen[o as usize] = true;
        }
    }
    Ok((0..seen.len() as u32)
        .filter(|&i| seen[i as usize])
        .collect())
}

/// A cell's PVS as the experiment is told it: object ids, ascending.
pub type PvsOf<'a> = dyn Fn(u32) -> Result<Vec<u64>> + Sync + 'a;

/// Where the PVS measured comes from.
pub enum PvsSource<'a> {
    /// The database's stored PVS.
    Stored,
    /// This binary's conservative test, sampling as given, told what the corners'
    /// rays met (as a build tells it).
    Recomputed(SampleOptions),
    /// Given by the caller, by cell id (a test breaks a PVS on purpose through it).
    Given(&'a PvsOf<'a>),
}

/// One sampled cell: what its corners' rays met, and what all its viewpoints' did.
#[derive(Clone, Debug)]
pub struct SampledCell {
    pub cell: u32,
    pub bounds: Aabb,
    /// Object indices (into [`Sampling::ids`]), ascending.
    pub corners_seen: Vec<u32>,
    pub seen: Vec<u32>,
}

/// The dense sampling of a database's cells, made once and set against any PVS.
pub struct Sampling {
    pub objects: Vec<(u64, Mesh)>,
    /// The object id of each index.
    pub ids: Vec<u64>,
    pub walkable_cells: usize,
    pub viewpoints_per_cell: usize,
    pub resolution: u32,
    pub rays: u64,
    pub seconds: f64,
    /// The stored conservative test's sampling.
    pub stored_samples: SampleOptions,
    pub cells: Vec<SampledCell>,
}

/// Measures `db` (built with --visibility) as `cfg` says.
pub fn run(db: &Database, cfg: &PvsTightnessConfig) -> Result<PvsTightnessReport> {
    let sampling = sample(db, cfg)?;
    let source = match cfg.recompute {
        None => PvsSource::Stored,
        Some(s) => PvsSource::Recomputed(s.unwrap_or(sampling.stored_samples)),
    };
    measure(db, &sampling, &source)
}

/// What an experiment on a database's stored visibility starts from: the cube it
/// samples with, the visibility head, the walkable cells' ids (ascending) and every
/// object's full mesh, by id, in the index's order.
pub struct StoredVisibility {
    pub projection: CubicProjection,
    pub head: TableHead,
    pub walkable: Vec<u32>,
    pub objects: Vec<(u64, Mesh)>,
}

/// Reads `db`'s [`StoredVisibility`] for `cells` cells at N = `resolution`: an error
/// naming `--cells` for none, `--resolution` for a bad N, and `--visibility` where the
/// database has none.
pub fn stored_visibility(db: &Database, cells: usize, resolution: u32) -> Result<StoredVisibility> {
    if cells == 0 {
        return Err(Error::Invalid("--cells must be at least 1".into()));
    }
    let projection = CubicProjection::new(resolution)
        .map_err(|e| Error::Invalid(format!("{e} (--resolution)")))?;
    let head = db.visibility()?.ok_or_else(|| {
        Error::Invalid(format!(
            "{} has no visibility: build it with --visibility",
            db.store().path().display()
        ))
    })?;
    let head = head.clone();
    let walkable = head.cells.iter().map(|c| c.id).collect();
    let objects = db
        .range(&db.bounds())?
        .objects
        .iter()
        .map(|e| Ok((e.id, db.mesh(e)?)))
        .collect::<Result<_>>()?;
    Ok(StoredVisibility {
        projection,
        head,
        walkable,
        objects,
    })
}

/// Samples `db`'s cells densely, as `cfg` says.
pub fn sample(db: &Database, cfg: &PvsTightnessConfig) -> Result<Sampling> {
    let StoredVisibility {
        projection,
        head,
        walkable,
        objects,
    } = stored_visibility(db, cfg.cells, cfg.resolution)?;
    let rays = RayScene::new(objects.iter().map(|(id, m)| (*id, m)))?;
    let ids: Vec<u64> = (0..rays.object_count() as u32)
        .map(|i| rays.object_id(i).unwrap_or(u64::MAX))
        .collect();
    let started = Instant::now();
    let mut cells = Vec::new();
    for cell in spread(&walkable, cfg.cells) {
        let (r, c) = head.grid.place(cell);
        let bounds = head.grid.cell_bounds(r, c);
        let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed ^ (u64::from(cell) << 20));
        let points = viewpoints(&bounds, cfg.interior, &mut rng);
        let corners_seen = seen_from(&rays, &projection, &points[..8])?;
        let mut seen = corners_seen.clone();
        seen.extend(seen_from(&rays, &projection, &points[8..])?);
        seen.sort_unstable();
        seen.dedup();
        cells.push(SampledCell {
            cell,
            bounds,
            corners_seen,
            seen,
        });
    }
    let viewpoints_per_cell = 12 + cfg.interior;
    Ok(Sampling {
        ids,
        walkable_cells: walkable.len(),
        viewpoints_per_cell,
        resolution: cfg.resolution,
        rays: cells.len() as u64 * viewpoints_per_cell as u64 * projection.rays_per_point(),
        seconds: started.elapsed().as_secs_f64(),
        stored_samples: head.settings.samples,
        cells,
        objects,
    })
}

/// Sets each sampled cell's PVS from `source` against what the sampling saw.
pub fn measure(
    db: &Database,
    sampling: &Sampling,
    source: &PvsSource,
) -> Result<PvsTightnessReport> {
    let samples = match source {
        PvsSource::Recomputed(s) => *s,
        _ => sampling.stored_samples,
    };
    samples.validate()?;
    let started = Instant::now();
    let conservative = match source {
        PvsSource::Recomputed(_) => Some(ConservativeScene::from_meshes(&sampling.objects)?),
        _ => None,
    };
    let setup_seconds = started.elapsed().as_secs_f64();
    let ids = &sampling.ids;
    let mut rows = Vec::with_capacity(sampling.cells.len());
    for c in &sampling.cells {
        let mut conservative_seconds = 0.0;
        let mut pvs: Vec<u64> = match (source, &conservative) {
            (PvsSource::Given(f), _) => f(c.cell)?,
            (_, Some(scene)) => {
                let t = Instant::now();
                let kept = scene.visible_from(&c.bounds, &samples, &c.corners_seen)?;
                conservative_seconds = t.elapsed().as_secs_f64();
                kept.iter().map(|&i| ids[i as usize]).collect()
            }
            _ => db.pvs(c.cell)?.map(|p| p.ids).unwrap_or_default(),
        };
        pvs.sort_unstable();
        let mut missing: Vec<u64> = c
            .seen
            .iter()
            .map(|&i| ids[i as usize])
            .filter(|id| pvs.binary_search(id).is_err())
            .collect();
        missing.sort_unstable();
        let ratio = if c.seen.is_empty() {
            if pvs.is_empty() {
                1.0
            } else {
                f64::INFINITY
            }
        } else {
            pvs.len() as f64 / c.seen.len() as f64
        };
        rows.push(CellRow {
            cell: c.cell,
            pvs: pvs.len(),
            seen: c.seen.len(),
            ratio,
            missing,
            conservative_seconds,
        });
    }
    let n = rows.len().max(1) as f64;
    let mean_pvs = rows.iter().map(|r| r.pvs as f64).sum::<f64>() / n;
    let mean_seen = rows.iter().map(|r| r.seen as f64).sum::<f64>() / n;
    let mut ratios: Vec<f64> = rows.iter().map(|r| r.ratio).collect();
    ratios.sort_unstable_by(f64::total_cmp);
    let at = |q: f64| {
        if ratios.is_empty() {
            return 0.0;
        }
        ratios[((ratios.len() - 1) as f64 * q).round() as usize]
    };
    Ok(PvsTightnessReport {
        objects: sampling.objects.len() as u64,
        walkable_cells: sampling.walkable_cells,
        viewpoints_per_cell: sampling.viewpoints_per_cell,
        resolution: sampling.resolution,
        rays: sampling.rays,
        source: match source {
            PvsSource::Stored => "stored",
            PvsSource::Recomputed(_) => "recomputed",
            PvsSource::Given(_) => "given",
        },
        spacing: samples.spacing,
        radius: samples.radius,
        setup_seconds,
        occluding_objects: conservative.as_ref().map_or(0, |s| s.occluding_objects()),
        prisms: conservative.as_ref().map_or(0, |s| s.prism_count()),
        sampling_seconds: sampling.seconds,
        mean_pvs,
        mean_seen,
        ratio_of_means: mean_pvs / mean_seen.max(f64::MIN_POSITIVE),
        ratio_quartiles: [at(0.0), at(0.25), at(0.5), at(0.75), at(1.0)],
        conservative_seconds_per_cell: rows.iter().map(|r| r.conservative_seconds).sum::<f64>() / n,
        rows,
    })
}

/// Runs the conservative test of `scene` over `cells` on all cores, told nothing seen:
/// the seconds it took and the PVS sizes (a profile of the test alone).
pub fn time_conservative(
    scene: &ConservativeScene,
    cells: &[Aabb],
    samples: &SampleOptions,
) -> Result<(f64, Vec<usize>)> {
    let t = Instant::now();
    let sizes = cells
        .par_iter()
        .map(|c| scene.visible_from(c, samples, &[]).map(|v| v.len()))
        .collect::<Result<Vec<usize>>>()?;
    Ok((t.elapsed().as_secs_f64(), sizes))
}

impl Report for PvsTightnessReport {
    fn name(&self) -> &'static str {
        "pvs-tightness"
    }

    fn to_csv(&self) -> String {
        let mut s = String::from("cell,pvs,seen,ratio,missing,conservative_seconds\n");
        for r in &self.rows {
            let missing: Vec<String> = r.missing.iter().map(u64::to_string).collect();
            s.push_str(&format!(
                "{},{},{},{:.4},{},{:.6}\n",
                r.cell,
                r.pvs,
                r.seen,
                r.ratio,
                missing.join(" "),
                r.conservative_seconds
            ));
        }
        s
    }

    fn markdown(&self) -> String {
        let q = self.ratio_quartiles;
        let mut s = format!(
            "# PVS tightness: the conservative PVS against a dense sampling\n\n\
             {} cells of {} walkable, {} objects; {} viewpoints a cell (8 corners, 4 side-face \
             centres, {} seeded interior points), {} × {} rays a cube face: {} rays in {:.1} s.\n\
             PVS {} (sample spacing {} m, occluder radius {} m).\n\n\
             | | value |\n|---|---|\n\
             | mean PVS | {:.1} |\n| mean seen | {:.1} |\n| mean PVS / mean seen | {:.3} |\n\
             | per-cell ratio: min, 25 %, median, 75 %, max | {:.2}, {:.2}, {:.2}, {:.2}, {:.2} |\n\
             | seen objects missing from the PVS | {} |\n",
            self.rows.len(),
            self.walkable_cells,
            self.objects,
            self.viewpoints_per_cell,
            self.viewpoints_per_cell - 12,
            self.resolution,
            self.resolution,
            self.rays,
            self.sampling_seconds,
            self.source,
            self.spacing,
            self.radius,
            self.mean_pvs,
            self.mean_seen,
            self.ratio_of_means,
            q[0],
            q[1],
            q[2],
            q[3],
            q[4],
            self.missing().len(),
        );
        if self.source == "recomputed" {
            s.push_str(&format!(
                "| conservative setup (occluders, prisms, indices) | {:.2} s: {} occluding \
                 objects, {} prisms |\n| conservative test a cell (told the corners' rays) | \
                 {:.1} ms |\n",
                self.setup_seconds,
                self.occluding_objects,
                self.prisms,
                1000.0 * self.conservative_seconds_per_cell
            ));
        }
        for (cell, id) in self.missing() {
            s.push_str(&format!(
                "\nMISSING: cell {cell} sees object {id}, not in its PVS"
            ));
        }
        s.push('\n');
        s
    }

    fn plot(&self, _dir: &std::path::Path) -> Result<()> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viewpoints_are_corners_faces_and_interior() {
        let cell = Aabb::new([0.0, 1.2, 0.0], [40.0, 2.0, 40.0]).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let p = viewpoints(&cell, 20, &mut rng);
        assert_eq!(p.len(), 32);
        assert!(p.iter().all(|v| cell.contains_point(*v)));
        assert_eq!(p[8], Vec3::new(0.0, 1.6, 20.0));
        assert_eq!(spread(&[1, 2, 3, 4, 5, 6], 3), vec![1, 3, 5]);
        assert_eq!(spread(&[1, 2], 3), vec![1, 2]);
    }
}
