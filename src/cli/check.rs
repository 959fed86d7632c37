//! `flaneur check`: every page and every structure of a database verified, every
//! problem named with its page and what the page belongs to.

use std::path::PathBuf;

use anyhow::{bail, Result};

/// `flaneur check`'s arguments.
#[derive(clap::Args)]
pub struct CheckArgs {
    /// The database file.
    db: PathBuf,
    /// The report as JSON (pages, objects, unclaimed pages, problems).
    #[arg(long)]
    json: bool,
}

impl CheckArgs {
    /// Runs the check and prints its report; fails (exit 1) when a problem was found.
    pub fn run(self) -> Result<()> {
        // A URL is read by byte ranges, as every command reads one.
        let report = match self.db.to_str() {
            Some(url) if flaneur::store::is_url(url) => {
                flaneur::check::check_url(url, &flaneur::store::HttpOptions::default())?
            }
            _ => flaneur::check::check(&self.db)?,
        };
        if self.json {
            println!("{}", serde_json::to_string_pretty(&report)?);
        } else {
            print_text(&self.db, &report);
        }
        if !report.ok() {
            bail!(
                "{}: {} problem{} found",
                self.db.display(),
                report.problems.len(),
                if report.problems.len() == 1 { "" } else { "s" }
            );
        }
        Ok(())
    }
}

fn print_text(db: &std::path::Path, r: &flaneur::check::CheckReport) {
    for p in &r.problems {
        match p.page {
            Some(page) => println!("page {page} ({}): {}", p.part, p.what),
            None => println!("{}: {}", p.part, p.what),
        }
    }
    if r.uncommitted_bytes > 0 {
        println!(
            "note: {} bytes past the last page are not part of the database (a write \
             interrupted before its commit, or bytes appended); never read",
            r.uncommitted_bytes
        );
    }
    for (kind, n) in &r.unclaimed {
        println!("note: {n} {kind} pages belong to no structure (an insert's replaced copies)");
    }
    if r.ok() {
        println!(
            "ok: {} — {} pages, {} objects, every checksum and structure verified ({} page reads)",
            db.display(),
            r.pages,
            r.objects,
            r.page_reads
        );
    }
}
