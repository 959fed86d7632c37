//! The `layout` experiment (ours): what the order of a database's objects in its file
//! costs a reader over HTTP.
//!
//! Each database (the same city written in different orders: `flaneur build --order`)
//! is served over HTTP and asked the same square range queries at random places, each
//! from a cold client (opened afresh, so that no page is held): the query itself, then
//! what a never-wait walk fetches for the objects it finds, their coarsest stored
//! levels first, then their full meshes. For each step the figures are exact counts:
//! pages the step read (the same in every order), pages it fetched (those the client
//! did not hold: the open's first round trip brings both ends of the file, whose
//! contents differ by order), HTTP requests, round trips (batches sent together) and
//! body bytes. Requests and bytes are what the order changes, since a request carries
//! one run of neighbouring pages (small gaps bridged).

use std::net::SocketAddr;
use std::path::Path;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::plot::{line_plot, LinePlot, Series};
use crate::report::Report;
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::geom::Aabb;
use flaneur::store::{HttpOptions, RemoteStats};

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct LayoutBenchConfig {
    /// Queries per box side, at random places (the same for every database).
    pub queries: usize,
    /// Sides of the square query boxes, metres (on the ground; each box spans the
    /// city's height).
    pub sides: Vec<f32>,
    /// Seed of the query places.
    pub seed: u64,
}

impl Default for LayoutBenchConfig {
    /// 40 queries each of 100, 200 and 400 m.
    fn default() -> LayoutBenchConfig {
        LayoutBenchConfig {
            queries: 40,
            sides: vec![100.0, 200.0, 400.0],
            seed: 1,
        }
    }
}

impl LayoutBenchConfig {
    /// Checks the settings.
    pub fn validate(&self) -> Result<()> {
        if self.queries == 0 || self.sides.is_empty() {
            return Err(Error::Invalid(
                "layout: give at least one query and one box side".into(),
            ));
        }
        if let Some(s) = self.sides.iter().find(|s| !(s.is_finite() && **s > 0.0)) {
            return Err(Error::Invalid(format!(
                "layout: a box side must be above 0 m, not {s}"
            )));
        }
        Ok(())
    }
}

/// A database to query: what to call it, and where it is served.
#[derive(Clone, Debug)]
pub struct Served {
    /// Its name in the report (the file's name, say).
    pub label: String,
    /// The URL it is served at.
    pub url: String,
}

/// One step's figures, summed over a row's queries.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Cost {
    /// Pages the step read, through the client cache.
    pub reads: u64,
    /// Of those, pages the client did not hold and asked the server for.
    pub fetched: u64,
    pub requests: u64,
    pub round_trips: u64,
    pub bytes: u64,
}

impl Cost {
    fn of(s: &RemoteStats) -> Cost {
        Cost {
            reads: s.page_reads,
            fetched: s.pages_fetched,
            requests: s.requests,
            round_trips: s.round_trips,
            bytes: s.bytes,
        }
    }

    fn add(&mut self, o: Cost) {
        self.reads += o.reads;
        self.fetched += o.fetched;
        self.requests += o.requests;
        self.round_trips += o.round_trips;
        self.bytes += o.bytes;
    }
}

/// One database at one box side.
#[derive(Clone, Debug, serde::Serialize)]
pub struct LayoutRow {
    pub label: String,
    pub side: f32,
    pub queries: usize,
    /// Objects found, summed over the queries.
    pub objects: u64,
    /// The range query (the R-tree's pages).
    pub query: Cost,
    /// The found objects' coarsest stored levels.
    pub coarse: Cost,
    /// Their full meshes.
    pub full: Cost,
}

impl LayoutRow {
    fn mean(&self, x: u64) -> f64 {
        x as f64 / self.queries.max(1) as f64
    }
}

/// The experiment's rows.
#[derive(Clone, Debug, serde::Serialize)]
pub struct LayoutReport {
    pub config: LayoutBenchConfig,
    pub objects: u64,
    pub page_size: usize,
    pub rows: Vec<LayoutRow>,
}

/// Asks every database of `served` the same queries, placed at random in `city`'s
/// bounds. `progress` is told each database and side as it starts.
pub fn run(
    city: &Database,
    served: &[Served],
    cfg: &LayoutBenchConfig,
    mut progress: impl FnMut(&str),
) -> Result<LayoutReport> {
    cfg.validate()?;
    let bounds = city.bounds();
    let mut rows = Vec::new();
    for &side in &cfg.sides {
        let boxes = query_boxes(&bounds, side, cfg.queries, cfg.seed);
        for s in served {
            progress(&format!("{} at {side} m", s.label));
            let mut row = LayoutRow {
                label: s.label.clone(),
                side,
                queries: boxes.len(),
                objects: 0,
                query: Cost::default(),
                coarse: Cost::default(),
                full: Cost::default(),
            };
            for b in &boxes {
                let (objects, costs) = one_query(&s.url, b)?;
                row.objects += objects;
                row.query.add(costs[0]);
                row.coarse.add(costs[1]);
                row.full.add(costs[2]);
            }
            rows.push(row);
        }
    }
    Ok(LayoutReport {
        config: cfg.clone(),
        objects: city.objects(),
        page_size: city.store().page_size(),
        rows,
    })
}

/// `count` boxes of `side` metres at seeded random centres inside `bounds`, each
/// spanning its height.
fn query_boxes(bounds: &Aabb, side: f32, count: usize, seed: u64) -> Vec<Aabb> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (lo, hi) = (bounds.min, bounds.max);
    (0..count)
        .map(|_| {
            let x = rng.gen_range(lo.x..=hi.x);
            let z = rng.gen_range(lo.z..=hi.z);
            let h = side / 2.0;
            Aabb::new([x - h, lo.y, z - h], [x + h, hi.y, z + h])
                .expect("a finite box with min below max")
        })
        .collect()
}

