//! The simulation of §7.5: one client walks a route position by position, and every
//! position's transaction is counted. Deterministic: the same table, rule and route
//! give the same counts.

use flaneur::error::{Error, Result};
use flaneur::prefetch::pvs::{Cell, Position, PrefetchArea, PvsClient, PvsSource};

/// What one position of the route cost.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StepRecord {
    /// 0 for the start, then one per step.
    pub step: usize,
    pub cell: Cell,
    pub transaction: bool,
    /// PVS rows requested.
    pub cells_requested: usize,
    /// ΔS: objects sent.
    pub objects_sent: usize,
    /// Cache entries replaced.
    pub swaps: usize,
    pub visual_misses: usize,
    /// Entries cached and objects held after the step.
    pub cached_cells: usize,
    pub held_objects: usize,
}

/// A whole route's counts.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct SimTotals {
    /// Positions walked (steps + 1, the start included).
    pub positions: usize,
    /// Prefetching transactions, the start-up one included.
    pub transactions: usize,
    /// Cache swaps: entries replaced in the cache, one per evicted cell.
    pub swaps: usize,
    pub objects_sent: usize,
    pub cells_requested: usize,
    /// Objects sent by the start-up transaction (the thesis reports it apart).
    pub first_transaction_objects: usize,
    /// Cells entered after the start, and those entered before their PVS was held.
    pub cells_entered: usize,
    pub late_entries: usize,
    /// Objects missing on entering a cell, summed over the route.
    pub visual_misses: usize,
    pub peak_cached_cells: usize,
    pub peak_held_objects: usize,
}

impl SimTotals {
    /// Objects sent per transaction, the start-up one included (0 with none).
    pub fn objects_per_transaction(&self) -> f64 {
        if self.transactions == 0 {
            0.0
        } else {
            self.objects_sent as f64 / self.transactions as f64
        }
    }

    /// Objects sent per transaction after the start-up one.
    pub fn objects_per_later_transaction(&self) -> f64 {
        if self.transactions <= 1 {
            0.0
        } else {
            (self.objects_sent - self.first_transaction_objects) as f64
                / (self.transactions - 1) as f64
        }
    }
}

/// One rule's walk along one route.
#[derive(Clone, Debug, PartialEq)]
pub struct SimReport {
    pub algorithm: &'static str,
    pub capacity: usize,
    pub steps: Vec<StepRecord>,
    pub totals: SimTotals,
}

/// Walks `route` with a client of `capacity` cache entries using `rule`.
///
/// ```
/// use flaneur::prefetch::pvs::{Cell, Pbnp, Position, Snp, ViewcellGrid};
/// use flaneur_bench::pvs_prefetch::{simulate, PvsTable};
/// let grid = ViewcellGrid::new(Position::new(0.0, 0.0), 20.0, 3, 10)?;
/// let mut table = PvsTable::new(grid, 100)?;
/// for row in 0..3 {
///     for col in 0..10u32 {
///         table.insert(Cell::new(row, col), (col as u64 * 5..col as u64 * 5 + 20).collect())?;
///     }
/// }
/// // East along the middle row, 4 m at a time.
/// let route: Vec<Position> = (0..45).map(|i| Position::new(10.0 + 4.0 * i as f64, 30.0)).collect();
/// let snp = simulate(&table, &Snp, &route, 9)?;
/// let pbnp = simulate(&table, &Pbnp::default(), &route, 9)?;
/// // SNP brings in a column of three cells per crossing and replaces three; PBNP one.
/// assert!(pbnp.totals.cells_requested < snp.totals.cells_requested);
/// assert!(pbnp.totals.swaps < snp.totals.swaps);
/// assert_eq!(pbnp.totals.visual_misses, 0);
/// # Ok::<(), flaneur::Error>(())
/// ```
pub fn simulate<S, A>(
    source: &S,
    rule: &A,
    route: &[Position],
    capacity: usize,
) -> Result<SimReport>
where
    S: PvsSource + ?Sized,
    A: PrefetchArea + ?Sized,
{
    if route.is_empty() {
        return Err(Error::Pvs("the route has no positions".into()));
    }
    let mut client = PvsClient::new(source, rule, capacity)?;
    let mut steps = Vec::with_capacity(route.len());
    let mut t = SimTotals {
        positions: route.len(),
        ..SimTotals::default()
    };
    for (step, &p) in route.iter().enumerate() {
        let o = client
            .step(p)
            .map_err(|e| Error::Pvs(format!("step {step}: {}", strip(&e))))?;
        let (requested, sent, swaps) = o.transaction.as_ref().map_or((0, 0, 0), |x| {
            (x.requested.len(), x.sent.len(), x.evicted.len())
        });
        if o.transaction.is_some() {
            if t.transactions == 0 {
                t.first_transaction_objects = sent;
            }
            t.transactions += 1;
        }
        t.swaps += swaps;
        t.objects_sent += sent;
        t.cells_requested += requested;
        t.visual_misses += o.visual_misses;
        t.cells_entered += usize::from(o.entered);
        t.late_entries += usize::from(o.visual_misses > 0);
        let cache = client.cache();
        t.peak_cached_cells = t.peak_cached_cells.max(cache.len());
        t.peak_held_objects = t.peak_held_objects.max(cache.object_count());
        steps.push(StepRecord {
            step,
            cell: o.cell,
            transaction: o.transaction.is_some(),
            cells_requested: requested,
            objects_sent: sent,
            swaps,
            visual_misses: o.visual_misses,
            cached_cells: cache.len(),
            held_objects: cache.object_count(),
        });
    }
    Ok(SimReport {
        algorithm: rule.name(),
        capacity,
        steps,
        totals: t,
    })
}

/// An error's message without the variant's prefix, to wrap it in another.
fn strip(e: &Error) -> String {
    match e {
        Error::Pvs(m) => m.clone(),
        other => other.to_string(),
    }
}
