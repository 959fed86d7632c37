//! What a walk shows, frame by frame, for whoever draws it: the camera, the object
//! buffer, and the objects drawn (the buffer after frustum culling). The renderer
//! implements [`FrameSink`]; a walk that draws nothing passes [`NoSink`].

use super::buffer::{Loaded, ObjectBuffer};
use crate::error::Result;
use crate::geom::Camera;

/// Receives each frame of a walk as the engine selected it.
pub trait FrameSink {
    /// Frame `index`, seen by `camera`: `drawn` are the objects of `buffer` in view.
    fn frame(
        &mut self,
        index: usize,
        camera: &Camera,
        buffer: &ObjectBuffer,
        drawn: &[&Loaded],
    ) -> Result<()>;

    /// Whether it draws, so that a walk must load the objects' meshes for it (a walk
    /// that only counts, like the PVS walk, loads none otherwise).
    fn draws(&self) -> bool {
        true
    }
}

/// A sink that draws nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoSink;

impl FrameSink for NoSink {
    fn frame(&mut self, _: usize, _: &Camera, _: &ObjectBuffer, _: &[&Loaded]) -> Result<()> {
        Ok(())
    }

    fn draws(&self) -> bool {
        false
    }
}
