//! The `pvs-prefetch` experiment (Zheng 2007 §7.5, Table 7.2, Figs. 7.6–7.8): SNP
//! against PBNP on the thesis's synthetic city, a 9-entry client cache and
//! delta-transmission for both, along a random route and a route of straight lines —
//! prefetching transactions, cache swaps, objects sent per transaction and at each
//! step, and visual misses; beside them, PBNP swept over its region size, which the
//! thesis leaves open, and SNP, PBNP and LANP (ours, `flaneur::prefetch::pvs::Lanp`)
//! with transactions answered 0 to 8 steps after they are asked (`simulate_with_latency`).
//!
//! It runs on the synthetic PVS table (`synthetic`, how it is drawn is named there,
//! held in a `PvsTable`) and the two routes (`flaneur::prefetch::pvs::routes`); one seed
//! draws both, and `simulate` walks a route (§7.5); `report` writes the CSVs, the summary
//! and the plots. No database: the table and the
//! walks take well under a second. [`run_on_database`]
//! runs the same experiment over a database's precomputed visibility, every PVS record
//! read through the store, with route 2 drawn along the city's walkable cells
//! (`axis_route`).

use std::path::Path;

use crate::report::Report;
use flaneur::error::{Error, Result};
use flaneur::prefetch::pvs::routes::{axis_route, random_route, straight_route, RouteConfig};
use flaneur::prefetch::pvs::{
    check_border, Lanp, Pbnp, Position, PrefetchArea, PvsSource, Snp, StoredPvs, DEFAULT_BORDER,
    THESIS_CAPACITY,
};

use crate::pvs_stats::{measure, TableStats};

mod report;
mod sim;
pub mod synthetic;
mod table;

pub use sim::{simulate, simulate_with_latency, SimReport, SimTotals, StepRecord};
pub use synthetic::{SyntheticCity, SyntheticConfig};
pub use table::{PvsTable, MAX_CELLS};

/// One column of Zheng 2007 Table 7.2, with §7.5's objects per transaction and in the
/// first transaction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThesisColumn {
    /// 1 (random) or 2 (straight lines).
    pub route: u8,
    pub algorithm: &'static str,
    pub transactions: usize,
    pub swaps: usize,
    pub objects_per_transaction: f64,
    pub first_transaction_objects: usize,
}

/// Table 7.2 and §7.5, column by column.
pub const THESIS: [ThesisColumn; 4] = [
    ThesisColumn {
        route: 1,
        algorithm: "SNP",
        transactions: 585,
        swaps: 1785,
        objects_per_transaction: 30.0,
        first_transaction_objects: 158,
    },
    ThesisColumn {
        route: 1,
        algorithm: "PBNP",
        transactions: 487,
        swaps: 876,
        objects_per_transaction: 16.0,
        first_transaction_objects: 87,
    },
    ThesisColumn {
        route: 2,
        algorithm: "SNP",
        transactions: 600,
        swaps: 1797,
        objects_per_transaction: 29.0,
        first_transaction_objects: 153,
    },
    ThesisColumn {
        route: 2,
        algorithm: "PBNP",
        transactions: 600,
        swaps: 828,
        objects_per_transaction: 16.0,
        first_transaction_objects: 51,
    },
];

/// The thesis's column for `route` and `algorithm`.
pub fn thesis(route: u8, algorithm: &str) -> Option<&'static ThesisColumn> {
    THESIS
        .iter()
        .find(|t| t.route == route && t.algorithm == algorithm)
}

/// The region sizes swept by default, fractions of a cell's side.
pub const DEFAULT_BORDERS: [f64; 9] = [0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5];

