//! A walk drawn headless, frame by frame, into PNG files: the objects the walk engine
//! selected, each at the level of detail the walk's LOD selection chose, kept on the GPU as
//! the object buffer holds them (uploaded when an object is loaded or changes level,
//! freed when it is evicted, so a steady walk allocates nothing), with the time each
//! frame spent on the CPU side (LOD selection, uploads) and on drawing and reading back.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::{Frame, Gpu, GpuMeshes, Offscreen};
use flaneur::error::{Error, Result};
use flaneur::geom::{Aabb, Camera};
use flaneur::walk::lod_select::{check_tau, LodCounts};
use flaneur::walk::{FrameSink, ObjectBuffer, Selection};

/// What drawing a walk cost.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct FrameTimes {
    /// Frames drawn, and written as PNGs.
    pub frames: usize,
    pub written: usize,
    /// Per frame, milliseconds: LOD selection, and uploads and frees (the CPU side);
    /// drawing and reading back (the GPU side).
    pub select_ms: Vec<f64>,
    pub upload_ms: Vec<f64>,
    pub draw_ms: Vec<f64>,
    pub uploads: usize,
    pub evictions: usize,
    /// The most GPU memory the meshes took, bytes.
    pub peak_gpu_bytes: u64,
    /// Per frame: triangles drawn, and objects drawn coarser than full detail.
    pub triangles: Vec<u64>,
    pub coarse: Vec<usize>,
    /// What LOD selection read, `None` when the frames are drawn at full detail.
    pub lod: Option<LodCounts>,
}

impl FrameTimes {
    /// One row per frame drawn: the CPU side (LOD selection; uploads and frees) and
    /// the GPU side (drawing and reading back), milliseconds, the triangles drawn and
    /// the objects drawn coarser than full detail.
    pub fn to_csv(&self) -> String {
        let mut s = String::from("frame,select_ms,upload_ms,draw_ms,triangles,coarse_objects\n");
        for (i, ((((l, u), d), t), c)) in self
            .select_ms
            .iter()
            .zip(&self.upload_ms)
            .zip(&self.draw_ms)
            .zip(&self.triangles)
            .zip(&self.coarse)
            .enumerate()
        {
            s.push_str(&format!("{i},{l:.3},{u:.3},{d:.3},{t},{c}\n"));
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
    /// The τ the walk's LOD selection draws under; `None`: every object at full detail.
    lod_tau: Option<f32>,
    /// Whether LOD selection refines a large object from its first frame.
    lod_settled: bool,
    /// Whether refined objects adapt ahead on the thread pool.
    lod_adapt_ahead: bool,
    /// Objects refined elsewhere, handed to the walk when it starts.
    remote: Option<Box<dyn flaneur::walk::RemoteRefinements>>,
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
            lod_tau: None,
            lod_settled: false,
            lod_adapt_ahead: false,
            remote: None,
            times: FrameTimes::default(),
        })
    }

    /// The same writer asking the walk for each object at the level of detail LOD
    /// selection chooses under `tau` (a fraction of the viewport; see
    /// [`flaneur::walk::lod_select`]): the walk reads the coarse levels and selects.
    pub fn with_lod_tau(self, tau: f32) -> Result<FrameWriter<'a>> {
        check_tau(tau)?;
        Ok(FrameWriter {
            lod_tau: Some(tau),
            times: FrameTimes {
                lod: Some(LodCounts::default()),
                ..self.times
            },
            ..self
        })
    }

    /// The same writer asking the walk to refine each large object from the frame it is
    /// first drawn, waiting for its decoding ([`FrameSink::lod_settled`]): its pictures
    /// then follow from the path alone, whatever the thread pool's speed.
    pub fn settling_lods(self) -> FrameWriter<'a> {
        FrameWriter {
            lod_settled: true,
            ..self
        }
    }

    /// The same writer asking the walk to refine each object drawn refined view by
    /// view on the thread pool once a frame is drawn, for the next frame's predicted
    /// view ([`FrameSink::lod_adapt_ahead`]): the traversal leaves the frame's thread.
    pub fn adapting_ahead(self) -> FrameWriter<'a> {
        FrameWriter {
            lod_adapt_ahead: true,
            ..self
        }
    }

    /// The same writer handing the walk objects refined elsewhere to draw from there
    /// ([`FrameSink::lod_remote`]): a stream server's landmarks. Only with a τ
    /// ([`FrameWriter::with_lod_tau`]): a walk at full detail draws every object whole.
    pub fn with_remote(self, remote: Box<dyn flaneur::walk::RemoteRefinements>) -> FrameWriter<'a> {
        FrameWriter {
            remote: Some(remote),
            ..self
        }
    }

    /// The meshes on the GPU now.
    pub fn resident(&self) -> &GpuMeshes {
        &self.meshes
    }
}

impl FrameWriter<'_> {
    /// Draws one frame as [`FrameSink::frame`] does, without writing it: each object
    /// of `selection` at its level, the GPU made to hold what `buffer` holds of what has
    /// been drawn, at the level last drawn.
    pub fn draw(
        &mut self,
        camera: &Camera,
        buffer: &ObjectBuffer,
        selection: &mut Selection<'_>,
    ) -> Result<Frame> {
        if let Some(counts) = selection.lod {
            self.times.lod = Some(counts);
        }
        let select = selection.select_ms;
        let (selected, refinements) = selection.parts();
        let started = Instant::now();
        let f = self
            .meshes
            .follow(self.gpu, |id| buffer.contains(id), selected, refinements)?;
        self.times.uploads += f.uploads;
        self.times.evictions += f.freed;
        let upload = started.elapsed();
        let keys: Vec<_> = selected.iter().map(|d| (d.id, d.level)).collect();
        let (triangles, coarse) = (
            selected.iter().map(|d| d.triangles as u64).sum(),
            selected.iter().filter(|d| d.is_coarse()).count(),
        );
        // What adapts ahead refines for the next frame while this one draws.
        selection.uploaded()?;
        let started = Instant::now();
        let frame = self
            .target
            .render_camera(self.gpu, camera, &self.meshes, &keys)?;
        let draw = started.elapsed();
        let t = &mut self.times;
        t.frames += 1;
        t.select_ms.push(select);
        t.upload_ms.push(ms(upload));
        t.draw_ms.push(ms(draw));
        t.peak_gpu_bytes = t.peak_gpu_bytes.max(self.meshes.bytes());
        t.triangles.push(triangles);
        t.coarse.push(coarse);
        Ok(frame)
    }
}

impl FrameSink for FrameWriter<'_> {
    fn frame(
        &mut self,
        index: usize,
        camera: &Camera,
        buffer: &ObjectBuffer,
        selection: &mut Selection<'_>,
    ) -> Result<()> {
        let frame = self.draw(camera, buffer, selection)?;
        if let Some((dir, every)) = &self.out {
            if index.is_multiple_of(*every) {
                frame.save_png(&dir.join(format!("frame-{index:05}.png")))?;
                self.times.written += 1;
            }
        }
        Ok(())
    }

    fn lod_tau(&self) -> Option<f32> {
        self.lod_tau
    }

    fn lod_settled(&self) -> bool {
        self.lod_settled
    }

    fn lod_adapt_ahead(&self) -> bool {
        self.lod_adapt_ahead
    }

    fn lod_remote(&mut self) -> Option<Box<dyn flaneur::walk::RemoteRefinements>> {
        self.remote.take()
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}
