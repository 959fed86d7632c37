//! A walk drawn headless, frame by frame, into PNG files: the objects the walk engine
//! selected, kept on the GPU as the object buffer holds them (uploaded when an object
//! is loaded, freed when it is evicted, so a steady walk allocates nothing), with the
//! time each frame spent on the CPU side (uploads) and on drawing and reading back.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::{Frame, Gpu, GpuMeshes, Offscreen};
use crate::error::{Error, Result};
use crate::geom::{Aabb, Camera};
use crate::walk::buffer::{Loaded, ObjectBuffer};
use crate::walk::FrameSink;

/// What drawing a walk cost.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameTimes {
    /// Frames drawn, and written as PNGs.
    pub frames: usize,
    pub written: usize,
    /// Per frame: uploads and frees (CPU side), drawing and reading back (GPU side),
    /// milliseconds.
    pub upload_ms: Vec<f64>,
    pub draw_ms: Vec<f64>,
    pub uploads: usize,
    pub evictions: usize,
    /// The most GPU memory the meshes took, bytes.
    pub peak_gpu_bytes: u64,
    pub triangles: Vec<u64>,
}

impl FrameTimes {
    /// One row per frame drawn: the CPU side (uploads and frees) and the GPU side
    /// (drawing and reading back), milliseconds, and the triangles drawn.
    pub fn to_csv(&self) -> String {
        let mut s = String::from("frame,upload_ms,draw_ms,triangles\n");
        for (i, ((u, d), t)) in self
            .upload_ms
            .iter()
            .zip(&self.draw_ms)
            .zip(&self.triangles)
            .enumerate()
        {
            s.push_str(&format!("{i},{u:.3},{d:.3},{t}\n"));
        }
        s
    }
}

/// Draws each frame of a walk; writes every `every`-th into `dir` as
/// `frame-NNNNN.png`, or none (made by [`FrameWriter::drawing`]).
pub struct FrameWriter<'a> {
    gpu: &'a Gpu,
    target: Offscreen,
    meshes: GpuMeshes,
    /// Where frames go, and every how many.
    out: Option<(PathBuf, usize)>,
    pub times: FrameTimes,
}

impl<'a> FrameWriter<'a> {
    /// Frames of `width` × `height` into `dir` (made if missing), every `every`-th
    /// written (at least 1), with a ground under `city` reaching `margin` metres past it.
    pub fn new(
        gpu: &'a Gpu,
        (width, height): (u32, u32),
        (city, margin): (&Aabb, f32),
        dir: &Path,
        every: usize,
    ) -> Result<FrameWriter<'a>> {
        if every == 0 {
            return Err(Error::Invalid(
                "write every 0th frame? give 1 or more".into(),
            ));
        }
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        Ok(FrameWriter {
            out: Some((dir.to_path_buf(), every)),
            ..FrameWriter::drawing(gpu, (width, height), (city, margin))?
        })
    }

    /// A writer that draws and times each frame but writes none.
    pub fn drawing(
        gpu: &'a Gpu,
        (width, height): (u32, u32),
        (city, margin): (&Aabb, f32),
    ) -> Result<FrameWriter<'a>> {
        let mut target = Offscreen::new(gpu, width, height)?;
        target.set_ground(gpu, city, margin);
        Ok(FrameWriter {
            gpu,
            target,
            meshes: GpuMeshes::default(),
            out: None,
            times: FrameTimes::default(),
        })
    }

    /// The meshes on the GPU now.
    pub fn resident(&self) -> &GpuMeshes {
        &self.meshes
    }
}

impl FrameWriter<'_> {
    /// Draws one frame as [`FrameSink::frame`] does, without writing it: the GPU made
    /// to hold what `buffer` holds of what has been drawn, then `drawn` drawn.
    pub fn draw(
        &mut self,
        camera: &Camera,
        buffer: &ObjectBuffer,
        drawn: &[&Loaded],
    ) -> Result<Frame> {
        let started = Instant::now();
        // The GPU holds what the object buffer holds: free what it evicted, and upload
        // what is drawn for the first time.
        self.times.evictions += self.meshes.retain(|id| buffer.contains(id));
        for o in drawn {
            if self.meshes.upload(self.gpu, o.entry.id, &o.mesh)? {
                self.times.uploads += 1;
            }
        }
        let upload = started.elapsed();
        let started = Instant::now();
        let ids: Vec<u64> = drawn.iter().map(|o| o.entry.id).collect();
        let frame = self
            .target
            .render_camera(self.gpu, camera, &self.meshes, &ids)?;
        let draw = started.elapsed();
        let t = &mut self.times;
        t.frames += 1;
        t.upload_ms.push(ms(upload));
        t.draw_ms.push(ms(draw));
        t.peak_gpu_bytes = t.peak_gpu_bytes.max(self.meshes.bytes());
        t.triangles
            .push(drawn.iter().map(|o| o.mesh.triangle_count() as u64).sum());
        Ok(frame)
    }
}

impl FrameSink for FrameWriter<'_> {
    fn frame(
        &mut self,
        index: usize,
        camera: &Camera,
        buffer: &ObjectBuffer,
        drawn: &[&Loaded],
    ) -> Result<()> {
        let frame = self.draw(camera, buffer, drawn)?;
        if let Some((dir, every)) = &self.out {
            if index.is_multiple_of(*every) {
                frame.save_png(&dir.join(format!("frame-{index:05}.png")))?;
                self.times.written += 1;
            }
        }
        Ok(())
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
