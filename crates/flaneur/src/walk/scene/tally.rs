//! A scene-tree walk's summary, tallied a frame at a time: the same whether the walk
//! keeps its frames or hands each one on and forgets it, in constant memory.

use crate::walk::cells_entered::CellsEntered;
use crate::walk::frame_times::FrameTimesTally;
use crate::walk::scene::Traversal;
use crate::walk::scene::{SceneFrame, SceneSummary};

/// What the summary needs of the frames seen so far.
#[derive(Clone, Debug, Default)]
pub(crate) struct SceneTally {
    times: FrameTimesTally,
    cells_entered: CellsEntered,
    /// Traversal times from frame 1 on, ms.
    traverse_ms: f64,
    triangles: f64,
    visited: f64,
    drawn: f64,
    /// The counts and extremes, named as the summary's.
    sum: SceneSummary,
}

impl SceneTally {
    /// The next frame, of a walk whose traversal is `traversal`.
    pub(crate) fn add(&mut self, f: &SceneFrame, traversal: Traversal) {
        let s = &mut self.sum;
        if s.frames > 0 {
            self.traverse_ms += f.traverse_ms;
        }
        self.cells_entered.add(f.cell);
        if let (None, Some((id, t))) = (s.first_too_big, f.too_big) {
            s.first_too_big = Some((s.frames, id, t));
        }
        s.frames += 1;
        self.times.add(f.frame_ms);
        self.triangles += f.triangles as f64;
        self.visited += f.visited as f64;
        self.drawn += f.drawn as f64;
        s.max_triangles = s.max_triangles.max(f.triangles);
        s.frames_outside += usize::from(f.cell.is_none());
        s.frames_conv += usize::from(f.conv);
        if let Traversal::Pb { budget } = traversal {
            s.frames_over_budget += usize::from(f.triangles > budget);
        }
        s.frames_too_big += usize::from(f.too_big.is_some());
        s.frames_ended += usize::from(f.ended);
    }

    /// The walk's summary.
    pub(crate) fn summary(&self) -> SceneSummary {
        let times = self.times.times();
        let all = self.sum.frames.max(1) as f64;
        SceneSummary {
            mean_frame_ms: times.mean,
            frame_ms_variance: times.variance,
            max_frame_ms: times.max,
            mean_traverse_ms: self.traverse_ms / self.sum.frames.saturating_sub(1).max(1) as f64,
            mean_triangles: self.triangles / all,
            mean_visited: self.visited / all,
            mean_drawn: self.drawn / all,
            cells_entered: self.cells_entered.count(),
            ..self.sum.clone()
        }
    }
}
