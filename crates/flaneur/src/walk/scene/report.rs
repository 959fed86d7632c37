//! What a scene-tree walk reports: each frame's figures, and the walk's in all.

use super::config::SceneConfig;
use crate::walk::scene::Traversal;
use serde::Serialize;

/// One frame of a scene-tree walk. Times in milliseconds.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SceneFrame {
    /// The frame's index, from 0.
    pub frame: usize,
    /// Its pose's time on the path, seconds.
    pub time: f64,
    /// The viewcell the eye is in; `None` outside every one.
    pub cell: Option<u32>,
    /// Drawn by CONV, no cell having been entered yet.
    pub conv: bool,
    /// Bringing the VDs to a new cell.
    pub update_ms: f64,
    /// The traversal.
    pub traverse_ms: f64,
    /// The walk's whole time for the frame.
    pub frame_ms: f64,
    /// Nodes the traversal visited.
    pub visited: usize,
    /// Nodes drawn (objects and internal nodes).
    pub drawn: usize,
    /// Of those, internal nodes at an internal LOD.
    pub internal: usize,
    /// Triangles drawn.
    pub triangles: u64,
    /// PB: nodes dropped for want of budget.
    pub dropped: usize,
    /// PB: the traversal ran out of attempts and ended, drawing what was active.
    pub ended: bool,
    /// PB: an object whose coarsest representation alone is over the budget (id,
    /// triangles), when the frame met one.
    pub too_big: Option<(u64, u32)>,
    /// Pages read (a new cell's PVS; the tree is in memory).
    pub pages: u64,
}

impl SceneFrame {
    /// The columns of [`SceneFrame::csv_row`].
    pub const CSV_HEADER: &'static str = "frame,time,cell,conv,update_ms,traverse_ms,frame_ms,visited,drawn,internal,triangles,dropped,ended,pages";

    /// The frame as one CSV row (no line end), its columns [`SceneFrame::CSV_HEADER`].
    pub fn csv_row(&self) -> String {
        let f = self;
        format!(
            "{},{:.4},{},{},{:.3},{:.3},{:.3},{},{},{},{},{},{},{}",
            f.frame,
            f.time,
            f.cell.map_or(String::new(), |c| c.to_string()),
            f.conv as u8,
            f.update_ms,
            f.traverse_ms,
            f.frame_ms,
            f.visited,
            f.drawn,
            f.internal,
            f.triangles,
            f.dropped,
            f.ended as u8,
            f.pages
        )
    }
}

/// A scene-tree walk in all; frame 0 left out of the frame-time figures.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SceneSummary {
    /// Frames walked, frame 0 included.
    pub frames: usize,
    /// Mean frame time from frame 1 on, ms.
    pub mean_frame_ms: f64,
    /// Frame time's variance from frame 1 on, ms².
    pub frame_ms_variance: f64,
    /// Longest frame from frame 1 on, ms.
    pub max_frame_ms: f64,
    /// Mean traversal time, ms.
    pub mean_traverse_ms: f64,
    /// Triangles drawn per frame, on average.
    pub mean_triangles: f64,
    /// Nodes visited per frame, on average (Table 6.1's "Nodes").
    pub mean_visited: f64,
    /// Nodes drawn per frame, on average.
    pub mean_drawn: f64,
    /// The most triangles a frame drew.
    pub max_triangles: u64,
    /// Moves into another viewcell.
    pub cells_entered: usize,
    /// Frames outside every viewcell (the last cell's VDs kept).
    pub frames_outside: usize,
    /// Frames drawn by CONV before any cell was entered.
    pub frames_conv: usize,
    /// PB: frames that drew more triangles than the budget.
    pub frames_over_budget: usize,
    /// PB: frames that met an object whose coarsest representation alone is over the
    /// budget.
    pub frames_too_big: usize,
    /// PB: frames whose traversal ran out of attempts and ended early.
    pub frames_ended: usize,
    /// PB: the first frame that met an object whose coarsest representation alone is
    /// over the budget, with the object (id, triangles).
    pub first_too_big: Option<(usize, u64, u32)>,
}

/// What a scene-tree walk did.
#[derive(Clone, Debug, Serialize)]
pub struct SceneReport {
    /// The settings walked.
    pub config: SceneConfig,
    /// Every frame's figures, in order (empty for a walk that handed them on,
    /// [`Frames::Each`](crate::walk::Frames::Each)).
    pub frames: Vec<SceneFrame>,
    /// The walk in all.
    pub summary: SceneSummary,
}

impl SceneReport {
    /// PB's budget held on this share of the frames (1 for other traversals).
    pub fn within_budget(&self) -> f64 {
        1.0 - self.summary.frames_over_budget as f64 / self.summary.frames.max(1) as f64
    }

    /// What PB's budget could not hold, in words: the first object whose coarsest
    /// representation alone is over it. `None` when none was met.
    pub fn too_big(&self) -> Option<String> {
        let Traversal::Pb { budget } = self.config.traversal else {
            return None;
        };
        let (frame, id, t) = self.summary.first_too_big?;
        Some(format!(
            "object {id}'s coarsest representation alone has {t} triangles, over the budget of {budget} (first on frame {frame}, {} frames in all)",
            self.summary.frames_too_big
        ))
    }
}
