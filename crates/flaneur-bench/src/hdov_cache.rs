//! The `hdov-cache` experiment (Shou 2002 §5.7, §5.8.3, Figs. 5.15–5.20): the hit rate
//! of a cache of HDoV-tree nodes (their view-invariant part only; V-pages and objects
//! are not cached) against its size in pages, under LRU, DoV and DoV-Time (κ = 0.001, T
//! counted in searches), with Belady's offline optimum as the ceiling; for continuous
//! queries (a chain of neighbouring viewcells, as a walk visits them) and random ones,
//! at η ∈ {1e-5, 1e-4, 5e-4}.
//!
//! Approach, named: each query set and η is searched once through a cache large enough
//! for the whole tree, its node accesses recorded (with each node's level and DoV in the
//! cell); every policy and size is then a replay of that trace, which gives exactly the
//! counts a live cache of that size and policy would (`cache::Trace::replay`). The
//! continuous chain is a random walk over the walkable cells, each step to a walkable
//! side neighbour (staying put when there is none); both sets come from one ChaCha8 generator of a fixed seed.

use std::path::Path;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::report::Report;
use flaneur::cache::{belady_replay, policy_by_name, BufferPool, Trace};
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::hdov::Scheme;

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct HdovCacheConfig {
    /// Queries of each set (the thesis: 4,000 continuous and 4,000 random).
    pub queries: usize,
    pub etas: Vec<f32>,
    /// Cache sizes, in node pages.
    pub sizes: Vec<usize>,
    /// The online policies, by `cache::policy_by_name`'s names.
    pub policies: Vec<String>,
    pub seed: u64,
}

impl Default for HdovCacheConfig {
    fn default() -> Self {
        HdovCacheConfig {
            queries: 4000,
            etas: vec![1e-5, 1e-4, 5e-4],
            sizes: vec![10, 25, 50, 100, 200, 400],
            policies: vec!["lru".into(), "dov".into(), "dovtime".into()],
            seed: 1,
        }
    }
}

impl HdovCacheConfig {
    /// Checks the settings, naming a bad one.
    pub fn validate(&self) -> Result<()> {
        if self.queries == 0 || self.sizes.is_empty() || self.sizes.contains(&0) {
            return Err(Error::Invalid(format!(
                "hdov-cache needs queries and cache sizes above 0 (got {} queries, sizes {:?})",
                self.queries, self.sizes
            )));
        }
        if self.etas.iter().any(|e| !(e.is_finite() && *e >= 0.0)) {
            return Err(Error::Invalid(format!(
                "hdov-cache thresholds {:?}",
                self.etas
            )));
        }
        for p in &self.policies {
            policy_by_name(p)?;
        }
        Ok(())
    }
}

/// One query set, η, size and policy.
#[derive(Clone, Debug, serde::Serialize)]
pub struct HdovCacheRow {
    /// "continuous" or "random".
    pub queries: String,
    pub eta: f32,
    pub size: usize,
    /// A policy's name, or "belady".
    pub policy: String,
    pub hit_rate: f64,
    /// The trace's node accesses and distinct nodes (its working set).
    pub accesses: usize,
    pub working_set: usize,
}

/// What the experiment measured.
#[derive(Clone, Debug, serde::Serialize)]
pub struct HdovCacheReport {
    pub config: HdovCacheConfig,
    pub nodes: u32,
    pub cells: usize,
    pub scheme: Scheme,
    pub rows: Vec<HdovCacheRow>,
}

/// `n` random walkable cells, and a chain of `n` neighbouring ones, of a grid with
/// `columns` columns whose walkable cells are `cells` (ascending).
pub fn query_sets(cells: &[u32], columns: u32, n: usize, seed: u64) -> (Vec<u32>, Vec<u32>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let random = crate::hdov_search::draw_cells(cells, n, &mut rng);
    let walkable = |id: i64| id >= 0 && cells.binary_search(&(id as u32)).is_ok();
    let mut at = cells[rng.gen_range(0..cells.len())];
    let mut chain = Vec::with_capacity(n);
    for _ in 0..n {
        chain.push(at);
        let (r, c) = ((at / columns) as i64, (at % columns) as i64);
        let steps: Vec<i64> = [(r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)]
            .into_iter()
            .filter(|&(r, c)| r >= 0 && c >= 0 && c < columns as i64)
            .map(|(r, c)| r * columns as i64 + c)
            .filter(|&id| walkable(id))
            .collect();
        if !steps.is_empty() {
            at = steps[rng.gen_range(0..steps.len())] as u32;
        }
    }
    (chain, random)
}

/// Runs the experiment on `db` (built with `--visibility --hdov`) through its smallest
/// scheme; `tick` is told each (query set, η) traced, of how many.
pub fn run(
    db: &Database,
    cfg: &HdovCacheConfig,
    mut tick: impl FnMut(usize, usize),
) -> Result<HdovCacheReport> {
    cfg.validate()?;
    let head = db.hdov_head()?;
    let (nodes, cells) = (head.nodes, head.cells.clone());
    let scheme = head.smallest_scheme()?;
    let columns = db
        .visibility()?
        .ok_or_else(|| Error::Invalid("an HDoV-tree without visibility".into()))?
        .grid
        .columns();
    let (chain, random) = query_sets(&cells, columns, cfg.queries, cfg.seed);
    let steps = 2 * cfg.etas.len();
    let mut rows = Vec::new();
    let mut done = 0;
    for (name, set) in [("continuous", &chain), ("random", &random)] {
        for &eta in &cfg.etas {
            let trace = record(db, set, eta, scheme, nodes)?;
            let (accesses, working_set) = (trace.len(), trace.distinct_pages());
            let row = |policy: &str, size: usize, hit_rate: f64| HdovCacheRow {
                queries: name.into(),
                eta,
                size,
                policy: policy.into(),
                hit_rate,
                accesses,
                working_set,
            };
            for &size in &cfg.sizes {
                for p in &cfg.policies {
                    let stats = trace.replay(policy_by_name(p)?, size);
                    rows.push(row(p, size, stats.hit_rate()));
                }
                rows.push(row("belady", size, belady_replay(&trace, size).hit_rate()));
            }
            done += 1;
            tick(done, steps);
        }
    }
    Ok(HdovCacheReport {
        config: cfg.clone(),
        nodes,
        cells: cells.len(),
        scheme,
        rows,
    })
}

