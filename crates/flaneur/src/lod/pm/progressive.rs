//! Progressive mesh construction — Hoppe's PM (Zheng 2007 §2.2.1) built from half-edge
//! collapses (§2.1.1) ordered by the quadric error metric (Garland & Heckbert, §2.1.2),
//! recorded as vertex splits in the form of §3.2, Fig. 3.5.
//!
//! The collapses themselves — their order, the rules that make one legal and the
//! choices the papers leave open (creases and seams, boundaries, normals, the error's
//! unit) — are `simplify`'s; this module renumbers them into the splits of Fig. 3.5's
//! implicit indices, and builds many meshes at once.

use rayon::prelude::*;

use crate::scene::Mesh;

use super::simplify::{Collapse, Domain, Setup, Simplifier};
use super::vsplit::{SplitIds, VertexSplit};
use crate::error::{Error, Result};

/// A mesh as a coarse base mesh and the vertex splits that refine it back to the
/// original, exactly (Zheng 2007 §2.2.1, §3.2).
///
/// Vertices are renumbered so that the base mesh's come first and split `i` creates
/// vertex `i + base vertices`; split `i` creates triangles `2i + base triangles` (f_l)
/// and `2i + 1 + base triangles` (f_r). `vertex_map` and `triangle_map` take the
/// original mesh's numbers to these. Applying every split to the base gives back the
/// original mesh, vertex for vertex and triangle for triangle, through the maps.
///
/// ```
/// use flaneur::lod::ProgressiveMesh;
/// let bunny = flaneur::scene::bunny();
/// let pm = ProgressiveMesh::build(&bunny)?;
/// assert!(pm.base.triangle_count() < bunny.triangle_count() / 20);
///
/// // A plain mesh of at most 1,000 triangles, and the error it was simplified to.
/// let level = pm.mesh_at_triangles(1000)?;
/// assert!(level.triangle_count() <= 1000 && level.validate().is_ok());
/// let error = pm.error_after(pm.splits_for_triangles(1000));
/// assert!(error > 0.0 && error < 0.1, "{error} m");
///
/// // Refining the base by every split restores the original, through the renumbering.
/// let full = pm.cursor_at(pm.splits.len())?;
/// assert_eq!(full.triangle_count(), bunny.triangle_count());
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ProgressiveMesh {
    /// The coarsest mesh: every vertex no split creates (unused ones too), and every
    /// triangle no split creates, in the original order.
    pub base: Mesh,
    /// The vertex splits, coarse to fine.
    pub splits: Vec<VertexSplit>,
    /// The renumbered index of each original vertex.
    pub vertex_map: Vec<u32>,
    /// The triangle slot of each original triangle.
    pub triangle_map: Vec<u32>,
}

impl ProgressiveMesh {
    /// Simplifies `mesh` as far as legal collapses go, recording each collapse as a
    /// vertex split.
    ///
    /// An `Error::Invalid` when the mesh fails `Mesh::validate` (a NaN, an index out of
    /// range), has no triangles, or is too large for 32-bit triangle slots.
    pub fn build(mesh: &Mesh) -> Result<ProgressiveMesh> {
        check_input(mesh)?;
        let mut s = Simplifier::new(mesh, Setup::of(mesh), Domain::everything());
        s.run();
        let (collapses, adj) = (s.collapses, s.adj);
        Ok(assemble(mesh, &collapses, &adj.faces, &adj.alive))
    }

    /// The number of vertices of the fully refined mesh (the original's).
    pub fn vertex_count(&self) -> usize {
        self.base.positions.len() + self.splits.len()
    }

    /// The number of triangle slots: the base's and two per split.
    pub fn triangle_slots(&self) -> usize {
        self.base.triangle_count() + 2 * self.splits.len()
    }

    /// The implicit indices of split `index` (Zheng Fig. 3.5).
    pub fn ids(&self, index: usize) -> SplitIds {
        SplitIds::new(index, self.base.positions.len(), self.base.triangle_count())
    }
}

/// Whether `mesh` can be simplified: valid, with triangles, and small enough for
/// 32-bit triangle slots.
pub(super) fn check_input(mesh: &Mesh) -> Result<()> {
    mesh.validate()
        .map_err(|e| Error::Invalid(format!("mesh: {e}")))?;
    if mesh.indices.is_empty() {
        return Err(Error::Invalid("mesh: no triangles to simplify".into()));
    }
    // Slots run to base + 2 per split, and there are fewer splits than vertices.
    if mesh.triangle_count() as u64 + 2 * mesh.positions.len() as u64 >= u32::MAX as u64 {
        return Err(Error::Invalid(format!(
            "mesh: {} vertices and {} triangles are too many for 32-bit indices",
            mesh.positions.len(),
            mesh.triangle_count()
        )));
    }
    Ok(())
}

