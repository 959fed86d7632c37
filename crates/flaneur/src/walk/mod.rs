//! The walkthrough engine. So far: camera paths through a city (`path`: street walks,
//! the motion patterns of Shou 2002 §4.4.1, viewcell walks, the routes of Zheng 2007
//! §7.5 and their CSV files) and the disk cells a walk queries (Shou 2002 §4.1); one
//! walk session (`session`), the frame loop every mode shares, with its object buffer
//! (`buffer`); the modes it plays (`mode`): REVIEW and BOX, whose settings and figures
//! are `review`'s, and the PVS walk, whose are `pvs_walk`'s; and walks at a live viewer
//! one after another as its person changes mode (`live`).

pub mod buffer;
pub mod cells;
pub mod live;
pub mod lod_select;
mod mode;
pub mod path;
pub mod pvs_walk;
pub mod review;
pub mod session;
mod sink;
pub mod start;
pub mod steer;

pub use path::motion::Motion;
pub use path::{street_walk, CameraPath, Pose};
pub use sink::{FrameFigures, FrameSink, NoSink, Selection, Viewer};
