//! The history H of CSearch (Shou 2002, §4.2.2, text after Fig. 4.7): the cells
//! already queried along a walk, filtered before each query and bounded in length.
//!
//! Filter rule (as the thesis states it): a history cell may be dropped only when no
//! object box retrieved for it overlaps the new cell. Each cell therefore keeps
//! `covered`, the MBR of the objects attributed to it. When a cell leaves the history
//! (filtered, or evicted because the history is full), its `covered` box is merged
//! into every remaining cell whose box it touches: an object attributed to the cell
//! that leaves and overlapping a remaining cell is then still accounted for, so a
//! later filter cannot drop that remaining cell while the object still matters.
//! With that, filtering never changes a query's result: CSearch against the
//! filtered history equals CSearch against the history before filtering. The length
//! bound does change results (the thesis keeps fewer than 20 cells); it is the price
//! of a bounded history, and the oldest cell goes first.

use std::collections::VecDeque;

use super::node::ObjectEntry;
use crate::geom::Aabb;

/// The default bound on the history length (the thesis kept fewer than twenty).
pub const DEFAULT_HISTORY_LEN: usize = 16;

#[derive(Clone, Copy, Debug, PartialEq)]
struct Cell {
    cell: Aabb,
    covered: Aabb,
}

/// The cells a walk has queried, oldest first.
///
/// ```
/// use flaneur::{geom::Aabb, History};
/// let mut h = History::new(16);
/// let c1: Aabb = "0,0,0,10,10,10".parse().unwrap();
/// h.record(c1, &[]); // nothing was retrieved for c1 ...
/// h.filter(&"50,0,0,60,10,10".parse().unwrap());
/// assert!(h.is_empty()); // ... so it cannot matter to any later cell
/// ```
#[derive(Clone, Debug)]
pub struct History {
    cells: VecDeque<Cell>,
    max_len: usize,
}

impl History {
    /// A history holding at most `max_len` cells (at least 1).
    pub fn new(max_len: usize) -> History {
        History {
            cells: VecDeque::new(),
            max_len: max_len.max(1),
        }
    }

    /// Cells held.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// Whether no cell is held.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// The most cells it holds.
    pub fn max_len(&self) -> usize {
        self.max_len
    }

    /// The cells, oldest first: the `history` argument of CSearch.
    pub fn cells(&self) -> Vec<Aabb> {
        self.cells.iter().map(|c| c.cell).collect()
    }

    /// Forgets every cell.
    pub fn clear(&mut self) {
        self.cells.clear();
    }

    /// Drops the cells that cannot affect a query of `next`; returns how many.
    pub fn filter(&mut self, next: &Aabb) -> usize {
        let mut dropped = 0;
        let mut i = 0;
        while i < self.cells.len() {
            if self.cells[i].covered.overlaps(next) {
                i += 1;
            } else {
                self.remove(i);
                dropped += 1;
            }
        }
        dropped
    }

    /// Appends `cell` with the objects CSearch retrieved for it, evicting the oldest
    /// cell when the history is full.
    pub fn record(&mut self, cell: Aabb, retrieved: &[ObjectEntry]) {
        if self.cells.len() == self.max_len {
            self.remove(0);
        }
        let covered = retrieved
            .iter()
            .fold(Aabb::EMPTY, |b, o| b.union(&o.bounds));
        self.cells.push_back(Cell { cell, covered });
    }

    fn remove(&mut self, i: usize) {
        let Some(gone) = self.cells.remove(i) else {
            return;
        };
        if gone.covered.is_empty() {
            return;
        }
        for c in self.cells.iter_mut() {
            if c.cell.overlaps(&gone.covered) {
                c.covered = c.covered.union(&gone.covered);
            }
        }
    }
}

impl Default for History {
    fn default() -> History {
        History::new(DEFAULT_HISTORY_LEN)
    }
}
