//! The papers' experiments as library code: `flaneur bench` and the criterion benches
//! call these and only print or plot what they return.

pub mod csearch;
pub mod index_cache;
pub mod patterns;
pub mod plot;
pub mod prefetch_k;
pub mod view_culling;
