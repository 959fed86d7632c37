//! Discrete levels of detail cut from a progressive mesh: walking the split list from
//! the base (refine) or back (coarsen), and plain meshes at a triangle count or an error.
//!
//! A level is always a prefix of the split list that ends between two position splits
//! (never inside a run of `joins_previous` splits, which would crack a crease), so the
//! levels of one mesh are nested, and each level's error is the largest error of the
//! collapses that made it: the error of the coarsest collapse is not always the largest,
//! since the heap's order is by the error at the time.

use crate::scene::Mesh;

use super::progressive::ProgressiveMesh;
use super::vsplit::SelectiveMesh;
use crate::error::{Error, Result};

/// A progressive mesh refined by a prefix of its splits, which grows or shrinks by one
/// position split at a time.
#[derive(Clone, Debug)]
pub struct PmCursor<'a> {
    pm: &'a ProgressiveMesh,
    mesh: SelectiveMesh,
    applied: usize,
}

/// One level of a chain of discrete LODs.
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    /// The level as a plain compact mesh.
    pub mesh: Mesh,
    /// How many of the progressive mesh's splits it takes.
    pub splits: usize,
    /// The largest error of the collapses that made it from the original (metres).
    pub error: f32,
}

impl ProgressiveMesh {
    /// A cursor at the base mesh. An `Err` when the base mesh is not a valid mesh.
    pub fn cursor(&self) -> Result<PmCursor<'_>> {
        Ok(PmCursor {
            pm: self,
            mesh: SelectiveMesh::new(&self.base, self.splits.len())?,
            applied: 0,
        })
    }

    /// A cursor with the first `splits` splits applied. An `Err` when `splits` is past
    /// the end or inside a run of splits that must go together, or when a split does not
    /// apply (a damaged progressive mesh).
    pub fn cursor_at(&self, splits: usize) -> Result<PmCursor<'_>> {
        let mut cursor = self.cursor()?;
        cursor.seek(splits)?;
        Ok(cursor)
    }

    /// Whether a level may end after `splits` splits: not inside a position split's run.
    pub fn is_level_boundary(&self, splits: usize) -> bool {
        splits == 0
            || splits == self.splits.len()
            || self.splits.get(splits).is_some_and(|s| !s.joins_previous)
    }

    /// The number of triangles after the first `splits` splits (the base's when 0).
    pub fn triangles_after(&self, splits: usize) -> usize {
        self.base.triangle_count()
            + self.splits[..splits.min(self.splits.len())]
                .iter()
                .map(|s| s.added_triangles())
                .sum::<usize>()
    }

    /// The largest number of splits (at a level boundary) that leaves at most
    /// `triangles` triangles; 0 when the base alone has more.
    pub fn splits_for_triangles(&self, triangles: usize) -> usize {
        let mut count = self.base.triangle_count();
        let mut best = 0;
        for (i, s) in self.splits.iter().enumerate() {
            count += s.added_triangles();
            if count > triangles {
                break;
            }
            if self.is_level_boundary(i + 1) {
                best = i + 1;
            }
        }
        best
    }

    /// The fewest splits (at a level boundary) such that every collapse left undone has
    /// an error of at most `error` metres. An `Err` for a NaN.
    pub fn splits_for_error(&self, error: f32) -> Result<usize> {
        if error.is_nan() {
            return Err(Error::Invalid("LOD error bound is NaN".into()));
        }
        let mut k = self
            .splits
            .iter()
            .rposition(|s| s.error > error)
            .map_or(0, |i| i + 1);
        while !self.is_level_boundary(k) {
            k += 1;
        }
        Ok(k)
    }

    /// The error of the level after the first `splits` splits: the largest error of the
    /// collapses it is made of (0 for the full mesh).
    pub fn error_after(&self, splits: usize) -> f32 {
        self.splits
            .get(splits..)
            .map_or(0.0, |rest| rest.iter().map(|s| s.error).fold(0.0, f32::max))
    }

    /// The finest level with at most `triangles` triangles, as a compact mesh (the base
    /// mesh when even that has more).
    pub fn mesh_at_triangles(&self, triangles: usize) -> Result<Mesh> {
        Ok(self
            .cursor_at(self.splits_for_triangles(triangles))?
            .to_mesh())
    }

    /// The coarsest level made only of collapses with an error of at most `error`
    /// metres, as a compact mesh.
    pub fn mesh_at_error(&self, error: f32) -> Result<Mesh> {
        Ok(self.cursor_at(self.splits_for_error(error)?)?.to_mesh())
    }

    /// A chain of levels, finest (the original) first: each has about `ratio` times the
    /// triangles of the one before, down to `min_triangles` or the base mesh. An `Err`
    /// when `ratio` is not strictly between 0 and 1.
    pub fn levels(&self, ratio: f32, min_triangles: usize) -> Result<Vec<Level>> {
        if !(ratio > 0.0 && ratio < 1.0) {
            return Err(Error::Invalid(format!(
                "LOD ratio {ratio} is not between 0 and 1"
            )));
        }
        let mut cuts = vec![self.splits.len()];
        let mut count = self.triangles_after(self.splits.len());
        while count > min_triangles {
            let target = ((count as f64 * ratio as f64) as usize).max(min_triangles);
            let k = self.splits_for_triangles(target);
            let reached = self.triangles_after(k);
            if reached >= count {
                break;
            }
            cuts.push(k);
            count = reached;
            if k == 0 {
                break;
            }
        }
        // One walk up from the base, taking each level as it passes.
        let mut cursor = self.cursor()?;
        let mut levels = Vec::with_capacity(cuts.len());
        for &k in cuts.iter().rev() {
            cursor.seek(k)?;
            levels.push(Level {
                mesh: cursor.to_mesh(),
                splits: k,
                error: self.error_after(k),
            });
        }
        levels.reverse();
        Ok(levels)
    }
}

