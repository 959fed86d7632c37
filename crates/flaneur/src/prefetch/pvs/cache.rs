//! The client-side cache (Zheng 2007 §7.4, Fig. 7.5): the local PVS table of at most
//! nine viewcell entries and the local graphical database of the objects they see,
//! kept consistent: an object stays exactly as long as some cached cell sees it.
//!
//! Replacement: entries are replaced only when the table is full, and only entries of
//! cells that are not the current cell's neighbours (Dr > 1 or Dc > 1) may go. The
//! thesis does not say which of several such entries goes first: here the farthest
//! from the current cell (by max(Dr, Dc)), then the one least recently needed by a
//! prefetching area, then the lowest (row, column), so that runs are reproducible.
//! Only as many go as the new entries need (Fig. 7.5 replaces one entry for one new
//! cell). An evicted entry's objects are dropped unless a kept or new entry sees them
//! (ΔS_d = S_d − (S_d ∩ S_c)).

use std::cmp::Reverse;
use std::collections::HashMap;

use super::grid::Cell;
use super::source::ObjectId;
use crate::error::{Error, Result};

/// The thesis's cache: 9 entries, the least that holds SNP's 3 × 3 block.
pub const THESIS_CAPACITY: usize = 9;

#[derive(Clone, Debug)]
struct Entry {
    cell: Cell,
    pvs: Vec<ObjectId>,
    /// The tick at which a prefetching area last needed this cell.
    used: u64,
}

/// What an update of the cache did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Admitted {
    /// The entries replaced, in the order they went: one cache swap each.
    pub evicted: Vec<Cell>,
    /// Objects deleted from the local graphical database with them.
    pub dropped: usize,
}

/// The client's local PVS table and graphical database.
///
/// ```
/// use flaneur::prefetch::pvs::{Cell, ClientCache};
/// let mut cache = ClientCache::new(9)?;
/// let here = Cell::new(5, 5);
/// cache.admit(here, vec![(here, vec![1, 2]), (Cell::new(5, 6), vec![2, 3])])?;
/// assert!(cache.holds(3) && cache.contains(Cell::new(5, 6)));
/// assert_eq!(cache.object_count(), 3);
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct ClientCache {
    capacity: usize,
    entries: Vec<Entry>,
    /// Each held object and how many cached entries see it.
    objects: HashMap<ObjectId, u32>,
    clock: u64,
}

impl ClientCache {
    /// An empty cache of `capacity` entries: at least [`THESIS_CAPACITY`], or the
    /// neighbours that must stay could leave no room for a new one.
    pub fn new(capacity: usize) -> Result<ClientCache> {
        if capacity < THESIS_CAPACITY {
            return Err(Error::Pvs(format!(
                "a client cache of {capacity} entries is too small: it must hold the current cell and its 8 neighbours ({THESIS_CAPACITY})"
            )));
        }
        Ok(ClientCache {
            capacity,
            entries: Vec::new(),
            objects: HashMap::new(),
            clock: 0,
        })
    }

    /// The most entries (viewcells) the cache holds.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Raises the capacity to `entries`, if it is below: a rule whose whole area must
    /// be held (`PrefetchArea::grows_cache`). The capacity never falls.
    pub fn grow_to(&mut self, entries: usize) {
        self.capacity = self.capacity.max(entries);
    }

    /// Cached entries (viewcells).
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether no entry is cached.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Whether `cell`'s entry (its PVS row) is cached.
    pub fn contains(&self, cell: Cell) -> bool {
        self.entries.iter().any(|e| e.cell == cell)
    }

