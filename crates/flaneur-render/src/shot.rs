//! One picture of a database from a viewpoint, drawn headless: the objects whose boxes
//! meet the view frustum (an R-tree range query over the frustum's box, then the
//! frustum test), each at full detail.

use std::path::Path;
use std::time::{Duration, Instant};

use crate::{Frame, Gpu, GpuMeshes, Offscreen};
use flaneur::error::{Error, Result};
use flaneur::geom::Camera;
use flaneur::{Database, ObjectEntry};

/// What [`shot`] drew.
#[derive(Clone, Debug)]
pub struct Shot {
    pub frame: Frame,
    /// Objects drawn, and their triangles.
    pub objects: usize,
    pub triangles: u64,
    /// GPU memory the objects' meshes took, bytes.
    pub gpu_bytes: u64,
    /// Selecting and reading the objects, uploading them, drawing and reading back.
    pub select: Duration,
    pub upload: Duration,
    pub draw: Duration,
}

/// The horizontal field of view that, with `fov_y`, fills an image of `aspect`
/// (width / height).
pub fn fov_x_for(fov_y: f32, aspect: f32) -> f32 {
    2.0 * ((fov_y * 0.5).tan() * aspect).atan()
}

/// The objects of `db` whose boxes meet `camera`'s view frustum: a range query over the
/// frustum's box, then the frustum test. What a full-detail picture draws.
pub fn in_view(db: &Database, camera: &Camera) -> Result<Vec<ObjectEntry>> {
    let frustum = camera.frustum();
    let mut found = db.range(&frustum.aabb())?.objects;
    found.retain(|o| frustum.overlaps_aabb(&o.bounds));
    Ok(found)
}

/// Renders `db` as `camera` sees it (its vertical field of view kept, its horizontal
/// one fitted to the image) into a `width` × `height` frame.
///
/// ```no_run
/// # fn main() -> flaneur::Result<()> {
/// use flaneur::{geom::Camera, Database};
/// use flaneur_render::{shot, Gpu};
/// let db = Database::open("city.flaneur".as_ref())?;
/// let camera = Camera::new(glam::Vec3::new(100.0, 1.7, 80.0), 0.0, 0.0)?;
/// let picture = shot(&db, &Gpu::headless()?, &camera, 640, 480)?;
/// picture.frame.save_png("shot.png".as_ref())?;
/// println!("{} objects, {} triangles", picture.objects, picture.triangles);
/// # Ok(()) }
/// ```
pub fn shot(db: &Database, gpu: &Gpu, camera: &Camera, width: u32, height: u32) -> Result<Shot> {
    let mut target = Offscreen::new(gpu, width, height)?;
    target.set_ground(gpu, &db.bounds(), camera.far);
    let (camera, aspect) = target.fitted(camera)?;
    let started = Instant::now();
    let mut meshes = Vec::new();
    for o in in_view(db, &camera)? {
        meshes.push((o.id, db.mesh(&o)?));
    }
    let select = started.elapsed();
    let started = Instant::now();
    let mut resident = GpuMeshes::default();
    for (id, mesh) in &meshes {
        resident.upload(gpu, (*id, 0), mesh)?;
    }
    let upload = started.elapsed();
    let started = Instant::now();
    let ids: Vec<_> = meshes.iter().map(|m| (m.0, 0)).collect();
    let frame = target.render(gpu, camera.view_proj(aspect)?, &resident, &ids)?;
    Ok(Shot {
        frame,
        objects: meshes.len(),
        triangles: meshes.iter().map(|m| m.1.triangle_count() as u64).sum(),
        gpu_bytes: resident.bytes(),
        select,
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