/// The node accesses of searching `cells` in order under `eta`.
fn record(db: &Database, cells: &[u32], eta: f32, scheme: Scheme, nodes: u32) -> Result<Trace> {
    let whole = nodes as usize * db.store().page_size();
    let pool = BufferPool::new(db.store(), whole, policy_by_name("lru")?)?;
    pool.set_trace(true);
    for &cell in cells {
        db.hdov_search_cached(cell, eta, scheme, Some(&pool))?;
    }
    Ok(pool.take_trace())
}

/// The plot's file for a query set.
pub fn plot_file(queries: &str) -> String {
    format!("hdov-cache-{queries}.png")
}

impl Report for HdovCacheReport {
    fn name(&self) -> &'static str {
        "hdov-cache"
    }

    /// One line per query set, η, size and policy.
    fn to_csv(&self) -> String {
        let mut s = String::from("queries,eta,size,policy,hit_rate,accesses,working_set\n");
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{},{},{:.4},{},{}\n",
                r.queries, r.eta, r.size, r.policy, r.hit_rate, r.accesses, r.working_set
            ));
        }
        s
    }

    fn markdown(&self) -> String {
        let c = &self.config;
        let mut s = format!(
            "# HDoV node caches (Shou 2002 §5.7, Figs. 5.15–5.20)\n\n\
             {} continuous and {} random queries over {} viewcells, an HDoV-tree of {} nodes \
             searched through the {} scheme; hit rates of node caches (view-invariant nodes \
             only) by size in pages.\n",
            c.queries,
            c.queries,
            self.cells,
            self.nodes,
            self.scheme.name()
        );
        let mut policies = c.policies.clone();
        policies.push("belady".into());
        for set in ["continuous", "random"] {
            for &eta in &c.etas {
                let at: Vec<&HdovCacheRow> = self
                    .rows
                    .iter()
                    .filter(|r| r.queries == set && r.eta == eta)
                    .collect();
                let Some(first) = at.first() else { continue };
                s.push_str(&format!(
                    "\n## {set} queries, η = {eta} ({} node accesses, working set {} nodes)\n\n| size |",
                    first.accesses, first.working_set
                ));
                for p in &policies {
                    s.push_str(&format!(" {p} |"));
                }
                s.push_str(&format!("\n|---|{}\n", "---|".repeat(policies.len())));
                for &size in &c.sizes {
                    s.push_str(&format!("| {size} |"));
                    for p in &policies {
                        match at.iter().find(|r| r.size == size && &r.policy == p) {
                            Some(r) => s.push_str(&format!(" {:.3} |", r.hit_rate)),
                            None => s.push_str(" – |"),
                        }
                    }
                    s.push('\n');
                }
            }
        }
        s.push_str(
            "\nThe thesis (Figs. 5.15–5.20): DoV and DoV-Time beat LRU when the cache is \
             smaller than the nodes a search round touches, LRU catching up as the cache \
             grows; Belady bounds them all.\n",
        );
        s
    }

    fn plot(&self, dir: &Path) -> Result<()> {
        use crate::plot::{line_plot, LinePlot, Series};
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let c = &self.config;
        let mut policies = c.policies.clone();
        policies.push("belady".into());
        for set in ["continuous", "random"] {
            let mut series = Vec::new();
            for &eta in &c.etas {
                for p in &policies {
                    series.push(Series {
                        name: format!("{p} η={eta}"),
                        points: self
                            .rows
                            .iter()
                            .filter(|r| r.queries == set && r.eta == eta && &r.policy == p)
                            .map(|r| (r.size as f64, r.hit_rate))
                            .collect(),
                    });
                }
            }
            line_plot(
                &dir.join(plot_file(set)),
                &LinePlot {
                    title: format!("HDoV node cache hit rate, {set} queries"),
                    x_label: "cache size (node pages)".into(),
                    y_label: "hit rate".into(),
                    series,
                },
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chain_steps_between_neighbours_and_the_random_set_covers_the_cells() {
        // A 4 × 5 grid whose walkable cells are a cross and a lone corner.
        let cells = [2, 7, 10, 11, 12, 13, 14, 17, 19];
        let (chain, random) = query_sets(&cells, 5, 400, 3);
        assert_eq!((chain.len(), random.len()), (400, 400));
        for w in chain.windows(2) {
            let (a, b) = (w[0] as i64, w[1] as i64);
            assert!(
                a == b || (a - b).abs() == 1 || (a - b).abs() == 5,
                "{a} → {b}"
            );
        }
        assert!(random.iter().all(|c| cells.contains(c)));
        assert!(cells.iter().all(|c| random.contains(c)));
    }
}
