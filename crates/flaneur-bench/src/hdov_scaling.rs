//! The `hdov-scaling` experiment (Shou 2002 §5.8.4, Fig. 5.23): the HDoV-tree's search
//! against the naive method on generated cities of growing size, each built once with
//! LODs, visibility and the tree (`city_series`, kind `Hdov`) into a folder and reused.
//! On each city `hdov-search` runs with the settings given (its queries, its η), and
//! the indexed-vertical scheme's rows and the naive method's are kept: search pages and
//! total pages per query against the city's size.
//!
//! Cities of citygen's default layout grow wider at the same density, so a cell sees
//! about as much of a larger city as of a smaller one: what grows is the tree.

use std::path::Path;

use crate::city_series::{self, SeriesKind};
use crate::hdov_search::{self, HdovSearchConfig};
use crate::report::Report;
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::hdov::Scheme;

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct HdovScalingConfig {
    /// Objects in each city of the series.
    pub sizes: Vec<u64>,
    /// The citygen seed of the cities.
    pub city_seed: u64,
    /// Their page size, bytes.
    pub page_size: usize,
    /// The DoV's cube-map resolution of their visibility.
    pub resolution: u32,
    /// The search experiment run on each.
    pub search: HdovSearchConfig,
}

impl Default for HdovScalingConfig {
    fn default() -> Self {
        HdovScalingConfig {
            sizes: vec![250, 500, 1000],
            city_seed: 1,
            page_size: 4096,
            resolution: 32,
            search: HdovSearchConfig {
                queries: 1000,
                load_queries: 20,
                etas: vec![0.0, 0.001, 0.008],
                seed: 1,
            },
        }
    }
}

/// One method at one η on one city.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ScalingRow {
    pub objects: u64,
    /// "indexed" or "naive".
    pub method: String,
    pub eta: f32,
    /// The tree's nodes (0 for the naive method's rows).
    pub nodes: u32,
    /// Per query: the search's pages and ms, and (over the loaded queries) the total.
    pub search_pages: f64,
    pub search_ms: f64,
    pub total_pages: f64,
}

/// What the experiment measured.
#[derive(Clone, Debug, serde::Serialize)]
pub struct HdovScalingReport {
    pub config: HdovScalingConfig,
    pub rows: Vec<ScalingRow>,
}

/// Builds (or reuses) the cities in `dir` and runs the search on each;
/// `tick(done, total)` after each city.
pub fn run(
    dir: &Path,
    cfg: &HdovScalingConfig,
    mut tick: impl FnMut(usize, usize),
) -> Result<HdovScalingReport> {
    if cfg.sizes.is_empty() {
        return Err(Error::Invalid(
            "hdov-scaling needs at least one city size".into(),
        ));
    }
    cfg.search.validate()?;
    let kind = SeriesKind::Hdov {
        resolution: cfg.resolution,
    };
    let cities = city_series::ensure_of(
        dir,
        &cfg.sizes,
        cfg.city_seed,
        cfg.page_size,
        kind,
        |_, _| {},
    )?;
    let mut rows = Vec::new();
    for (i, city) in cities.iter().enumerate() {
        let db = Database::open(&city.path)?;
        let head = db.hdov_head()?;
        let (nodes, scheme) = (head.nodes, head.smallest_scheme()?);
        let r = hdov_search::run(&db, &cfg.search, |_, _| {})?;
        for row in r
            .rows
            .iter()
            .filter(|x| x.method == "naive" || x.method == scheme.name())
        {
            rows.push(ScalingRow {
                objects: city.objects,
                method: row.method.clone(),
                eta: row.eta,
                nodes: if row.method == "naive" { 0 } else { nodes },
                search_pages: row.search_pages,
                search_ms: row.search_ms,
                total_pages: row.total_pages,
            });
        }
        tick(i + 1, cities.len());
    }
    Ok(HdovScalingReport {
        config: cfg.clone(),
        rows,
    })
}

/// The plots' file names.
pub const PLOT_SEARCH: &str = "hdov-scaling-search.png";
pub const PLOT_TOTAL: &str = "hdov-scaling-total.png";

impl HdovScalingReport {
    /// Each (method, η) series, in the order met.
    fn series_keys(&self) -> Vec<(String, f32)> {
        let mut keys: Vec<(String, f32)> = Vec::new();
        for r in &self.rows {
            // The naive method's pages do not depend on η: one series.
            let key = (
                r.method.clone(),
                if r.method == "naive" { 0.0 } else { r.eta },
            );
            if !keys.contains(&key) {
                keys.push(key);
            }
        }
        keys
    }
}

impl Report for HdovScalingReport {
    fn name(&self) -> &'static str {
        "hdov-scaling"
    }

    fn to_csv(&self) -> String {
        let mut s = String::from("objects,method,eta,nodes,search_pages,search_ms,total_pages\n");
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{},{},{:.3},{:.4},{:.2}\n",
                r.objects, r.method, r.eta, r.nodes, r.search_pages, r.search_ms, r.total_pages
            ));
        }
        s
    }

    fn markdown(&self) -> String {
        let c = &self.config;
        let mut s = format!(
            "# HDoV-tree search against city size (Shou 2002 §5.8.4, Fig. 5.23)\n\n\
             Generated cities of {:?} objects (seed {}, {}-byte pages, DoV at {}²), each with \
             LODs, visibility and the HDoV-tree; on each, {} queries from random cells, the \
             first {} also reading what they found. Pages per query are exact counts; the \
             tree is searched through its {} scheme.\n\n\
             | objects | method | η | nodes | search pages | search ms | total pages |\n|---|---|---|---|---|---|---|\n",
            c.sizes,
            c.city_seed,
            c.page_size,
            c.resolution,
            c.search.queries,
            c.search.load_queries.min(c.search.queries),
            Scheme::Indexed.name()
        );
        for r in &self.rows {
            s.push_str(&format!(
                "| {} | {} | {} | {} | {:.1} | {:.3} | {:.1} |\n",
                r.objects, r.method, r.eta, r.nodes, r.search_pages, r.search_ms, r.total_pages
            ));
        }
        s.push_str(
            "\nThe thesis (Fig. 5.23): the HDoV-tree's search time and I/O grow slowly with the \
             size of the dataset, from 400 MB to 1.6 GB, and stay below the naive method's \
             total.\n",
        );
        s
    }

    fn plot(&self, dir: &Path) -> Result<()> {
        use crate::plot::{line_plot, LinePlot, Series};
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let series = |f: fn(&ScalingRow) -> f64| -> Vec<Series> {
            self.series_keys()
                .into_iter()
                .map(|(m, eta)| Series {
                    name: if m == "naive" {
                        m.clone()
                    } else {
                        format!("{m} η = {eta}")
                    },
                    points: self
                        .rows
                        .iter()
                        .filter(|r| r.method == m && (m == "naive" || r.eta == eta))
                        .filter(|r| m != "naive" || r.eta == self.rows[0].eta)
                        .map(|r| (r.objects as f64, f(r)))
                        .collect(),
                })
                .collect()
        };
        line_plot(
            &dir.join(PLOT_SEARCH),
            &LinePlot {
                title: "Search I/O per query against city size (Fig. 5.23)".into(),
                x_label: "objects".into(),
                y_label: "pages".into(),
                series: series(|r| r.search_pages),
            },
        )?;
        line_plot(
            &dir.join(PLOT_TOTAL),
            &LinePlot {
                title: "Total I/O per query against city size (Fig. 5.23b)".into(),
                x_label: "objects".into(),
                y_label: "pages".into(),
                series: series(|r| r.total_pages),
            },
        )
    }
}