/// One query from a cold client: the objects found and the cost of the query, the
/// coarse levels and the full meshes.
fn one_query(url: &str, b: &Aabb) -> Result<(u64, [Cost; 3])> {
    let db = Database::open_url_with(url, &HttpOptions::default())?;
    let stats = || db.remote_stats().unwrap_or_default();
    let opened = stats();
    let found = db.range(b)?.objects;
    let queried = stats();
    db.coarsest_meshes(&found)?;
    let coarse = stats();
    let extents: Vec<_> = found.iter().map(|o| o.mesh).collect();
    db.store().prefetch(&extents)?;
    for o in &found {
        db.mesh(o)?;
    }
    let full = stats();
    Ok((
        found.len() as u64,
        [
            Cost::of(&queried.since(&opened)),
            Cost::of(&coarse.since(&queried)),
            Cost::of(&full.since(&coarse)),
        ],
    ))
}

/// The plots' file names.
pub const PLOTS: [&str; 2] = ["layout-requests.png", "layout-bytes.png"];

impl Report for LayoutReport {
    fn name(&self) -> &'static str {
        "layout"
    }

    fn to_csv(&self) -> String {
        let mut s = String::from("database,side_m,queries,objects");
        for step in ["query", "coarse", "full"] {
            for f in ["reads", "fetched", "requests", "round_trips", "bytes"] {
                s.push_str(&format!(",{step}_{f}"));
            }
        }
        s.push('\n');
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{},{}",
                r.label, r.side, r.queries, r.objects
            ));
            for c in [r.query, r.coarse, r.full] {
                s.push_str(&format!(
                    ",{},{},{},{},{}",
                    c.reads, c.fetched, c.requests, c.round_trips, c.bytes
                ));
            }
            s.push('\n');
        }
        s
    }

    fn markdown(&self) -> String {
        let c = &self.config;
        let mut md = format!(
            "# The file's layout over HTTP (ours)\n\n{} objects, {} B pages. {} square \
             range queries per side at random places (seed {}), each from a cold client: \
             the query, then the found objects' coarsest stored levels, then their full \
             meshes. Per query, means: pages read, requests, round trips and KiB \
             moved.\n\n",
            self.objects, self.page_size, c.queries, c.seed
        );
        md.push_str("| database | side m | objects | query pages / req | coarse pages read | coarse requests | coarse round trips | coarse KiB | full pages read | full requests | full round trips | full KiB | bytes moved / bytes of pages fetched |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
        for r in &self.rows {
            let fetched =
                (r.query.fetched + r.coarse.fetched + r.full.fetched) * self.page_size as u64;
            let moved = r.query.bytes + r.coarse.bytes + r.full.bytes;
            md.push_str(&format!(
                "| {} | {} | {:.1} | {:.1} / {:.1} | {:.1} | {:.1} | {:.1} | {:.0} | {:.1} | {:.1} | {:.1} | {:.0} | {:.2} |\n",
                r.label,
                r.side,
                r.mean(r.objects),
                r.mean(r.query.reads),
                r.mean(r.query.requests),
                r.mean(r.coarse.reads),
                r.mean(r.coarse.requests),
                r.mean(r.coarse.round_trips),
                r.mean(r.coarse.bytes) / 1024.0,
                r.mean(r.full.reads),
                r.mean(r.full.requests),
                r.mean(r.full.round_trips),
                r.mean(r.full.bytes) / 1024.0,
                moved as f64 / fetched.max(1) as f64,
            ));
        }
        md.push_str(
            "\nPages read are the same in every order (the same objects, the same \
             extents); requests, round trips and bytes are what the order changes. Bytes \
             moved over bytes of the pages fetched say what bridging gaps between runs \
             cost. All figures are exact counts.\n",
        );
        md
    }

    fn plot(&self, dir: &Path) -> Result<()> {
        // Every side has a row per database, in the order they were given.
        let first = self.rows.first().map_or(0.0, |r| r.side);
        let labels: Vec<&str> = self
            .rows
            .iter()
            .filter(|r| r.side == first)
            .map(|r| r.label.as_str())
            .collect();
        let series = |f: &dyn Fn(&LayoutRow) -> f64| -> Vec<Series> {
            labels
                .iter()
                .map(|&label| Series {
                    name: label.to_string(),
                    points: self
                        .rows
                        .iter()
                        .filter(|r| r.label == label)
                        .map(|r| (f64::from(r.side), f(r)))
                        .collect(),
                })
                .collect()
        };
        line_plot(
            &dir.join(PLOTS[0]),
            &LinePlot {
                title: "Requests per query (coarse levels and full meshes)".into(),
                x_label: "query box side, m".into(),
                y_label: "requests".into(),
                series: series(&|r| r.mean(r.coarse.requests + r.full.requests)),
            },
        )?;
        line_plot(
            &dir.join(PLOTS[1]),
            &LinePlot {
                title: "KiB moved per query".into(),
                x_label: "query box side, m".into(),
                y_label: "KiB".into(),
                series: series(&|r| r.mean(r.query.bytes + r.coarse.bytes + r.full.bytes) / 1024.0),
            },
        )
    }
}

/// Serves nothing itself: the caller serves each database (any HTTP server with byte
/// ranges) and names it here.
pub fn served_at(label: &str, origin: SocketAddr, name: &str) -> Served {
    Served {
        label: label.to_string(),
        url: format!("http://{origin}/{name}"),
    }
}
