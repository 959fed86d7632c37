//! What `flaneur lod` does: a mesh file's levels written out as OBJ for inspection, and
//! one view's selective mesh measured — the LOD core run on a user's own model. The
//! command's own work, beside the arguments and the printing (`lod.rs`): it measures
//! no experiment, so it lives with the command rather than among the benches.

use std::io::Write;
use std::path::{Path, PathBuf};

use glam::Vec3;

use flaneur::error::{Error, Result};
use flaneur::lod::{
    hausdorff, Dag, DagConstruction, ProgressiveMesh, RefineParams, Refiner, Traversal, View,
};
use flaneur::scene::{load_obj, write_mesh_obj, Mesh};

/// Every object of an OBJ file merged into one mesh of disjoint pieces (the progressive
/// mesh keeps the pieces apart).
pub fn load_merged(path: &Path) -> Result<Mesh> {
    let mut merged = Mesh::default();
    for (_, mesh) in load_obj(path)? {
        merged.append(&mesh);
    }
    Ok(merged)
}

/// One level written by [`write_levels`].
#[derive(Clone, Debug)]
pub struct LevelFile {
    pub path: PathBuf,
    pub triangles: usize,
    /// The largest collapse error that made it (metres).
    pub error: f32,
}

/// Builds `mesh`'s progressive mesh and writes its chain of levels (each about `ratio`
/// times the triangles of the one before, down to `min_triangles`) as `level-N.obj` in
/// `out`, level 0 the original.
pub fn write_levels(
    mesh: &Mesh,
    out: &Path,
    ratio: f32,
    min_triangles: usize,
) -> Result<Vec<LevelFile>> {
    let pm = ProgressiveMesh::build(mesh)?;
    // The levels first: options they refuse leave no folder behind.
    let levels = pm.levels(ratio, min_triangles)?;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let mut files = Vec::new();
    for (i, level) in levels.into_iter().enumerate() {
        let path = out.join(format!("level-{i}.obj"));
        write_obj(
            &path,
            &level.mesh,
            &format!(
                "level {i}: {} triangles, error {} m",
                level.mesh.triangle_count(),
                level.error
            ),
        )?;
        files.push(LevelFile {
            path,
            triangles: level.mesh.triangle_count(),
            error: level.error,
        });
    }
    Ok(files)
}

/// One mesh as an OBJ file (positions, normals, faces), with a comment line.
pub fn write_obj(path: &Path, mesh: &Mesh, comment: &str) -> Result<()> {
    let file = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
    let mut w = std::io::BufWriter::new(file);
    let mut body = || -> std::io::Result<()> {
        writeln!(w, "# {comment}")?;
        write_mesh_obj(&mut w, mesh, 1)?;
        w.flush()
    };
    body().map_err(|e| Error::io(path, e))
}

/// The selective mesh of one view, as [`refine_view`] measures it.
#[derive(Clone, Debug)]
pub struct ViewRefinement {
    pub original_triangles: usize,
    pub triangles: usize,
    pub vertices: usize,
    /// Frames the priority traversal took to settle (it does at most N operations each).
    pub frames: usize,
    /// Sampled symmetric Hausdorff distance to the original mesh, metres (the whole
    /// mesh, so parts out of view or facing away count at their coarse level).
    pub hausdorff: f32,
}

/// How many frames [`refine_view`] gives the refinement to settle.
const MAX_SETTLE_FRAMES: usize = 10_000;

/// Refines `mesh` for the view from `eye` towards the point `look_at` (cone of `fov`
/// radians, screen-space error `tau` as a fraction of the viewport), with the
/// priority-oriented traversal and no triangle budget, until a frame changes nothing.
pub fn refine_view(
    mesh: &Mesh,
    eye: Vec3,
    look_at: Vec3,
    fov: f32,
    tau: f32,
) -> Result<ViewRefinement> {
    let view = View::new(eye, look_at - eye, fov)?;
    let pm = ProgressiveMesh::build(mesh)?;
    let dag = Dag::build(&pm, DagConstruction::MiniRedundant)?;
    let mut refiner = Refiner::new(&pm, &dag)?;
    let params = RefineParams {
        tau,
        budget: None,
        ..RefineParams::thesis(Traversal::Priority)
    };
    params.validate()?;
    let mut frames = 0;
    loop {
        frames += 1;
        let report = refiner.refine(&view, &params)?;
        if report.stats.updates() == 0 || frames >= MAX_SETTLE_FRAMES {
            break;
        }
    }
    let selective = refiner.mesh().to_mesh();
    Ok(ViewRefinement {
        original_triangles: mesh.triangle_count(),
        triangles: selective.triangle_count(),
        vertices: selective.positions.len(),
        frames,
        hausdorff: hausdorff(&selective, mesh, 100_000)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_view_refines_the_bunny_near_the_eye_more_than_a_far_one() {
        let bunny = flaneur::scene::bunny();
        let centre = Vec3::new(0.0, 5.0, 0.0);
        let near = refine_view(
            &bunny,
            centre + Vec3::new(0.0, 0.0, 20.0),
            centre,
            1.0,
            0.001,
        )
        .unwrap();
        let far = refine_view(
            &bunny,
            centre + Vec3::new(0.0, 0.0, 2000.0),
            centre,
            1.0,
            0.001,
        )
        .unwrap();
        assert!(near.triangles > far.triangles, "near {near:?}\nfar {far:?}");
        assert!(near.triangles <= bunny.triangle_count());
        assert!(near.hausdorff < far.hausdorff, "near {near:?}\nfar {far:?}");
    }

    #[test]
    fn bad_views_are_errors() {
        let bunny = flaneur::scene::bunny();
        assert!(refine_view(&bunny, Vec3::ZERO, Vec3::ZERO, 1.0, 0.001).is_err());
        assert!(refine_view(&bunny, Vec3::Z * 20.0, Vec3::ZERO, 1.0, 0.0).is_err());
        assert!(refine_view(&bunny, Vec3::NAN, Vec3::ZERO, 1.0, 0.001).is_err());
        assert!(write_levels(&bunny, Path::new("."), 1.5, 10).is_err());
    }

    #[test]
    fn each_level_is_coarser_than_the_one_before() {
        let dir = tempfile::tempdir().unwrap();
        let levels = write_levels(&flaneur::scene::bunny(), dir.path(), 0.25, 50).unwrap();
        assert_eq!(levels[0].triangles, 3674);
        assert!(levels.windows(2).all(|w| w[1].triangles < w[0].triangles));
        assert!(levels.iter().all(|l| l.path.exists()));
    }

    #[test]
    fn written_levels_load_back() {
        let dir = tempfile::tempdir().unwrap();
        let levels = write_levels(&flaneur::scene::bunny(), dir.path(), 0.5, 200).unwrap();
        for l in &levels {
            let back = load_merged(&l.path).unwrap();
            assert_eq!(back.triangle_count(), l.triangles, "{}", l.path.display());
        }
    }
}
