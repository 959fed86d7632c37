//! `flaneur lod`: the LOD core on one mesh file, its levels written or one view's
//! selective mesh measured.

use crate::cli::args::{lod_ratio, tau};
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;

use super::args::{parse_fov_degrees, parse_vec3};

/// `flaneur lod`'s arguments.
#[derive(clap::Args)]
pub struct LodArgs {
    /// An OBJ file; its objects are simplified together as disjoint pieces.
    mesh: PathBuf,
    /// Write level-0.obj (the original), level-1.obj, … into this folder (default:
    /// none; --out or --refine is needed).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Triangles of each level over the one before, within (0, 1) (as `build` stores
    /// them).
    #[arg(long, default_value_t = flaneur::lod::LodOptions::default().ratio, value_parser = lod_ratio, allow_negative_numbers = true)]
    ratio: f32,
    /// Stop the chain of levels at this many triangles.
    #[arg(long, default_value_t = flaneur::lod::LodOptions::default().min_triangles)]
    min_triangles: usize,
    /// Refine view-dependently for one view instead.
    #[arg(long)]
    refine: bool,
    /// The eye, x,y,z: with --refine, and then needed.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    eye: Option<glam::Vec3>,
    /// The point looked at, x,y,z: with --refine, and then needed.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    look: Option<glam::Vec3>,
    /// Screen-space error, a fraction of the viewport within (0, 1) (the thesis's:
    /// 0.001).
    #[arg(long, default_value_t = 0.001, value_parser = tau, allow_negative_numbers = true)]
    tau: f32,
    /// Full apex angle of the view cone, degrees.
    #[arg(long, default_value_t = 60.0, value_parser = parse_fov_degrees)]
    fov: f32,
}

impl LodArgs {
    /// Writes the levels or measures the view, and prints the figures.
    pub fn run(self) -> Result<()> {
        let LodArgs {
            mesh,
            out,
            ratio,
            min_triangles,
            refine,
            eye,
            look,
            tau,
            fov,
        } = self;
        lod(
            &mesh,
            out.as_deref(),
            ratio,
            min_triangles,
            refine.then_some((eye, look, tau, fov)),
        )
    }
}

type RefineArgs = (Option<glam::Vec3>, Option<glam::Vec3>, f32, f32);

fn lod(
    mesh: &Path,
    out: Option<&Path>,
    ratio: f32,
    min_triangles: usize,
    refine: Option<RefineArgs>,
) -> Result<()> {
    let m = super::lod_inspect::load_merged(mesh)?;
    match (refine, out) {
        (Some((Some(eye), Some(look), tau, fov)), _) => {
            let t = Instant::now();
            let r = super::lod_inspect::refine_view(&m, eye, look, fov.to_radians(), tau)?;
            println!(
                "{}: {} of {} triangles ({} vertices) for the view from {eye} towards {look}, tau {tau}; \
                 Hausdorff distance to the original {:.4} m; settled in {} frames, {:.2} s with the build",
                mesh.display(),
                r.triangles,
                r.original_triangles,
                r.vertices,
                r.hausdorff,
                r.frames,
                t.elapsed().as_secs_f64()
            );
            Ok(())
        }
        (Some(_), _) => Err(flaneur::Error::Invalid(
            "--refine needs --eye x,y,z and --look x,y,z".into(),
        )
        .into()),
        (None, Some(out)) => {
            let t = Instant::now();
            let levels = super::lod_inspect::write_levels(&m, out, ratio, min_triangles)?;
            for l in &levels {
                println!(
                    "{}: {} triangles, error {:.5} m",
                    l.path.display(),
                    l.triangles,
                    l.error
                );
            }
            println!(
                "{} levels in {:.2} s",
                levels.len(),
                t.elapsed().as_secs_f64()
            );
            Ok(())
        }
        (None, None) => Err(flaneur::Error::Invalid(
            "give --out DIR for the levels, or --refine with --eye and --look".into(),
        )
        .into()),
    }
}
