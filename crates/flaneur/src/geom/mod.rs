//! Geometry shared by every module: axis-aligned boxes, planes, view frusta and
//! cameras. Built on glam.

mod aabb;
mod camera;
mod frustum;
mod plane;
mod union_cover;

pub use aabb::Aabb;
pub use camera::{fov_x_for, Camera, DEFAULT_FAR, DEFAULT_FOV, DEFAULT_NEAR};
pub use frustum::Frustum;
pub use frustum::{box_corners, EDGES};
pub use plane::Plane;
pub(crate) use union_cover::covered;