/// The main CSV's extra companions, and the plots.
pub const STEPS_CSV: &str = "pvs-prefetch-steps.csv";
pub const REGIONS_CSV: &str = "pvs-prefetch-regions.csv";
pub const ROUTES_CSV: &str = "pvs-prefetch-routes.csv";
pub const ROUTES_PLOT: &str = "pvs-prefetch-routes.png";
pub const REGIONS_PLOT: &str = "pvs-prefetch-regions.png";
pub const MISSES_PLOT: &str = "pvs-prefetch-regions-misses.png";
pub const LATENCY_CSV: &str = "pvs-prefetch-latency.csv";
pub const LATENCY_MISSES_PLOT: &str = "pvs-prefetch-latency-misses.png";
pub const LATENCY_SWAPS_PLOT: &str = "pvs-prefetch-latency-swaps.png";

/// The latencies swept by default, steps from asking a transaction to its answer.
pub const DEFAULT_LATENCIES: [usize; 9] = [0, 1, 2, 3, 4, 5, 6, 7, 8];

/// The longest latency the experiment takes, steps: longer than a route is no walk.
pub const MAX_LATENCY: usize = 1000;

/// The algorithms of the latency sweep, in the order they are reported.
pub const LATENCY_ALGORITHMS: [&str; 3] = ["SNP", "PBNP", "LANP"];

/// The PNG of the objects sent at each step along `route` by `algorithm` (Figs. 7.7,
/// 7.8), and of the objects sent so far by both.
pub fn steps_plot(route: u8, algorithm: &str) -> String {
    format!("pvs-prefetch-route{route}-{}.png", algorithm.to_lowercase())
}

pub fn cumulative_plot(route: u8) -> String {
    format!("pvs-prefetch-route{route}-cumulative.png")
}

/// The settings of the experiment; the defaults are the thesis's.
#[derive(Clone, Debug, PartialEq)]
pub struct PvsPrefetchConfig {
    pub city: SyntheticConfig,
    /// Both routes' length; its seed draws them.
    pub route: RouteConfig,
    /// PBNP's region border, a fraction of the cell's side.
    pub border: f64,
    /// Client cache entries.
    pub capacity: usize,
    /// PBNP's region borders to sweep (none: no sweep).
    pub borders: Vec<f64>,
    /// Latencies, steps, to walk SNP, PBNP and LANP at (none: no sweep). LANP's band is
    /// `border`, and the viewer is taken to set off at a route's step (`Lanp::new`).
    pub latencies: Vec<usize>,
}

impl Default for PvsPrefetchConfig {
    fn default() -> PvsPrefetchConfig {
        PvsPrefetchConfig {
            city: SyntheticConfig::default(),
            route: RouteConfig::default(),
            border: DEFAULT_BORDER,
            capacity: THESIS_CAPACITY,
            borders: DEFAULT_BORDERS.to_vec(),
            latencies: DEFAULT_LATENCIES.to_vec(),
        }
    }
}

impl PvsPrefetchConfig {
    /// A clear error for settings the experiment cannot run.
    pub fn validate(&self) -> Result<()> {
        self.city.validate()?;
        self.route.validate()?;
        check_border(self.border)?;
        for &b in &self.borders {
            check_border(b)?;
        }
        Lanp::new(self.border, self.route.step)?;
        if let Some(l) = self.latencies.iter().find(|&&l| l > MAX_LATENCY) {
            return Err(Error::Pvs(format!(
                "a latency of {l} steps is more than the {MAX_LATENCY} the experiment takes"
            )));
        }
        if self.capacity < THESIS_CAPACITY {
            return Err(Error::Pvs(format!(
                "a client cache of {} entries is too small: it must hold the current cell and its 8 neighbours ({THESIS_CAPACITY})",
                self.capacity
            )));
        }
        Ok(())
    }
}

/// Both algorithms along one route.
#[derive(Clone, Debug)]
pub struct RouteRun {
    /// 1 (random) or 2 (straight lines).
    pub route: u8,
    pub positions: Vec<Position>,
    pub snp: SimReport,
    pub pbnp: SimReport,
    /// Pages SNP's walk and PBNP's read, over a database.
    pub pages: Option<[u64; 2]>,
}

impl RouteRun {
    pub fn name(&self) -> String {
        format!("route {}", self.route)
    }

    /// SNP's report, then PBNP's.
    pub fn reports(&self) -> [&SimReport; 2] {
        [&self.snp, &self.pbnp]
    }
}