    /// The cached cells, in no particular order.
    pub fn cells(&self) -> impl Iterator<Item = Cell> + '_ {
        self.entries.iter().map(|e| e.cell)
    }

    /// The cached PVS of `cell`.
    pub fn pvs(&self, cell: Cell) -> Option<&[ObjectId]> {
        self.entries
            .iter()
            .find(|e| e.cell == cell)
            .map(|e| &e.pvs[..])
    }

    /// Whether the local graphical database holds `id`.
    pub fn holds(&self, id: ObjectId) -> bool {
        self.objects.contains_key(&id)
    }

    /// The objects in the local graphical database, in no particular order.
    pub fn objects(&self) -> impl Iterator<Item = ObjectId> + '_ {
        self.objects.keys().copied()
    }

    /// Objects in the local graphical database.
    pub fn object_count(&self) -> usize {
        self.objects.len()
    }

    /// Notes that a prefetching area needs `cells` now (for the replacement order).
    pub fn touch(&mut self, cells: &[Cell]) {
        self.clock += 1;
        for e in &mut self.entries {
            if cells.contains(&e.cell) {
                e.used = self.clock;
            }
        }
    }

    /// Adds the `new` entries (cell and its sorted PVS) with the viewer in `current`,
    /// replacing non-neighbours of `current` if the table would overflow. An error,
    /// and no change, when a new cell is cached already or there are not enough
    /// non-neighbours to replace.
    pub fn admit(&mut self, current: Cell, new: Vec<(Cell, Vec<ObjectId>)>) -> Result<Admitted> {
        self.admit_keeping(current, new, &[], false)
    }

    /// New entries the cache can take with the viewer in `current` without replacing
    /// a cell of `keep` or, unless `neighbours_go`, a neighbour of `current`.
    pub fn room(&self, current: Cell, keep: &[Cell], neighbours_go: bool) -> usize {
        let staying = self
            .entries
            .iter()
            .filter(|e| keep.contains(&e.cell) || (!neighbours_go && current.is_neighbour(e.cell)))
            .count();
        self.capacity.saturating_sub(staying)
    }

    /// [`admit`](Self::admit), never replacing a cell of `keep` either, and when
    /// `neighbours_go`, replacing neighbours of `current` once no other cell is left
    /// to replace. A rule that looks further than the neighbours (`Lanp`) keeps the far
    /// cells it has just asked for and may need the room its unwanted neighbours take;
    /// SNP and PBNP ask only for neighbours, which stay anyway, and never run short.
    pub fn admit_keeping(
        &mut self,
        current: Cell,
        new: Vec<(Cell, Vec<ObjectId>)>,
        keep: &[Cell],
        neighbours_go: bool,
    ) -> Result<Admitted> {
        for (i, (cell, _)) in new.iter().enumerate() {
            if self.contains(*cell) || new[..i].iter().any(|(c, _)| c == cell) {
                return Err(Error::Pvs(format!(
                    "cell {cell} is admitted to the client cache twice"
                )));
            }
        }
        let need = (self.entries.len() + new.len()).saturating_sub(self.capacity);
        let mut victims: Vec<&Entry> = self
            .entries
            .iter()
            .filter(|e| !keep.contains(&e.cell) && (neighbours_go || !current.is_neighbour(e.cell)))
            .collect();
        if victims.len() < need {
            return Err(Error::Pvs(format!(
                "a client cache of {} entries has no room for {} new cells around {current}: only {} cached cells are not its neighbours",
                self.capacity,
                new.len(),
                victims.len()
            )));
        }
        // Farthest first puts the neighbours, if they may go, after every other cell.
        victims.sort_by_key(|e| (Reverse(current.chebyshev(e.cell)), e.used, e.cell));
        let evicted: Vec<Cell> = victims[..need].iter().map(|e| e.cell).collect();

        // New entries first, so that an object both an evicted and a new cell see stays.
        for (cell, pvs) in new {
            for &id in &pvs {
                *self.objects.entry(id).or_insert(0) += 1;
            }
            self.entries.push(Entry {
                cell,
                pvs,
                used: self.clock,
            });
        }
        let mut dropped = 0;
        for cell in &evicted {
            let i = self
                .entries
                .iter()
                .position(|e| e.cell == *cell)
                .expect("a victim is cached");
            for id in self.entries.swap_remove(i).pvs {
                let n = self
                    .objects
                    .get_mut(&id)
                    .expect("a cached entry's object is held");
                *n -= 1;
                if *n == 0 {
                    self.objects.remove(&id);
                    dropped += 1;
                }
            }
        }
        Ok(Admitted { evicted, dropped })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(row: u32, col: u32) -> Cell {
        Cell::new(row, col)
    }

    /// Every held object is seen by some entry, and every entry's objects are held.
    fn consistent(cache: &ClientCache) -> bool {
        let mut seen: HashMap<ObjectId, u32> = HashMap::new();
        for e in &cache.entries {
            for &id in &e.pvs {
                *seen.entry(id).or_insert(0) += 1;
            }
        }
        seen == cache.objects
    }

    /// Fig. 7.5: full with (a, b) and its eight neighbours; the viewer moves to
    /// (a − 1, b), (a − 2, b) comes in, and one entry of row a + 1 goes.
    #[test]
    fn figure_7_5_replaces_one_far_entry() {
        let (a, b) = (10, 10);
        let mut cache = ClientCache::new(9).unwrap();
        let block: Vec<(Cell, Vec<ObjectId>)> = (a - 1..=a + 1)
            .flat_map(|r| (b - 1..=b + 1).map(move |cl| (c(r, cl), vec![(r * 100 + cl) as u64])))
            .collect();
        cache.admit(c(a, b), block).unwrap();
        assert_eq!(cache.len(), 9);
        let got = cache
            .admit(c(a - 1, b), vec![(c(a - 2, b), vec![7])])
            .unwrap();
        assert_eq!(got.evicted.len(), 1);
        assert_eq!(got.evicted[0].row, a + 1);
        assert_eq!(got.dropped, 1);
        assert_eq!(cache.len(), 9);
        assert!(consistent(&cache));
    }

    #[test]
    fn objects_another_entry_sees_stay() {
        let mut cache = ClientCache::new(9).unwrap();
        // Nine cells in a row, all seeing object 1; cell k also sees 100 + k.
        for k in 0..9 {
            cache
                .admit(c(0, k), vec![(c(0, k), vec![1, 100 + k as u64])])
                .unwrap();
        }
        // At (0, 9) the new cell also sees 100 (cell 0's): it must stay held.
        let got = cache
            .admit(c(0, 9), vec![(c(0, 10), vec![1, 100, 200])])
            .unwrap();
        // Farthest first: column 0 is 9 away from the current column 9.
        assert_eq!(got.evicted, [c(0, 0)]);
        assert_eq!(got.dropped, 0);
        assert!(cache.holds(1) && cache.holds(100) && cache.holds(200));
        assert!(consistent(&cache));
    }

    #[test]
    fn never_over_capacity_and_neighbours_stay() {
        let mut cache = ClientCache::new(9).unwrap();
        // March east along a row, admitting the column ahead each time (SNP's pattern).
        for col in 1..40u32 {
            let here = c(5, col);
            let new: Vec<_> = (4..=6)
                .flat_map(|r| [col - 1, col, col + 1].map(|cl| c(r, cl)))
                .filter(|&x| !cache.contains(x))
                .map(|x| (x, vec![x.row as u64 * 1000 + x.col as u64, 7]))
                .collect();
            let got = cache.admit(here, new).unwrap();
            assert!(cache.len() <= 9);
            assert!(got.evicted.iter().all(|e| !here.is_neighbour(*e)));
            assert!(cache.cells().all(|x| here.is_neighbour(x)), "col {col}");
            assert!(consistent(&cache));
        }
    }

    #[test]
    fn refusals_change_nothing() {
        assert!(ClientCache::new(8)
            .unwrap_err()
            .to_string()
            .contains("too small"));
        assert!(ClientCache::new(usize::MAX).is_ok());
        let mut cache = ClientCache::new(9).unwrap();
        let here = c(5, 5);
        let block: Vec<_> = (4..=6)
            .flat_map(|r| (4..=6).map(move |cl| (c(r, cl), vec![1])))
            .collect();
        cache.admit(here, block).unwrap();
        // A tenth cell with all nine neighbours cached: nothing may go.
        let e = cache
            .admit(here, vec![(c(5, 8), vec![2])])
            .unwrap_err()
            .to_string();
        assert!(e.contains("no room"), "{e}");
        let e = cache
            .admit(c(5, 6), vec![(c(5, 5), vec![])])
            .unwrap_err()
            .to_string();
        assert!(e.contains("twice"), "{e}");
        assert_eq!(cache.len(), 9);
        assert!(!cache.holds(2));
        assert!(consistent(&cache));
    }
}
