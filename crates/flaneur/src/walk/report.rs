//! What any walk reports: the mode's own report (its settings, the frames it kept, its
//! summary), behind the figures every mode has.

use super::frame::Frame;
use super::pvs::PvsWalkReport;
use super::review::WalkReport;
use super::scene::SceneReport;
use super::visual::VisualReport;
use crate::error::{Error, Result};

/// A whole walk's report, as its mode keeps it.
///
/// A caller that walked one mode takes that mode's report out of it:
/// `let r: review::WalkReport = walk::run(..)?.try_into()?`.
#[derive(Clone, Debug, serde::Serialize)]
#[serde(untagged)]
pub enum Report {
    /// A REVIEW or BOX walk's.
    Review(WalkReport),
    /// A PVS walk's.
    Pvs(PvsWalkReport),
    /// A VISUAL walk's.
    Visual(VisualReport),
    /// A VSC, PB or CONV walk's.
    Scene(SceneReport),
}

impl Report {
    /// Frames walked.
    pub fn frames_walked(&self) -> usize {
        match self {
            Report::Review(r) => r.summary.frames,
            Report::Pvs(r) => r.walked,
            Report::Visual(r) => r.summary.frames,
            Report::Scene(r) => r.summary.frames,
        }
    }

    /// The frames kept ([`Frames::Keep`](super::Frames::Keep)), in order; none for a
    /// walk that handed them on.
    pub fn frames(&self) -> Vec<Frame> {
        match self {
            Report::Review(r) => r.frames.iter().cloned().map(Frame::Review).collect(),
            Report::Pvs(r) => r.frames.iter().copied().map(Frame::Pvs).collect(),
            Report::Visual(r) => r.frames.iter().cloned().map(Frame::Visual).collect(),
            Report::Scene(r) => r.frames.iter().cloned().map(Frame::Scene).collect(),
        }
    }

    /// The kept frames as one CSV text: a header, then a row a frame.
    pub fn to_csv(&self) -> String {
        let header = match self {
            Report::Review(_) => super::review::FrameStats::CSV_HEADER,
            Report::Pvs(_) => super::pvs::PvsFrame::CSV_HEADER,
            Report::Visual(_) => super::visual::VisualFrame::CSV_HEADER,
            Report::Scene(_) => super::scene::SceneFrame::CSV_HEADER,
        };
        super::frame_csv::table(header, &self.frames(), Frame::csv_row)
    }

    /// What the walk could not read for damage and went on without, in words.
    pub fn damaged(&self) -> &[String] {
        match self {
            Report::Review(r) => &r.summary.damaged,
            Report::Pvs(r) => &r.damaged,
            Report::Visual(_) | Report::Scene(_) => &[],
        }
    }

    /// Loads that failed on the network and were asked for again, and the last of
    /// their errors (never-wait walks).
    pub fn failed_loads(&self) -> (usize, Option<&str>) {
        let (n, last) = match self {
            Report::Review(r) => (r.summary.failed_loads, &r.summary.last_load_error),
            Report::Pvs(r) => (r.failed_loads, &r.last_load_error),
            Report::Visual(r) => (r.summary.failed_loads, &r.summary.last_load_error),
            Report::Scene(_) => return (0, None),
        };
        (n, last.as_deref())
    }
}

/// The mode reports taken out of a [`Report`]: an error naming both modes when the
/// walk was another.
macro_rules! report_of {
    ($variant:ident, $ty:ty, $name:literal) => {
        impl TryFrom<Report> for $ty {
            type Error = Error;

            fn try_from(r: Report) -> Result<$ty> {
                match r {
                    Report::$variant(r) => Ok(r),
                    other => Err(Error::Invalid(format!(
                        "a {} walk's report is not a {} walk's",
                        other.mode_name(),
                        $name
                    ))),
                }
            }
        }
    };
}

report_of!(Review, WalkReport, "REVIEW or BOX");
report_of!(Pvs, PvsWalkReport, "PVS");
report_of!(Visual, VisualReport, "VISUAL");
report_of!(Scene, SceneReport, "scene-tree");

impl Report {
    fn mode_name(&self) -> &'static str {
        match self {
            Report::Review(_) => "REVIEW or BOX",
            Report::Pvs(_) => "PVS",
            Report::Visual(_) => "VISUAL",
            Report::Scene(_) => "scene-tree",
        }
    }
}
