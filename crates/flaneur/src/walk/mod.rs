//! The walkthrough engine: a viewer's poses in; for each frame, the objects it sees read
//! from the database, kept in an object buffer, culled and selected at a level of
//! detail, every page counted, and handed to whoever draws them.
//!
//! One walk session (`session.rs`), the frame loop every mode shares, plays the modes
//! (`mode/`), its retrieval strategies: REVIEW and BOX over disk cells (Shou 2002
//! §4.1–4.4), whose settings, entry points and figures are [`review`]'s, and the PVS
//! walk (Zheng 2007 ch. 7), whose are [`pvs_walk`]'s. [`live`] runs walks one after
//! another at a live viewer as its person changes the mode; [`lod_select`] is each
//! frame's LOD selection; [`path`] the camera paths ([`CameraPath`](path::CameraPath),
//! a timed sequence of [`Pose`](path::Pose)s, and its CSV file; street walks, the
//! motion patterns of Shou 2002 §4.4.1, viewcell walks, the routes of Zheng 2007 §7.5).
//!
//! Re-exported here, one idea per file:
//! - `sink.rs`: what a walk hands whoever draws it: [`FrameSink`] (a frame's
//!   [`Selection`]; [`NoSink`] draws nothing), [`Viewer`] (a sink that also gives the
//!   poses), [`FrameFigures`] (what a frame cost);
//! - `buffer.rs`: [`ObjectBuffer`], the object buffer and its eviction (Shou 2002
//!   §4.2.2, Fig. 4.8), of [`Loaded`] objects ([`mesh_bytes`] each), an eviction's
//!   [`Eviction`];
//! - `cells.rs`: the disk cells of Shou 2002 §4.1: [`disk_cell`] around an eye,
//!   [`scaled_cell`] (REVIEW's, SF times the frustum cell) and [`contains_ground`];
//! - `start.rs`: [`busiest_street`], where a viewer starts;
//! - `steer.rs`: [`Steer`], a person steering the camera with [`Move`] keys and the
//!   mouse, at [`WALK_SPEED`].

mod buffer;
mod cells;
pub mod live;
pub mod lod_select;
mod mode;
pub mod path;
pub mod pvs_walk;
pub mod review;
mod session;
mod sink;
mod start;
mod steer;

pub use buffer::{mesh_bytes, Eviction, Loaded, ObjectBuffer};
pub use cells::{contains_ground, disk_cell, scaled_cell};
pub use sink::{FrameFigures, FrameSink, NoSink, Selection, Viewer};
pub use start::busiest_street;
pub use steer::{Move, Steer, WALK_SPEED};
