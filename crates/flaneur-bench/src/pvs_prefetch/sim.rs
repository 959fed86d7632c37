//! The simulation of §7.5: one client walks a route position by position, and every
//! position's transaction is counted. Deterministic: the same table, rule, route and
//! latency give the same counts.
//!
//! Latency (ours): a transaction asked at step t is answered at step t + L, after that
//! step's frame, so the frames of steps t + 1 … t + L draw without it and the frame of
//! step t + L + 1 with it; L = 0 is the thesis's walk, every transaction complete
//! before the next position. The viewer waits at the start until the start-up
//! transaction is answered (the thesis's start-up time, L steps), and the walk's visual
//! misses are counted from the first step on.

use std::collections::VecDeque;

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
    /// Objects of the cell's PVS not on hand in the frame drawn here.
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
    /// Objects of the current cell's PVS missing from a frame, summed over the route.
    pub visual_misses: usize,
    /// Steps whose frame missed any object (at L = 0, the late entries).
    pub miss_steps: usize,
    /// Steps the viewer waited at the start for the start-up transaction (L).
    pub start_up_wait: usize,
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
    /// Steps from asking a transaction to its answer.
    pub latency: usize,
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
    simulate_with_latency(source, rule, route, capacity, 0)
}

/// [`simulate`] with every transaction answered `latency` steps after it is asked.
///
/// ```
/// use flaneur::prefetch::pvs::{Cell, Pbnp, Position, Snp, ViewcellGrid};
/// use flaneur_bench::pvs_prefetch::{simulate_with_latency, PvsTable};
/// let grid = ViewcellGrid::new(Position::new(0.0, 0.0), 20.0, 3, 10)?;
/// let mut table = PvsTable::new(grid, 100)?;
/// for row in 0..3 {
///     for col in 0..10u32 {
///         table.insert(Cell::new(row, col), (col as u64 * 5..col as u64 * 5 + 20).collect())?;
///     }
/// }
/// let route: Vec<Position> = (0..45).map(|i| Position::new(10.0 + 4.0 * i as f64, 30.0)).collect();
/// // Answers 3 steps away: PBNP's one-step band is too late, SNP's whole cell is not.
/// let snp = simulate_with_latency(&table, &Snp, &route, 9, 3)?;
/// let pbnp = simulate_with_latency(&table, &Pbnp::default(), &route, 9, 3)?;
/// assert_eq!(snp.totals.visual_misses, 0);
/// assert!(pbnp.totals.visual_misses > 0 && pbnp.totals.miss_steps > 0);
/// assert_eq!(pbnp.totals.start_up_wait, 3);
/// # Ok::<(), flaneur::Error>(())
/// ```
pub fn simulate_with_latency<S, A>(
    source: &S,
    rule: &A,
    route: &[Position],
    capacity: usize,
    latency: usize,
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
        start_up_wait: latency,
        ..SimTotals::default()
    };
    // Transactions awaiting their answer: (the tick it comes at, id), oldest first.
    let mut awaited: VecDeque<(usize, u64)> = VecDeque::new();
    // Tick 0 is the start; the viewer stands there until tick `latency`.
    let ticks = (0..=latency).map(|_| 0).chain(1..route.len());
    for (tick, step) in ticks.enumerate() {
        let p = route[step];
        let o = client
            .look(p)
            .map_err(|e| Error::Pvs(format!("step {step}: {}", strip(&e))))?;
        if let Some(x) = &o.transaction {
            awaited.push_back((tick + latency, x.id));
        }
        while awaited.front().is_some_and(|&(at, _)| at <= tick) {
            let (_, id) = awaited.pop_front().expect("checked");
            client.deliver(id)?;
        }
        let waiting = step == 0 && tick > 0;
        if waiting && o.transaction.is_none() {
            continue;
        }
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
        let misses = if step == 0 { 0 } else { o.visual_misses };
        t.visual_misses += misses;
        t.miss_steps += usize::from(misses > 0);
        t.cells_entered += usize::from(o.entered);
        t.late_entries += usize::from(o.entered && misses > 0);
        let cache = client.cache();
        t.peak_cached_cells = t.peak_cached_cells.max(cache.len());
        t.peak_held_objects = t.peak_held_objects.max(cache.object_count());
        let record = StepRecord {
            step,
            cell: o.cell,
            transaction: o.transaction.is_some(),
            cells_requested: requested,
            objects_sent: sent,
            swaps,
            visual_misses: misses,
            cached_cells: cache.len(),
            held_objects: cache.object_count(),
        };
        // A transaction asked while waiting at the start counts with the start's.
        match steps.last_mut() {
            Some(last) if waiting => merge(last, &record),
            _ => steps.push(record),
        }
    }
    Ok(SimReport {
        algorithm: rule.name(),
        capacity,
        latency,
        steps,
        totals: t,
    })
}

/// Adds `more`'s costs to `into`'s, for two looks from one position.
fn merge(into: &mut StepRecord, more: &StepRecord) {
    into.transaction |= more.transaction;
    into.cells_requested += more.cells_requested;
    into.objects_sent += more.objects_sent;
    into.swaps += more.swaps;
    into.cached_cells = more.cached_cells;
    into.held_objects = more.held_objects;
}

/// An error's message without the variant's prefix, to wrap it in another.
fn strip(e: &Error) -> String {
    match e {
        Error::Pvs(m) => m.clone(),
        other => other.to_string(),
    }
}
