//! Search time against database size (Shou 2002 §4.4.2, Fig. 4.22): the mean time per
//! query of the Optimal configuration against BOX, on cities of growing size.
//!
//! The cities are a generated series (`bench::city_series`: citygen's default layout,
//! so a larger city is a wider one of the same density), built once into a folder and
//! reused. On each, both configurations walk the same pattern with the same seed — the
//! path differs from city to city, as the city's extent does.
//!
//! The search time plotted is the mean time of the index searches the viewer waited for
//! (`walk_setup::mean_search_ms`): the walk times a search only on the frame's thread,
//! and there it times the search alone, in either configuration. Beside it stands the
//! viewer's mean wait per query (`walk_setup::mean_query_ms`), which for Optimal also
//! holds the waits for prefetches still running, meshes included, so it does not
//! compare with BOX's. Times are wall-clock and noisy; the index pages read per query
//! are exact counts.

use std::path::Path;

use crate::city_series::{self, SeriesCity};
use crate::report::Report;
use crate::walk_setup::{
    check_sweep, describe_review, label, mean_query_ms, mean_search_ms, num, per_query,
    searches_timed, walk_path, WalkSetup,
};
use flaneur::build::BuildOptions;
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::path::motion::Motion;
use flaneur::walk::review::{Preset, WalkReport};
use flaneur::walk::NoSink;

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DbSizeConfig {
    /// The walk on every city: one path, of the one pattern in `walk.patterns` (normal
    /// by default), at `walk.sf`.
    pub walk: WalkSetup,
    /// Objects in each city of the series.
    pub sizes: Vec<u64>,
    /// The citygen seed of the cities.
    pub city_seed: u64,
    /// Page size of the cities' databases, bytes.
    pub page_size: usize,
}

/// The series walked by default: doubling from 2,500 objects to the demo's 20,000.
pub const DEFAULT_SIZES: [u64; 4] = [2_500, 5_000, 10_000, 20_000];

/// The two configurations of the figure, in the order of the report.
pub const PRESETS: [Preset; 2] = [Preset::Optimal, Preset::Box];

impl Default for DbSizeConfig {
    fn default() -> DbSizeConfig {
        DbSizeConfig {
            walk: WalkSetup::short(Motion::Normal),
            sizes: DEFAULT_SIZES.to_vec(),
            city_seed: citygen::CityConfig::default().seed,
            page_size: BuildOptions::default().page_size,
        }
    }
}

impl DbSizeConfig {
    /// Checks the walk (one pattern) and the sizes (at least one, none zero, none twice).
    pub fn validate(&self) -> Result<()> {
        self.walk.validate()?;
        self.walk.single_pattern("the database-size walk")?;
        check_sweep("database size", &self.sizes, |objects| {
            if objects == 0 {
                return Err(Error::Invalid(
                    "a city of the database-size series needs at least one object".into(),
                ));
            }
            Ok(())
        })
    }
}

/// One configuration on one city.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DbSizeRow {
    pub objects: u64,
    pub preset: Preset,
    /// Pages of the city's database, and the height of its R-tree.
    pub db_pages: u64,
    pub tree_height: u32,
    pub queries: usize,
    /// Mean time of the index searches the viewer waited for, ms, and how many there were.
    pub mean_search_ms: f64,
    pub searches_timed: usize,
    /// The viewer's mean wait per query, ms.
    pub mean_query_ms: f64,
    pub index_pages: u64,
    pub index_per_query: f64,
    /// Index and mesh pages per query.
    pub io_per_query: f64,
    pub mean_frame_ms: f64,
}

/// The whole series.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DbSizeReport {
    pub config: DbSizeConfig,
    /// The cities, smallest first.
    pub cities: Vec<SeriesCity>,
    /// City by city, smallest first, each in the order of [`PRESETS`].
    pub rows: Vec<DbSizeRow>,
}

/// The files [`DbSizeReport::plot`] writes: Fig. 4.22, and index pages per query.
pub const TIME_PLOT_FILE: &str = "csearch-db-size-search-time.png";
pub const PAGES_PLOT_FILE: &str = "csearch-db-size-pages.png";

/// Runs the experiment, with the cities in (or built into) `cities_dir`.
pub fn run(cities_dir: &Path, cfg: &DbSizeConfig) -> Result<DbSizeReport> {
    run_with_progress(cities_dir, cfg, |_, _| {})
}

/// Runs the experiment; `progress(done, total)` is told after each city is ready and
/// after each walk.
pub fn run_with_progress(
    cities_dir: &Path,
    cfg: &DbSizeConfig,
    mut progress: impl FnMut(usize, usize),
) -> Result<DbSizeReport> {
    cfg.validate()?;
    let pattern = cfg.walk.single_pattern("the database-size walk")?;
    let mut sizes = cfg.sizes.clone();
    sizes.sort_unstable();
    let total = sizes.len() * (1 + PRESETS.len());
    let mut done = 0;
    let cities = city_series::ensure(cities_dir, &sizes, cfg.city_seed, cfg.page_size, |_, _| {
        done += 1;
        progress(done, total);
    })?;
    let mut rows = Vec::with_capacity(sizes.len() * PRESETS.len());
    for city in &cities {
        let db = Database::open(&city.path)?;
        let path = cfg.walk.path(&db, pattern)?;
        for preset in PRESETS {
            let walk: WalkReport = walk_path(&db, &path, cfg.walk.review(preset), &mut NoSink)?;
            let s = &walk.summary;
            rows.push(DbSizeRow {
                objects: city.objects,
                preset,
                db_pages: db.store().page_count(),
                tree_height: db.tree().height,
                queries: s.queries,
                mean_search_ms: mean_search_ms(&walk),
                searches_timed: searches_timed(&walk),
                mean_query_ms: mean_query_ms(&walk),
                index_pages: s.index_pages,
                index_per_query: per_query(s.index_pages, s.queries),
                io_per_query: per_query(s.index_pages + s.mesh_pages, s.queries),
                mean_frame_ms: s.mean_frame_ms,
            });
            done += 1;
            progress(done, total);
        }
    }
    Ok(DbSizeReport {
        config: cfg.clone(),
        cities,
        rows,
    })
}

