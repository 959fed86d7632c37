//! `flaneur shot`: one picture of the city drawn headless.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;

use super::args::{parse_fov_degrees, parse_look, parse_size, parse_vec3};
use super::source::SourceArgs;

/// `flaneur shot`'s arguments.
#[derive(clap::Args)]
pub struct ShotArgs {
    /// The database: a file, or a URL (http://… or https://…) on any HTTP server.
    db: PathBuf,
    /// The eye: x,y,z in metres.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    at: glam::Vec3,
    /// Heading and elevation in degrees: yaw,pitch (yaw 0 looks along +x, 90 along
    /// +z; pitch positive looks up).
    #[arg(long, value_parser = parse_look, default_value = "0,0", allow_hyphen_values = true)]
    look: (f32, f32),
    /// Image size, WIDTHxHEIGHT pixels.
    #[arg(long, value_parser = parse_size, default_value = "960x540")]
    size: (u32, u32),
    /// Vertical field of view, degrees.
    #[arg(long, default_value_t = 60.0, value_parser = parse_fov_degrees)]
    fov: f32,
    /// The PNG file to write.
    #[arg(short, long, value_name = "PNG", default_value = "shot.png")]
    out: PathBuf,
    #[command(flatten)]
    source: SourceArgs,
}

impl ShotArgs {
    /// Draws the picture, saves it as PNG and prints what it cost.
    pub fn run(self) -> Result<()> {
        let ShotArgs {
            db,
            at,
            look,
            size,
            fov,
            out,
            source,
        } = self;
        let db = source.open(&db)?;
        let camera = flaneur::geom::Camera::new(at, look.0.to_radians(), look.1.to_radians())?
            .with_fov(fov.to_radians(), fov.to_radians())?
            .fitted_to(size.0 as f32 / size.1 as f32)?;
        let gpu = flaneur_render::Gpu::headless()?;
        // Every object in view, at full detail.
        let started = Instant::now();
        let mut meshes = Vec::new();
        for o in db.in_view(&camera)? {
            meshes.push((o.id, db.mesh(&o)?));
        }
        let select = started.elapsed();
        let s = flaneur_render::shot(&gpu, &camera, &db.bounds(), &meshes, size.0, size.1)?;
        s.frame.save_png(&out)?;
        println!(
            "{}: {} × {} on {} ({:?}); {} objects, {} triangles, {:.1} MiB on the GPU; \
             select {:.1} ms, upload {:.1} ms, draw and read back {:.1} ms",
            out.display(),
            size.0,
            size.1,
            gpu.adapter.name,
            gpu.adapter.backend,
            s.objects,
            s.triangles,
            s.gpu_bytes as f64 / 1048576.0,
            select.as_secs_f64() * 1e3,
            s.upload.as_secs_f64() * 1e3,
            s.draw.as_secs_f64() * 1e3
        );
        Ok(())
    }
}
