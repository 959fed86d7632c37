//! The walkthrough renderer's GPU side (wgpu): a device found without a window
//! ([`Gpu::headless`], a software adapter where there is no GPU), object meshes
//! resident on the GPU ([`GpuMeshes`]: uploaded on load, freed on eviction, their bytes
//! counted), and offscreen frames ([`Offscreen`]) that draw colour and, in the same
//! pass, the object each pixel shows, read back for PNGs and for tests. [`shot`] puts
//! them together for one viewpoint and the meshes read for it; [`FrameWriter`] draws a walk frame by
//! frame as the walk engine selects it. [`Hud`] blends a heads-up display (text and a
//! frame-time graph, [`rasterise`]d on the CPU) onto a frame or a window.

pub mod boxes;
mod frames;
mod gpu;
mod hud;
mod meshes;
mod offscreen;
mod scene;
mod shot;
mod window;

/// The walk modes the window shows, and the changes its keys ask of the walk, which
/// the walk engine's live session ([`flaneur::walk::live`]) acts on.
pub use flaneur::walk::{live::Change, WalkMode};
pub use frames::{FrameTimes, FrameWriter};
pub use gpu::Gpu;
pub use hud::{rasterise, Hud, HudContent};
pub use meshes::{gpu_bytes, Followed, GpuMesh, GpuMeshes, MeshKey, Vertex};
pub use offscreen::{Frame, Offscreen};
pub use scene::{drawing_view_proj, Fade, ScenePass, SceneView};
pub use shot::{shot, Shot};
/// The adapter a [`Gpu`] runs on (its name, driver and backend), as wgpu reports it.
pub use wgpu::AdapterInfo;
pub use window::{save_recording, ViewOptions, ViewSummary, WalkWindow};