/// PBNP with one region border along one route.
#[derive(Clone, Debug)]
pub struct SweepRow {
    pub border: f64,
    pub route: u8,
    pub totals: SimTotals,
}

/// One algorithm along one route with answers `latency` steps away.
#[derive(Clone, Debug)]
pub struct LatencyRow {
    pub route: u8,
    pub latency: usize,
    /// "SNP", "PBNP" or "LANP".
    pub algorithm: &'static str,
    pub totals: SimTotals,
}

/// Where the experiment ran.
#[derive(Clone, Debug, PartialEq)]
pub struct Place {
    /// What the report's title names: "a synthetic city", or a database.
    pub name: String,
    /// A paragraph on the city, its PVS table and the routes.
    pub description: String,
    /// A viewcell's side, metres.
    pub cell: f64,
}

/// What the experiment measured.
#[derive(Clone, Debug)]
pub struct PvsPrefetchReport {
    pub config: PvsPrefetchConfig,
    pub place: Place,
    pub stats: TableStats,
    /// Route 1, then route 2.
    pub routes: Vec<RouteRun>,
    pub sweep: Vec<SweepRow>,
    /// Route by route, latency by latency, SNP, PBNP then LANP.
    pub latency: Vec<LatencyRow>,
}

/// Draws the city and the routes and walks them.
pub fn run(cfg: &PvsPrefetchConfig) -> Result<PvsPrefetchReport> {
    cfg.validate()?;
    let city = SyntheticCity::generate(&cfg.city)?;
    let stats = measure(&city)?;
    let middle = cfg.city.blocks.div_ceil(2);
    let route1 = random_route(city.intersection(middle, middle), &cfg.route, |p| {
        Ok(city.on_walkway(p))
    })?;
    let route2 = straight_route(&city.street_grid(), &cfg.route)?.positions;
    let (routes, sweep, latency) = walk(&city, [route1, route2], cfg, || None)?;
    let c = &cfg.city;
    let place = Place {
        name: "a synthetic city".into(),
        description: format!(
            "City: {b} × {b} buildings of {} m, streets {} m, viewcells {} m: {} viewcells on a {g} × {g} grid, \
             PVS table drawn with seed {}. Routes: {} steps of {} m (seed {}); route 1 random from the central \
             crossing, route 2 seven straight lines with six right-angle turns. Client cache {} entries, \
             delta-transmission for both; PBNP's side and corner regions {} of a cell's side ({} m). \
             A cache swap is one cell evicted from the cache.",
            c.building,
            c.street,
            c.cell,
            stats.viewcells,
            c.seed,
            cfg.route.steps,
            cfg.route.step,
            cfg.route.seed,
            cfg.capacity,
            cfg.border,
            cfg.border * c.cell,
            b = c.blocks,
            g = (f64::from(c.blocks) * (c.building + c.street) + c.street) / c.cell,
        ),
        cell: c.cell,
    };
    Ok(PvsPrefetchReport {
        config: cfg.clone(),
        place,
        stats,
        routes,
        sweep,
        latency,
    })
}