impl<'a> PmCursor<'a> {
    /// How many splits are applied.
    pub fn applied(&self) -> usize {
        self.applied
    }

    /// The number of triangles of the current level.
    pub fn triangle_count(&self) -> usize {
        self.mesh.triangle_count()
    }

    /// The current level, slot by slot.
    pub fn mesh(&self) -> &SelectiveMesh {
        &self.mesh
    }

    /// The current level as a compact mesh.
    pub fn to_mesh(&self) -> Mesh {
        self.mesh.to_mesh()
    }

    /// Applies the next position split (one split, or a run that goes together).
    /// `Ok(false)` at the full mesh; an `Err`, and no change, when a split does not apply.
    pub fn refine(&mut self) -> Result<bool> {
        let splits = &self.pm.splits;
        if self.applied == splits.len() {
            return Ok(false);
        }
        let start = self.applied;
        loop {
            if let Err(e) = self.mesh.split(self.applied, &splits[self.applied]) {
                self.rewind(start);
                return Err(e);
            }
            self.applied += 1;
            if self.pm.is_level_boundary(self.applied) {
                return Ok(true);
            }
        }
    }

    /// Undoes the last position split. `Ok(false)` at the base mesh; an `Err`, and no
    /// change, when a collapse does not apply.
    pub fn coarsen(&mut self) -> Result<bool> {
        if self.applied == 0 {
            return Ok(false);
        }
        let start = self.applied;
        loop {
            let i = self.applied - 1;
            if let Err(e) = self.mesh.collapse(i, &self.pm.splits[i]) {
                self.replay(start);
                return Err(e);
            }
            self.applied = i;
            if self.pm.is_level_boundary(i) {
                return Ok(true);
            }
        }
    }

    /// Refines or coarsens to exactly `splits` splits, which must be a level boundary.
    pub fn seek(&mut self, splits: usize) -> Result<()> {
        if splits > self.pm.splits.len() || !self.pm.is_level_boundary(splits) {
            return Err(Error::Invalid(format!(
                "{splits} splits is not a level of this progressive mesh ({} splits)",
                self.pm.splits.len()
            )));
        }
        while self.applied < splits {
            self.refine()?;
        }
        while self.applied > splits {
            self.coarsen()?;
        }
        Ok(())
    }

