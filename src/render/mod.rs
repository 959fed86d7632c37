//! The walkthrough renderer's GPU side (wgpu): a device found without a window
//! ([`Gpu::headless`], a software adapter where there is no GPU), object meshes
//! resident on the GPU ([`GpuMeshes`]: uploaded on load, freed on eviction, their bytes
//! counted), and offscreen frames ([`Offscreen`]) that draw colour and, in the same
//! pass, the object each pixel shows, read back for PNGs and for tests. [`shot`] puts
//! them together for one viewpoint of a database; [`FrameWriter`] draws a walk frame by
//! frame as the walk engine selects it.

mod frames;
mod gpu;
mod meshes;
mod offscreen;
mod shot;

pub use frames::{FrameTimes, FrameWriter};
pub use gpu::Gpu;
pub use meshes::{GpuMesh, GpuMeshes, MeshKey, Vertex};
pub use offscreen::{Frame, Offscreen};
pub use shot::{fov_x_for, shot, Shot};
