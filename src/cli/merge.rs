//! `flaneur merge`: a database built from its inputs with its visibility joined from
//! the shards `flaneur build --visibility --shard K/N` computed, each on any machine.

use std::path::PathBuf;

use anyhow::Result;

use super::bars::Bars;
use super::build::{print_summary, DatabaseArgs};
use flaneur::progress::{Progress, Silent};

/// `flaneur merge`'s arguments: the build's less its visibility's, which are the
/// shards' own, and the shard files.
#[derive(clap::Args)]
pub struct MergeArgs {
    /// The shard files, every shard of one split (in any order).
    #[arg(long, num_args = 1.., required = true, value_name = "SHARD")]
    shards: Vec<PathBuf>,
    #[command(flatten)]
    build: DatabaseArgs,
}

impl MergeArgs {
    /// Builds the database with the shards' visibility and prints its summary.
    pub fn run(self) -> Result<()> {
        let opts = self.build.options(None)?;
        let progress: &dyn Progress = if self.build.quiet() {
            &Silent
        } else {
            &Bars::default()
        };
        let summary = flaneur::merge_visibility_shards(
            self.build.inputs(),
            &self.shards,
            self.build.out(),
            &opts,
            progress,
        )?;
        print_summary(self.build.out(), &summary, opts.order);
        println!(
            "  visibility merged from {} shards, with their settings (flaneur info shows them)",
            self.shards.len()
        );
        Ok(())
    }
}