impl DbSizeReport {
    /// The row of `preset` on the city of `objects` objects.
    pub fn row(&self, objects: u64, preset: Preset) -> Option<&DbSizeRow> {
        self.rows
            .iter()
            .find(|r| r.objects == objects && r.preset == preset)
    }
}

impl Report for DbSizeReport {
    fn name(&self) -> &'static str {
        "csearch-db-size"
    }

    /// One line per city and configuration.
    fn to_csv(&self) -> String {
        let mut s = String::from(
            "objects,configuration,db_pages,tree_height,queries,searches_timed,mean_search_ms,mean_query_ms,index_pages,index_per_query,io_per_query,mean_frame_ms\n",
        );
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{},{},{},{},{:.4},{:.4},{},{:.2},{:.2},{:.4}\n",
                r.objects,
                r.preset.name(),
                r.db_pages,
                r.tree_height,
                r.queries,
                r.searches_timed,
                r.mean_search_ms,
                r.mean_query_ms,
                r.index_pages,
                r.index_per_query,
                r.io_per_query,
                r.mean_frame_ms
            ));
        }
        s
    }

    /// Fig. 4.22 (mean search time) and index pages per query, each against the number
    /// of objects with a line per configuration; written to [`TIME_PLOT_FILE`] and
    /// [`PAGES_PLOT_FILE`] in `dir` (created if missing).
    fn plot(&self, dir: &Path) -> Result<()> {
        use super::plot::{line_plot, LinePlot, Series};
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let series = |by: fn(&DbSizeRow) -> f64| -> Vec<Series> {
            PRESETS
                .iter()
                .map(|&p| Series {
                    name: label(p).into(),
                    points: self
                        .rows
                        .iter()
                        .filter(|r| r.preset == p)
                        .map(|r| (r.objects as f64, by(r)))
                        .collect(),
                })
                .collect()
        };
        line_plot(
            &dir.join(TIME_PLOT_FILE),
            &LinePlot {
                title: "Mean search time per query against database size (Fig. 4.22)".into(),
                x_label: "objects in the database".into(),
                y_label: "mean search time per query (ms)".into(),
                series: series(|r| r.mean_search_ms),
            },
        )?;
        line_plot(
            &dir.join(PAGES_PLOT_FILE),
            &LinePlot {
                title: "Index pages read per query against database size".into(),
                x_label: "objects in the database".into(),
                y_label: "index pages per query".into(),
                series: series(|r| r.index_per_query),
            },
        )
    }

    /// The figures beside the thesis's Fig. 4.22, described in words (it gives no numbers).
    fn markdown(&self) -> String {
        let c = &self.config;
        let mut s = String::from(
            "## Search time against database size, Optimal against BOX (Shou 2002, Fig. 4.22)\n\n",
        );
        s.push_str(&format!(
            "Cities generated by citygen (seed {}, its default layout: a larger city is a wider one), {}-byte pages; \
             on each, one {} walk: {}, SF {}. Optimal: {}; BOX: {}.\n\n",
            c.city_seed,
            c.page_size,
            c.walk.patterns.iter().map(|p| p.name()).collect::<Vec<_>>().join(", "),
            c.walk.describe(),
            num(c.walk.sf),
            describe_review(&c.walk.review(Preset::Optimal)),
            describe_review(&c.walk.review(Preset::Box))
        ));
        s.push_str(
            "| objects | pages | tree height | configuration | queries | search, ms (searches timed) | wait per query, ms | index pages / query | disk I/Os / query |\n\
             |---|---|---|---|---|---|---|---|---|\n",
        );
        for r in &self.rows {
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} | {:.3} ({}) | {:.3} | {:.1} | {:.0} |\n",
                r.objects,
                r.db_pages,
                r.tree_height,
                label(r.preset),
                r.queries,
                r.mean_search_ms,
                r.searches_timed,
                r.mean_query_ms,
                r.index_per_query,
                r.io_per_query
            ));
        }
        let below = |by: fn(&DbSizeRow) -> f64| {
            self.cities
                .iter()
                .filter(|c| matches!((self.row(c.objects, Preset::Optimal), self.row(c.objects, Preset::Box)), (Some(o), Some(b)) if by(o) < by(b)))
                .count()
        };
        s.push_str(&format!(
            "\nSearch: the mean time of the index searches the viewer waited for (those not answered by a prefetch); \
             wait: the viewer's mean wait per query, which for Optimal holds prefetches still running, meshes \
             included. Here Optimal's search time is below BOX's on {} of {} cities, its index pages per query on {}.\n",
            below(|r| r.mean_search_ms),
            self.cities.len(),
            below(|r| r.index_per_query)
        ));
        if self
            .rows
            .iter()
            .any(|r| r.preset == Preset::Optimal && r.searches_timed <= 1)
        {
            s.push_str(
                "Where Optimal timed a single search it is the walk's first, a full search like BOX's (every later \
                 one came from a prefetch): a longer walk (more frames) gives its search time a meaning.\n",
            );
        }
        s.push_str(
            "\nThe thesis (Fig. 4.22): Optimal's average search time is below BOX's on every database size it tried. \
             It gives no numbers, and does not say how it made its smaller databases.\n",
        );
        s
    }
}
