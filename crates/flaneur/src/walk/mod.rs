//! The walkthrough engine. So far: camera paths through a city — street walks, the
//! motion patterns of Shou 2002 §4.4.1 and their CSV files — and the disk cells a walk
//! queries (Shou 2002 §4.1); the REVIEW frame loop (`review`) with its object buffer (`buffer`).

pub mod buffer;
pub mod cells;
pub mod lod_select;
pub mod motion;
mod path;
pub mod path_csv;
pub mod pvs_walk;
pub mod review;
mod sink;
pub mod start;
pub mod steer;

pub use motion::{CameraPath, Motion, Pose};
pub use path::{street_walk, WalkPath};
pub use sink::{FrameFigures, FrameSink, NoSink, Viewer};
