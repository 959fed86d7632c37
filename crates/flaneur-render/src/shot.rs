//! One picture drawn headless from a viewpoint: the meshes the caller read (for a
//! full-detail picture, those of [`Database::in_view`](flaneur::Database::in_view)),
//! uploaded, drawn and read back.

use std::path::Path;
use std::time::{Duration, Instant};

use crate::{Frame, Gpu, GpuMeshes, Offscreen};
use flaneur::error::{Error, Result};
use flaneur::geom::{Aabb, Camera};
use flaneur::scene::Mesh;

/// What [`shot`] drew.
#[derive(Clone, Debug)]
pub struct Shot {
    pub frame: Frame,
    /// Objects drawn, and their triangles.
    pub objects: usize,
    pub triangles: u64,
    /// GPU memory the objects' meshes took, bytes.
    pub gpu_bytes: u64,
    /// Uploading the objects, and drawing and reading back.
    pub upload: Duration,
    pub draw: Duration,
}

/// Renders `meshes` (each object's id and mesh) as `camera` sees them, over the ground
/// of a city within `city`, into a `width` × `height` frame. `camera` keeps its
/// vertical field of view and has its horizontal one fitted to the image
/// ([`Camera::fitted_to`]): select the meshes with the fitted camera. What it selects
/// is drawn whole, past its far plane, fading into the sky before it
/// ([`Offscreen::render_camera`]).
///
/// ```no_run
/// # fn main() -> flaneur::Result<()> {
/// use flaneur::{geom::Camera, Database};
/// use flaneur_render::{shot, Gpu};
/// let db = Database::open("city.flaneur".as_ref())?;
/// let camera = Camera::new(glam::Vec3::new(100.0, 1.7, 80.0), 0.0, 0.0)?.fitted_to(640.0 / 480.0)?;
/// let mut meshes = Vec::new();
/// for o in db.in_view(&camera)? {
///     meshes.push((o.id, db.mesh(&o)?));
/// }
/// let picture = shot(&Gpu::headless()?, &camera, &db.bounds(), &meshes, 640, 480)?;
/// picture.frame.save_png("shot.png".as_ref())?;
/// println!("{} objects, {} triangles", picture.objects, picture.triangles);
/// # Ok(()) }
/// ```
pub fn shot(
    gpu: &Gpu,
    camera: &Camera,
    city: &Aabb,
    meshes: &[(u64, Mesh)],
    width: u32,
    height: u32,
) -> Result<Shot> {
    let mut target = Offscreen::new(gpu, width, height)?;
    target.set_ground(gpu, city, camera.far);
    let (camera, _) = target.fitted(camera)?;
    let started = Instant::now();
    let mut resident = GpuMeshes::default();
    for (id, mesh) in meshes {
        resident.upload(gpu, (*id, 0), mesh)?;
    }
    let upload = started.elapsed();
    let started = Instant::now();
    let ids: Vec<_> = meshes.iter().map(|m| (m.0, 0)).collect();
    let frame = target.render_camera(gpu, &camera, &resident, &ids)?;
    Ok(Shot {
        frame,
        objects: meshes.len(),
        triangles: meshes.iter().map(|m| m.1.triangle_count() as u64).sum(),
        gpu_bytes: resident.bytes(),
        upload,
        draw: started.elapsed(),
    })
}

impl Frame {
    /// Writes the colour image as a PNG.
    pub fn save_png(&self, path: &Path) -> Result<()> {
        let image = image::RgbaImage::from_raw(self.width, self.height, self.rgba.clone())
            .ok_or_else(|| Error::Invalid("a frame's pixels do not fill its size".into()))?;
        image
            .save_with_format(path, image::ImageFormat::Png)
            .map_err(|e| Error::Render(format!("writing {}: {e}", path.display())))
    }
}