/// Builds the progressive meshes of many objects on all cores, in the order given.
///
/// An error names the first mesh (by position in `meshes`) that could not be built.
///
/// ```
/// let meshes = vec![flaneur::scene::bunny(), flaneur::scene::bunny()];
/// let pms = flaneur::lod::simplify_all(&meshes)?;
/// assert_eq!(pms[0], pms[1]);
/// # Ok::<(), flaneur::Error>(())
/// ```
pub fn simplify_all(meshes: &[Mesh]) -> Result<Vec<ProgressiveMesh>> {
    meshes
        .par_iter()
        .enumerate()
        .map(|(i, m)| {
            ProgressiveMesh::build(m).map_err(|e| match e {
                Error::Invalid(what) => Error::Invalid(format!("object {i}: {what}")),
                other => other,
            })
        })
        .collect()
}

/// Renumbers (Fig. 3.5's implicit indices) and turns the collapses of `mesh`, made in
/// order, into splits; `faces` and `alive` are the triangles after the last collapse.
pub(super) fn assemble(
    mesh: &Mesh,
    collapses: &[Collapse],
    faces: &[[u32; 3]],
    alive: &[bool],
) -> ProgressiveMesh {
    let nv = mesh.positions.len();
    let nt = mesh.triangle_count();
    let m = collapses.len();
    // Split i undoes collapse m − 1 − i.
    let in_split_order = || collapses.iter().rev();

    let mut split_vertex = vec![false; nv];
    for rec in collapses {
        split_vertex[rec.v_c as usize] = true;
    }
    let mut vertex_map = vec![u32::MAX; nv];
    let mut base = Mesh::default();
    for v in (0..nv).filter(|&v| !split_vertex[v]) {
        vertex_map[v] = base.positions.len() as u32;
        base.positions.push(mesh.positions[v]);
        base.normals.push(mesh.normals[v]);
    }
    let base_vertices = base.positions.len();
    for (i, rec) in in_split_order().enumerate() {
        vertex_map[rec.v_c as usize] = (base_vertices + i) as u32;
    }

    let mut triangle_map = vec![u32::MAX; nt];
    let mut base_triangles = 0u32;
    for f in (0..nt).filter(|&f| alive[f]) {
        triangle_map[f] = base_triangles;
        base_triangles += 1;
        base.indices
            .extend(faces[f].iter().map(|&v| vertex_map[v as usize]));
    }
    for (i, rec) in in_split_order().enumerate() {
        let ids = SplitIds::new(i, base_vertices, base_triangles as usize);
        if let Some(l) = rec.left {
            triangle_map[l.face as usize] = ids.f_l;
        }
        if let Some(r) = rec.right {
            triangle_map[r.face as usize] = ids.f_r;
        }
    }

    let mut splits = Vec::with_capacity(m);
    let mut previous_group = None;
    for rec in in_split_order() {
        let mut adjusted: Vec<u32> = rec
            .adjusted
            .iter()
            .map(|&f| triangle_map[f as usize])
            .collect();
        adjusted.sort_unstable();
        splits.push(VertexSplit {
            v_p: vertex_map[rec.v_p as usize],
            position: mesh.positions[rec.v_c as usize],
            normal: mesh.normals[rec.v_c as usize],
            v_l: rec.left.map(|l| vertex_map[l.pivot as usize]),
            v_r: rec.right.map(|r| vertex_map[r.pivot as usize]),
            adjusted,
            corners: [
                rec.left.map_or(0, |l| l.corner),
                rec.right.map_or(0, |r| r.corner),
            ],
            error: rec.error,
            joins_previous: previous_group == Some(rec.group),
        });
        previous_group = Some(rec.group);
    }
    ProgressiveMesh {
        base,
        splits,
        vertex_map,
        triangle_map,
    }
}

#[cfg(test)]
mod tests {
    use std::time::Instant;

    use glam::DVec3;

    use super::*;
    use crate::lod::fixtures::{
        boundary_length, building, check_exact, cube, duplicate_triangles, flat_cube, grid,
    };
    use crate::lod::pm::topology::Adjacency;

    #[test]
    fn bunny_refines_back_exactly() {
        let bunny = crate::scene::bunny();
        let started = Instant::now();
        let pm = ProgressiveMesh::build(&bunny).unwrap();
        let took = started.elapsed();
        eprintln!(
            "bunny: {} → {} triangles, {} splits, {:.1} ms, {:.0} triangles/s",
            bunny.triangle_count(),
            pm.base.triangle_count(),
            pm.splits.len(),
            took.as_secs_f64() * 1e3,
            bunny.triangle_count() as f64 / took.as_secs_f64()
        );
        // A closed genus-0 surface simplifies down to a handful of triangles.
        assert!(
            pm.base.triangle_count() <= 8,
            "{}",
            pm.base.triangle_count()
        );
        assert!(
            pm.splits.iter().all(|s| !s.joins_previous),
            "the bunny has no seams"
        );
        assert!(
            pm.splits.iter().all(|s| s.v_l.is_some() && s.v_r.is_some()),
            "nor any boundary"
        );
        check_exact(&bunny, &pm);
    }

