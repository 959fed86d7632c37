//! The `flaneur` command's parts: one file per command, and what they share.

pub mod bars;
