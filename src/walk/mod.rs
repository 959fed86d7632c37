//! The walkthrough engine. So far: camera paths through a city and the disk cells a
//! walk queries (Shou 2002 §4.1); the frame loop comes with the renderer.

pub mod cells;
mod path;

pub use path::{street_walk, WalkPath};