/// Runs the experiment over `db`'s precomputed visibility (`name` says which database
/// in the report): both routes from the walkable viewcell nearest the city's centre,
/// route 1 random as on the synthetic city, route 2 along x and z (`axis_route`). The
/// PVS pages each walk reads are counted. `cfg.city` is not used.
pub fn run_on_database(
    db: &flaneur::Database,
    name: &str,
    cfg: &PvsPrefetchConfig,
) -> Result<PvsPrefetchReport> {
    cfg.validate()?;
    let source = StoredPvs::new(db)?;
    let stats = measure(&source)?;
    let head = db.visibility()?.expect("StoredPvs checked it");
    let centre = db.bounds().center();
    let start = source
        .walkable_centres()?
        .into_iter()
        .min_by(|a, b| {
            let d =
                |p: &Position| (p.x - centre.x as f64).powi(2) + (p.z - centre.z as f64).powi(2);
            d(a).total_cmp(&d(b))
        })
        .ok_or_else(|| Error::Pvs("the database has no walkable viewcell".into()))?;
    // Walkable as the walk will see it: by the prefetcher's grid, whose arithmetic
    // decides a position exactly on a cell border the same way here and there.
    let walkable = |p: Position| match source.grid().cell_of(p) {
        Ok(cell) => source.is_viewcell(cell),
        Err(_) => Ok(false),
    };
    let route1 = random_route(start, &cfg.route, walkable)?;
    let route2 = axis_route(start, &cfg.route, walkable)?;
    let (routes, sweep, latency) =
        walk(&source, [route1, route2], cfg, || Some(db.io().page_reads))?;
    let cell = source.grid().cell_size();
    let place = Place {
        name: name.into(),
        description: format!(
            "{name}: {} walkable viewcells of {cell} m on a {} × {} grid, each cell's PVS read from the \
             database's precomputed visibility through the store; {} objects in the scene. Routes: {} steps \
             of {} m (seed {}) from the walkable cell nearest the centre; route 1 random, route 2 straight \
             lines along x and z with right-angle turns (more than seven where buildings cut them short). \
             Client cache {} entries, delta-transmission for both; PBNP's side and corner regions {} of a \
             cell's side ({} m). A cache swap is one cell evicted from the cache. The thesis's figures, in \
             brackets, are for its synthetic city.",
            stats.viewcells,
            head.grid.rows(),
            head.grid.columns(),
            stats.scene_objects,
            cfg.route.steps,
            cfg.route.step,
            cfg.route.seed,
            cfg.capacity,
            cfg.border,
            cfg.border * cell,
        ),
        cell,
    };
    Ok(PvsPrefetchReport {
        config: cfg.clone(),
        place,
        stats,
        routes,
        sweep,
        latency,
    })
}

type Walked = (Vec<RouteRun>, Vec<SweepRow>, Vec<LatencyRow>);

/// SNP and PBNP along both routes over `source`, then PBNP at each swept border, then
/// SNP, PBNP and LANP at each swept latency; `pages` reads a page counter, if there
/// is one.
fn walk<S: PvsSource + ?Sized>(
    source: &S,
    positions: [Vec<Position>; 2],
    cfg: &PvsPrefetchConfig,
    pages: impl Fn() -> Option<u64>,
) -> Result<Walked> {
    let pbnp = Pbnp::new(cfg.border)?;
    let counted = |rule: &dyn flaneur::prefetch::pvs::PrefetchArea,
                   positions: &[Position]|
     -> Result<(SimReport, Option<u64>)> {
        let before = pages();
        let report = simulate(source, rule, positions, cfg.capacity)?;
        Ok((report, before.zip(pages()).map(|(a, b)| b - a)))
    };
    let mut routes = Vec::new();
    for (route, positions) in (1..).zip(positions) {
        let (snp, snp_pages) = counted(&Snp, &positions)?;
        let (pbnp, pbnp_pages) = counted(&pbnp, &positions)?;
        routes.push(RouteRun {
            route,
            snp,
            pbnp,
            pages: snp_pages.zip(pbnp_pages).map(|(a, b)| [a, b]),
            positions,
        });
    }
    let mut sweep = Vec::new();
    for &border in &cfg.borders {
        for r in &routes {
            let totals = simulate(source, &Pbnp::new(border)?, &r.positions, cfg.capacity)?.totals;
            sweep.push(SweepRow {
                border,
                route: r.route,
                totals,
            });
        }
    }
    let lanp = Lanp::new(cfg.border, cfg.route.step)?;
    let rules: [&dyn PrefetchArea; 3] = [&Snp, &pbnp, &lanp];
    let mut latency = Vec::new();
    for r in &routes {
        for &l in &cfg.latencies {
            for rule in rules {
                let totals =
                    simulate_with_latency(source, rule, &r.positions, cfg.capacity, l)?.totals;
                latency.push(LatencyRow {
                    route: r.route,
                    latency: l,
                    algorithm: rule.name(),
                    totals,
                });
            }
        }
    }
    Ok((routes, sweep, latency))
}