    /// Collapses back to `applied == start` after a failed refinement. The splits being
    /// undone were just applied, so their collapses apply.
    fn rewind(&mut self, start: usize) {
        while self.applied > start {
            self.applied -= 1;
            let _ = self
                .mesh
                .collapse(self.applied, &self.pm.splits[self.applied]);
        }
    }

    /// Splits forward to `applied == end` after a failed coarsening.
    fn replay(&mut self, end: usize) {
        while self.applied < end {
            let _ = self.mesh.split(self.applied, &self.pm.splits[self.applied]);
            self.applied += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::fixtures::{
        building, check_exact, check_level, cube, flat_cube, grid, random_patch,
    };

    /// Checks a spread of levels of `m`'s progressive mesh, and every one for small meshes.
    fn check_levels(m: &Mesh) -> ProgressiveMesh {
        let pm = ProgressiveMesh::build(m).unwrap();
        let n = pm.splits.len();
        let step = (n / 40).max(1);
        for k in (0..=n).step_by(step).chain([n]) {
            let k = pm.splits_for_triangles(pm.triangles_after(k));
            check_level(m, &pm, k);
        }
        pm
    }

    #[test]
    fn every_level_is_a_clean_mesh() {
        check_levels(&crate::scene::bunny());
        check_levels(&building());
        check_levels(&flat_cube([0.0, 0.0, 0.0], 2));
        let mut two = cube([-3.0, 0.0, 0.0], 2);
        two.append(&cube([3.0, 0.5, 0.0], 1));
        check_levels(&two);
        check_levels(&grid(9));
    }

    #[test]
    fn random_patches_refine_exactly_and_every_level_is_clean() {
        let (mut runs, mut one_sided, mut coarse) = (0, 0, 0);
        for seed in 0..48 {
            let m = random_patch(seed);
            let pm = ProgressiveMesh::build(&m).unwrap();
            check_exact(&m, &pm);
            runs += pm.splits.iter().filter(|s| s.joins_previous).count();
            one_sided += pm
                .splits
                .iter()
                .filter(|s| s.added_triangles() == 1)
                .count();
            coarse += (pm.base.triangle_count() * 2 < m.triangle_count()) as usize;
            for k in 0..=pm.splits.len() {
                if pm.is_level_boundary(k) {
                    check_level(&m, &pm, k);
                }
            }
            assert_eq!(pm, ProgressiveMesh::build(&m).unwrap(), "seed {seed}");
        }
        // The patches do exercise seams and boundaries, and holes, seams and all, every
        // one at least halves.
        assert!(
            runs > 100 && one_sided > 100 && coarse == 48,
            "{runs} {one_sided} {coarse}"
        );
    }

    #[test]
    fn bunny_levels_stay_close_to_the_original() {
        let bunny = crate::scene::bunny();
        let pm = ProgressiveMesh::build(&bunny).unwrap();
        let (lo, hi) = bunny.bounds();
        let diagonal = glam::Vec3::from(hi).distance(glam::Vec3::from(lo));
        // Hausdorff distance over the bounding-box diagonal, with room above what the
        // build gives today (0.34 %, 2.0 %, 7.9 %).
        for (share, bound) in [(0.5, 0.005), (0.1, 0.03), (0.01, 0.10)] {
            let n = (bunny.triangle_count() as f64 * share).round() as usize;
            let level = pm.mesh_at_triangles(n).unwrap();
            let d = crate::lod::hausdorff(&bunny, &level, 20_000).unwrap() / diagonal;
            eprintln!(
                "bunny at {n} triangles: {} triangles, Hausdorff {:.2} % of the diagonal",
                level.triangle_count(),
                100.0 * d
            );
            assert!(
                level.triangle_count() * 10 >= n * 9,
                "{n}: {}",
                level.triangle_count()
            );
            assert!(d < bound, "{share}: {d}");
        }
    }

    #[test]
    fn levels_by_count_and_by_error() {
        let bunny = crate::scene::bunny();
        let pm = ProgressiveMesh::build(&bunny).unwrap();
        for n in [0, 1, 10, 100, 1000, 3000, 3674, 10_000] {
            let m = pm.mesh_at_triangles(n).unwrap();
            assert!(m.triangle_count() <= n.max(pm.base.triangle_count()), "{n}");
            // The next position split would pass n.
            let k = pm.splits_for_triangles(n);
            if k < pm.splits.len() {
                assert!(pm.triangles_after(k + 1) > n);
            }
        }
        assert_eq!(pm.mesh_at_triangles(10_000).unwrap().triangle_count(), 3674);
        assert_eq!(pm.mesh_at_triangles(0).unwrap(), pm.base);

        let mut previous = usize::MAX;
        for e in [0.0, 0.001, 0.01, 0.03, 0.1, 0.3, 1.0, 10.0] {
            let k = pm.splits_for_error(e).unwrap();
            assert!(pm.error_after(k) <= e, "{e}");
            assert!(k <= previous, "a larger error never gives a finer level");
            previous = k;
            assert_eq!(
                pm.mesh_at_error(e).unwrap().triangle_count(),
                pm.triangles_after(k)
            );
        }
        assert_eq!(pm.mesh_at_error(0.0).unwrap().triangle_count(), 3674);
        assert!(pm.mesh_at_error(f32::NAN).is_err());
    }

    #[test]
    fn chain_halves_down_to_the_floor() {
        let bunny = crate::scene::bunny();
        let pm = ProgressiveMesh::build(&bunny).unwrap();
        let chain = pm.levels(0.5, 100).unwrap();
        assert_eq!(chain[0].mesh.triangle_count(), 3674);
        assert_eq!(chain[0].error, 0.0);
        for w in chain.windows(2) {
            let (fine, coarse) = (w[0].mesh.triangle_count(), w[1].mesh.triangle_count());
            // About half, or the floor when half would pass it.
            assert!(
                coarse <= (fine / 2 + 1).max(100) && coarse * 2 + 4 >= fine,
                "{fine} → {coarse}"
            );
            assert!(w[1].error >= w[0].error);
        }
        assert!(chain.last().unwrap().mesh.triangle_count() <= 100);
        assert!(chain.len() >= 5);
        for level in &chain {
            assert_eq!(level.mesh, pm.cursor_at(level.splits).unwrap().to_mesh());
        }
        assert!(pm.levels(1.0, 10).is_err());
        assert!(pm.levels(0.0, 10).is_err());
        assert!(pm.levels(f32::NAN, 10).is_err());
    }

    #[test]
    fn refine_and_coarsen_walk_both_ways() {
        let b = building();
        let pm = ProgressiveMesh::build(&b).unwrap();
        let mut cursor = pm.cursor().unwrap();
        let base = cursor.mesh().clone();
        let mut steps = 0;
        while cursor.refine().unwrap() {
            steps += 1;
            assert!(pm.is_level_boundary(cursor.applied()));
        }
        assert_eq!(cursor.applied(), pm.splits.len());
        assert!(
            steps < pm.splits.len(),
            "creases split several vertices in one step"
        );
        assert_eq!(cursor.triangle_count(), b.triangle_count());
        while cursor.coarsen().unwrap() {}
        assert_eq!(cursor.mesh(), &base);

        let inside = (1..pm.splits.len())
            .find(|&k| !pm.is_level_boundary(k))
            .unwrap();
        assert!(pm.cursor_at(inside).is_err());
        assert!(pm.cursor_at(pm.splits.len() + 1).is_err());
    }

    #[test]
    fn a_damaged_split_is_an_error_and_the_cursor_stays() {
        let mut pm = ProgressiveMesh::build(&crate::scene::bunny()).unwrap();
        pm.splits[5].adjusted.push(0);
        pm.splits[5].adjusted.push(u32::MAX);
        let mut cursor = pm.cursor_at(5).unwrap();
        let before = cursor.mesh().clone();
        assert!(cursor.refine().is_err());
        assert_eq!(cursor.applied(), 5);
        assert_eq!(cursor.mesh(), &before);
        assert!(pm.mesh_at_triangles(5000).is_err());
        pm.base.indices[0] = 1_000_000;
        assert!(pm.cursor().is_err());
        assert!(pm.mesh_at_triangles(0).is_err());
    }
}
