//! `flaneur query`: one range query (BOX), or CSearch against history cells, with the
//! pages it read and its time; each object with its name where the database keeps names
//! (an imported OpenStreetMap building's `way/…` or `relation/…`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;

use super::source::{remote_line, SourceArgs};
use flaneur::geom::Aabb;

/// `flaneur query`'s arguments.
#[derive(clap::Args)]
pub struct QueryArgs {
    /// The database: a file, or a URL (http://… or https://…) on any HTTP server.
    db: PathBuf,
    /// The query box: x0,y0,z0,x1,y1,z1.
    #[arg(long = "box", value_name = "BOX", allow_hyphen_values = true)]
    query: Aabb,
    /// History cells for CSearch (repeatable; default: none, a plain BOX query).
    #[arg(long, value_name = "BOX", allow_hyphen_values = true)]
    history: Vec<Aabb>,
    #[command(flatten)]
    source: SourceArgs,
    /// Print the answer as JSON: the ids (and names), pages, page reads, microseconds,
    /// and the HTTP figures of a URL.
    #[arg(long)]
    json: bool,
}

impl QueryArgs {
    /// Runs the query and prints its objects, pages and time.
    pub fn run(self) -> Result<()> {
        run_query(
            &self.db,
            &self.query,
            &self.history,
            &self.source,
            self.json,
        )
    }
}

fn run_query(
    path: &Path,
    q: &Aabb,
    history: &[Aabb],
    source: &SourceArgs,
    json: bool,
) -> Result<()> {
    let db = source.open(path)?;
    let t = Instant::now();
    let result = if history.is_empty() {
        db.range(q)?
    } else {
        db.csearch(q, history)?
    };
    let us = t.elapsed().as_secs_f64() * 1e6;
    let io = db.io();
    // Names are looked up after the query's figures are taken: they are not its reads.
    let names = if db.named_objects() > 0 {
        let names: flaneur::Result<Vec<Option<String>>> =
            result.ids().iter().map(|&id| db.object_name(id)).collect();
        Some(names?)
    } else {
        None
    };
    if json {
        let mut v = serde_json::json!({
            "query": if history.is_empty() { "box" } else { "csearch" },
            "ids": result.ids(),
            "pages": result.pages,
            "page_reads": io.page_reads,
            "micros": us,
        });
        if let Some(names) = &names {
            v["names"] = serde_json::json!(names);
        }
        if let Some(s) = db.remote_stats() {
            v["http"] = serde_json::json!({
                "requests": s.requests,
                "round_trips": s.round_trips,
                "bytes": s.bytes,
                "retries": s.retries,
                "page_reads": s.page_reads,
                "pages_fetched": s.pages_fetched,
            });
        }
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    let ids: Vec<String> = match &names {
        Some(names) => result
            .ids()
            .iter()
            .zip(names)
            .map(|(id, n)| match n {
                Some(n) => format!("{id} ({n})"),
                None => id.to_string(),
            })
            .collect(),
        None => result.ids().iter().map(u64::to_string).collect(),
    };
    println!("{} objects: {}", ids.len(), ids.join(" "));
    let pages: Vec<String> = result.pages.iter().map(u64::to_string).collect();
    println!("{} pages read: {}", pages.len(), pages.join(" "));
    println!("{:.0} µs", us);
    if let Some(stats) = db.remote_stats() {
        println!("{}", remote_line(&stats));
    }
    Ok(())
}
