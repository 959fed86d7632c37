//! LODs stored in the database: what `flaneur build` bakes for each object (its chain of
//! coarse levels, coarsest first so that a coarse level reads few pages, and for large
//! objects its progressive mesh and DAG), the table that finds them by object id, and
//! their reading back through the store, every page counted.

mod bake;
pub(crate) mod chain;
pub(crate) mod read;
mod select;
pub(crate) mod table;

pub(crate) use bake::{simplify_stored, LodWriter};
pub use bake::{LodOptions, LodReport, DEFAULT_PM_THRESHOLD};
#[cfg(test)]
pub(crate) use chain::encode_chain;
pub(crate) use chain::encode_chain_with;
pub use chain::{LevelInfo, CHAIN_MAGIC};
pub(crate) use read::{
    chain_level, chain_levels, chain_levels_at, coarse_levels, coarsest_levels, level_mesh, levels,
    levels_at, progressive, read_progressive, ProgressiveBytes,
};
pub use select::{distance_to, level_for};
pub use table::LodStats;
pub(crate) use table::{LodEntry, LodTable};