    #[test]
    fn building_refines_back_exactly_and_keeps_its_creases() {
        let b = building();
        let pm = ProgressiveMesh::build(&b).unwrap();
        eprintln!(
            "building: {} → {} triangles, {} splits",
            b.triangle_count(),
            pm.base.triangle_count(),
            pm.splits.len()
        );
        assert!(
            pm.base.triangle_count() < b.triangle_count() / 2,
            "{}",
            pm.base.triangle_count()
        );
        assert!(
            pm.splits.iter().any(|s| s.joins_previous),
            "creases move several vertices at once"
        );
        check_exact(&b, &pm);
        // A crack would add boundary; legal collapses never lengthen it.
        let original = boundary_length(&b);
        let base = boundary_length(&pm.base);
        assert!(
            base <= original * (1.0 + 1e-6) + 1e-6,
            "{base} > {original}"
        );
    }

    #[test]
    fn flat_shaded_cube_keeps_its_creases_and_corners() {
        let m = flat_cube([0.0; 3], 3);
        let pm = ProgressiveMesh::build(&m).unwrap();
        check_exact(&m, &pm);
        // Every collapse that keeps the creases costs nothing on a cube; the first that
        // crosses one costs at least its edge.
        let k = pm.splits_for_error(1e-3).unwrap();
        assert!(
            pm.splits[..k].iter().all(|s| s.error >= 0.25),
            "{:?}",
            &pm.splits[..k]
        );
        let base = &pm.cursor_at(k).unwrap().to_mesh();
        assert_eq!(base.triangle_count(), 12, "two triangles per side");
        assert_eq!(boundary_length(base), 0.0);
        for t in base.indices.chunks_exact(3) {
            let p = |i: u32| DVec3::from(base.positions[i as usize].map(|c| c as f64));
            let n = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).normalize();
            for &v in t {
                let vn = DVec3::from(base.normals[v as usize].map(|c| c as f64));
                assert!(vn.dot(n) > 0.9999, "a side took a neighbour's normal");
            }
        }
        let corners = base
            .positions
            .iter()
            .filter(|p| p.iter().all(|c| c.abs() == 1.0))
            .count();
        assert_eq!(corners, 24, "8 corners × 3 sides");
        eprintln!("flat cube: base {} triangles", pm.base.triangle_count());
        assert_eq!(boundary_length(&pm.base), 0.0);
    }

    #[test]
    fn disjoint_pieces_stay_apart() {
        let mut two = cube([-5.0, 0.0, 0.0], 2);
        two.append(&cube([5.0, 0.0, 0.0], 2));
        let pm = ProgressiveMesh::build(&two).unwrap();
        check_exact(&two, &pm);
        for k in [0, pm.splits.len() / 3, pm.splits.len() / 2, pm.splits.len()] {
            let k = pm.splits_for_triangles(pm.triangles_after(k));
            let level = pm.cursor_at(k).unwrap().to_mesh();
            let mut sides = [0; 2];
            for t in level.indices.chunks_exact(3) {
                let x = t.iter().map(|&v| level.positions[v as usize][0]);
                let (lo, hi) = x.fold((f32::MAX, f32::MIN), |(lo, hi), x| (lo.min(x), hi.max(x)));
                assert!(hi < 0.0 || lo > 0.0, "a triangle spans both cubes");
                sides[(lo > 0.0) as usize] += 1;
            }
            assert!(
                sides[0] >= 4 && sides[1] >= 4,
                "a piece vanished: {sides:?}"
            );
        }
    }

    #[test]
    fn open_grid_keeps_its_outline() {
        let n = 16;
        let m = grid(n);
        let pm = ProgressiveMesh::build(&m).unwrap();
        check_exact(&m, &pm);
        let side = n as f32;
        // Only the last collapse, of one triangle of the square, cuts a corner.
        let flat = pm.splits_for_error(1e-4).unwrap();
        assert_eq!(
            pm.triangles_after(flat),
            2,
            "a flat square is two triangles"
        );
        let half = (flat + pm.splits.len()) / 2;
        for k in [
            flat,
            pm.splits_for_triangles(pm.triangles_after(half)),
            pm.splits.len(),
        ] {
            let level = pm.cursor_at(k).unwrap().to_mesh();
            assert!(
                (boundary_length(&level) - 4.0 * side as f64).abs() < 1e-9,
                "level {k}: boundary {}",
                boundary_length(&level)
            );
            let adj = Adjacency::new(&level);
            for (a, b, _) in adj.boundary_edges() {
                let (a, b) = (adj.coords[a as usize], adj.coords[b as usize]);
                let on = |x: f64, y: f64| {
                    (x == 0.0 && y == 0.0) || (x == side as f64 && y == side as f64)
                };
                assert!(
                    on(a.x, b.x) || on(a.z, b.z),
                    "boundary edge {a} – {b} is off the outline"
                );
            }
            for corner in [
                [0.0, 0.0, 0.0],
                [side, 0.0, 0.0],
                [0.0, 0.0, side],
                [side, 0.0, side],
            ] {
                assert!(level.positions.contains(&corner), "corner {corner:?} lost");
            }
            let area: f64 = level
                .indices
                .chunks_exact(3)
                .map(|t| {
                    let p = |i: u32| DVec3::from(level.positions[i as usize].map(|c| c as f64));
                    0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length()
                })
                .sum();
            assert!((area - (side * side) as f64).abs() < 1e-6, "{area}");
        }
        assert_eq!(pm.base.triangle_count(), 1);
    }

    #[test]
    fn deterministic_and_the_same_in_parallel() {
        let meshes = vec![
            crate::scene::bunny(),
            building(),
            flat_cube([1.0, 2.0, 3.0], 2),
        ];
        let one = ProgressiveMesh::build(&meshes[1]).unwrap();
        assert_eq!(one, ProgressiveMesh::build(&meshes[1]).unwrap());
        let all = simplify_all(&meshes).unwrap();
        for (m, pm) in meshes.iter().zip(&all) {
            assert_eq!(pm, &ProgressiveMesh::build(m).unwrap());
        }
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let good = crate::scene::bunny();
        let mut nan = good.clone();
        nan.positions[10][0] = f32::NAN;
        let e = ProgressiveMesh::build(&nan).unwrap_err().to_string();
        assert!(e.contains("position 10"), "{e}");
        let mut out_of_range = good.clone();
        out_of_range.indices[5] = 99_999;
        let e = ProgressiveMesh::build(&out_of_range)
            .unwrap_err()
            .to_string();
        assert!(e.contains("99999"), "{e}");
        let e = ProgressiveMesh::build(&Mesh::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("no triangles"), "{e}");
        let mut ragged = good.clone();
        ragged.indices.pop();
        assert!(ProgressiveMesh::build(&ragged).is_err());
        let mut few_normals = good.clone();
        few_normals.normals.pop();
        assert!(ProgressiveMesh::build(&few_normals).is_err());
        let e = simplify_all(&[good.clone(), nan]).unwrap_err().to_string();
        assert!(e.contains("object 1"), "{e}");
    }

    #[test]
    fn odd_but_valid_input_builds() {
        // Degenerate triangles, a repeated index, unused vertices, a lone triangle.
        let mut m = grid(3);
        m.positions.push([9.0, 9.0, 9.0]);
        m.normals.push([0.0, 1.0, 0.0]);
        m.indices.extend_from_slice(&[0, 0, 1, 1, 2, 3]);
        let mut lone = grid(1);
        lone.indices.truncate(3);
        m.append(&lone);
        let pm = ProgressiveMesh::build(&m).unwrap();
        check_exact(&m, &pm);
    }

    #[test]
    fn non_manifold_edges_and_duplicate_triangles_stay_put() {
        // A fin: a third triangle on an interior edge of a grid, standing up from it;
        // and a triangle given twice. The fin's edge ends stay until the fin itself has
        // collapsed away (its tip onto an end, along the fin's boundary).
        let mut m = grid(6);
        let (a, b) = (8u32, 9u32);
        m.positions.push([1.5, 2.0, 1.0]);
        m.normals.push([0.0, 0.0, 1.0]);
        let top = m.positions.len() as u32 - 1;
        m.indices.extend_from_slice(&[a, b, top]);
        let first: Vec<u32> = m.indices[..3].to_vec();
        m.indices.extend_from_slice(&first);
        let pm = ProgressiveMesh::build(&m).unwrap();
        check_exact(&m, &pm);
        for k in [0, pm.splits.len() / 2, pm.splits.len()] {
            let level = pm.cursor_at(k).unwrap().to_mesh();
            level.validate().unwrap();
            // The input's duplicate is kept; no collapse makes another.
            assert!(duplicate_triangles(&level) <= 1, "level {k}");
        }
        let (pm2, _) = ProgressiveMesh::build_parallel(
            &m,
            &crate::lod::ParallelOptions {
                leaf_triangles: 8,
                ..Default::default()
            },
        )
        .unwrap();
        check_exact(&m, &pm2);
    }
}
