//! A viewer that plays poses and keeps every frame's figures, as the window's HUD gets
//! them; it claims to draw (so that walks select what a window would) but draws nothing.

use flaneur::path::Pose;
use flaneur::walk::{FrameFigures, FrameSink, ObjectBuffer, Selection, Viewer};

pub struct Recorder {
    pub poses: Vec<Pose>,
    pub figures: Vec<FrameFigures>,
}

impl Recorder {
    pub fn new(poses: Vec<Pose>) -> Recorder {
        Recorder {
            poses,
            figures: Vec::new(),
        }
    }
}

impl FrameSink for Recorder {
    fn frame(
        &mut self,
        _: usize,
        _: &flaneur::geom::Camera,
        _: &ObjectBuffer,
        _: &mut Selection<'_>,
    ) -> flaneur::Result<()> {
        Ok(())
    }
}

impl Viewer for Recorder {
    fn next_pose(&mut self, frame: usize) -> flaneur::Result<Option<Pose>> {
        Ok(self.poses.get(frame).copied())
    }

    fn figures(&mut self, figures: &FrameFigures) {
        self.figures.push(figures.clone());
    }
}
