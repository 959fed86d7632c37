//! What a never-wait walk went on without: the damage its loaders met and the loads the
//! network failed, told in its summary and then made the walk's failure, so that a
//! headless walk ends as a waiting walk would have (that one stops at the first), its
//! figures printed first.

use anyhow::{bail, Result};

/// Names printed in a summary before the rest are only counted.
const NAMED: usize = 10;

/// The summary's lines for `damaged`, each object's damage in words naming its page.
pub(super) fn print_damaged(damaged: &[String]) {
    if damaged.is_empty() {
        return;
    }
    println!(
        "  damaged: {} objects could not be read whole, and the walk went on without that part:",
        damaged.len()
    );
    for what in damaged.iter().take(NAMED) {
        println!("    {what}");
    }
    if damaged.len() > NAMED {
        println!("    and {} more", damaged.len() - NAMED);
    }
}

/// The walk's end: an error when it went on past damage or past loads the network
/// failed (`failed`, the last one's words `last`).
pub(super) fn went_without(damaged: &[String], failed: usize, last: Option<&str>) -> Result<()> {
    if let Some(first) = damaged.first() {
        bail!(
            "the walk met damage and went on without it ({} objects; the first: {first}); \
             `flaneur check` names every damaged page",
            damaged.len()
        );
    }
    if failed > 0 {
        bail!(
            "{failed} loads failed on the network and the walk went on without them; the last: {}",
            last.unwrap_or("unknown")
        );
    }
    Ok(())
}
