//! One frame of any walk: the figures every mode has (its index, its viewcell, what it
//! drew, what it read, what it missed) and the columns the mode adds, in the mode's
//! own record. Serialised flat, as the mode's record.

use super::pvs::PvsFrame;
use super::review::FrameStats;
use super::scene::SceneFrame;
use super::visual::VisualFrame;
use super::walk_mode::WalkMode;

/// A frame's figures, as the walk's mode keeps them.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(untagged)]
pub enum Frame {
    /// A REVIEW or BOX frame.
    Review(FrameStats),
    /// A PVS frame.
    Pvs(PvsFrame),
    /// A VISUAL frame.
    Visual(VisualFrame),
    /// A VSC, PB or CONV frame.
    Scene(SceneFrame),
}

impl Frame {
    /// The frame's index in the walk, from 0.
    pub fn index(&self) -> usize {
        match self {
            Frame::Review(f) => f.frame,
            Frame::Pvs(f) => f.frame,
            Frame::Visual(f) => f.frame,
            Frame::Scene(f) => f.frame,
        }
    }

    /// The viewcell the viewer stood in, for the modes over viewcells.
    pub fn cell(&self) -> Option<u32> {
        match self {
            Frame::Review(_) => None,
            Frame::Pvs(f) => f.cell,
            Frame::Visual(f) => f.cell,
            Frame::Scene(f) => f.cell,
        }
    }

    /// Objects (or HDoV nodes) drawn.
    pub fn drawn(&self) -> usize {
        match self {
            Frame::Review(f) => f.objects_drawn,
            Frame::Pvs(f) => f.drawn,
            Frame::Visual(f) => f.drawn,
            Frame::Scene(f) => f.drawn,
        }
    }

    /// Pages the mode read for the frame (LOD selection's apart).
    pub fn pages(&self) -> u64 {
        match self {
            Frame::Review(f) => f.index_pages + f.mesh_pages,
            Frame::Pvs(f) => f.pages,
            Frame::Visual(f) => f.tree_pages + f.model_pages + f.other_pages,
            Frame::Scene(f) => f.pages,
        }
    }

    /// Objects the viewer should have seen that were not in memory (a scene-tree walk
    /// holds the whole city: none).
    pub fn visual_misses(&self) -> usize {
        match self {
            Frame::Review(f) => f.visual_misses,
            Frame::Pvs(f) => f.visual_misses,
            Frame::Visual(f) => f.visual_misses,
            Frame::Scene(_) => 0,
        }
    }

    /// The frame as one CSV row (no line end), under [`Frame::csv_header`] of its mode.
    pub fn csv_row(&self) -> String {
        match self {
            Frame::Review(f) => f.csv_row(),
            Frame::Pvs(f) => f.csv_row(),
            Frame::Visual(f) => f.csv_row(),
            Frame::Scene(f) => f.csv_row(),
        }
    }

    /// The columns of this frame's [`Frame::csv_row`].
    pub fn header(&self) -> &'static str {
        match self {
            Frame::Review(_) => FrameStats::CSV_HEADER,
            Frame::Pvs(_) => PvsFrame::CSV_HEADER,
            Frame::Visual(_) => VisualFrame::CSV_HEADER,
            Frame::Scene(_) => SceneFrame::CSV_HEADER,
        }
    }

    /// The columns of a `mode` walk's [`Frame::csv_row`].
    pub fn csv_header(mode: WalkMode) -> &'static str {
        match mode {
            WalkMode::Review | WalkMode::Box => FrameStats::CSV_HEADER,
            WalkMode::Pvs => PvsFrame::CSV_HEADER,
            WalkMode::Visual => VisualFrame::CSV_HEADER,
            WalkMode::Vsc | WalkMode::Pb | WalkMode::Conv => SceneFrame::CSV_HEADER,
        }
    }
}
