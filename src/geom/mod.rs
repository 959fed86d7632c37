//! Geometry shared by every module: axis-aligned boxes and (later) planes, frusta and
//! cameras. Built on glam.

mod aabb;

pub use aabb::Aabb;
