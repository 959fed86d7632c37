//! The `flaneur` command's parts: one file per command, and what they share.

pub mod args;
pub mod bars;
pub mod bench;
pub mod build;
pub mod check;
pub mod demo;
mod demo_modes;
pub mod info;
pub mod insert;
pub mod lod;
mod lod_inspect;
pub mod merge;
pub mod query;
pub mod serve;
pub mod serve_stream;
pub mod shot;
pub mod source;
pub mod stream_client;
pub mod view;
pub mod walk;

use std::path::Path;

use anyhow::{Context, Result};

/// Writes `text` to `path`, the path named in the error.
pub fn write_file(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))
}