/// The change from `from` to `to`, as a percentage of `from`.
fn change(from: f64, to: f64) -> String {
    if from == 0.0 {
        "—".into()
    } else {
        format!("{:+.0} %", 100.0 * (to - from) / from)
    }
}

impl PvsPrefetchReport {
    /// Objects sent at each step (Figs. 7.7, 7.8): one column per route and algorithm.
    pub fn steps_csv(&self) -> String {
        let mut s = String::from("step");
        for r in &self.routes {
            for rep in r.reports() {
                s.push_str(&format!(
                    ",route{}_{}",
                    r.route,
                    rep.algorithm.to_lowercase()
                ));
            }
        }
        s.push('\n');
        let n = self
            .routes
            .iter()
            .map(|r| r.positions.len())
            .max()
            .unwrap_or(0);
        for i in 0..n {
            s.push_str(&i.to_string());
            for r in &self.routes {
                for rep in r.reports() {
                    match rep.steps.get(i) {
                        Some(st) => s.push_str(&format!(",{}", st.objects_sent)),
                        None => s.push(','),
                    }
                }
            }
            s.push('\n');
        }
        s
    }

    /// PBNP against its region border.
    pub fn regions_csv(&self) -> String {
        let side = self.place.cell;
        let mut s = String::from(
            "border,band_m,route,transactions,cache_swaps,objects_per_transaction,first_transaction_objects,visual_misses,late_entries\n",
        );
        for w in &self.sweep {
            let t = &w.totals;
            s.push_str(&format!(
                "{},{},{},{},{},{:.2},{},{},{}\n",
                w.border,
                w.border * side,
                w.route,
                t.transactions,
                t.swaps,
                t.objects_per_transaction(),
                t.first_transaction_objects,
                t.visual_misses,
                t.late_entries
            ));
        }
        s
    }

    /// SNP, PBNP and LANP against the latency.
    pub fn latency_csv(&self) -> String {
        let mut s = String::from(
            "route,algorithm,latency,transactions,cache_swaps,objects_sent,objects_per_transaction,visual_misses,miss_steps,late_entries,cells_entered,cells_requested,peak_cached_cells,peak_held_objects\n",
        );
        for w in &self.latency {
            let t = &w.totals;
            s.push_str(&format!(
                "{},{},{},{},{},{},{:.2},{},{},{},{},{},{},{}\n",
                w.route,
                w.algorithm,
                w.latency,
                t.transactions,
                t.swaps,
                t.objects_sent,
                t.objects_per_transaction(),
                t.visual_misses,
                t.miss_steps,
                t.late_entries,
                t.cells_entered,
                t.cells_requested,
                t.peak_cached_cells,
                t.peak_held_objects
            ));
        }
        s
    }

    /// The latency sweep's row for `route`, `latency` and `algorithm`.
    pub fn at_latency(&self, route: u8, latency: usize, algorithm: &str) -> Option<&SimTotals> {
        self.latency
            .iter()
            .find(|w| w.route == route && w.latency == latency && w.algorithm == algorithm)
            .map(|w| &w.totals)
    }

    /// The routes' positions (Fig. 7.6).
    pub fn routes_csv(&self) -> String {
        let mut s = String::from("step");
        for r in &self.routes {
            s.push_str(&format!(",route{0}_x,route{0}_z", r.route));
        }
        s.push('\n');
        let n = self
            .routes
            .iter()
            .map(|r| r.positions.len())
            .max()
            .unwrap_or(0);
        for i in 0..n {
            s.push_str(&i.to_string());
            for r in &self.routes {
                match r.positions.get(i) {
                    Some(p) => s.push_str(&format!(",{:.3},{:.3}", p.x, p.z)),
                    None => s.push_str(",,"),
                }
            }
            s.push('\n');
        }
        s
    }
}

#[cfg(test)]
mod city_tests;
#[cfg(test)]
mod route_tests;
#[cfg(test)]
mod tests;
