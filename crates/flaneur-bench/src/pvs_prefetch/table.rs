//! The in-memory PVS table: one sorted row per viewcell of a grid, none for the cells
//! without a viewcell. The synthetic city fills one; tests build small ones by hand.

use flaneur::error::{Error, Result};
use flaneur::prefetch::pvs::{Cell, ObjectId, PvsSource, ViewcellGrid};

/// The most cells a [`PvsTable`]'s grid may have (a row slot each, viewcell or not).
pub const MAX_CELLS: u64 = 1 << 24;

/// A [`PvsSource`] held in memory.
///
/// ```
/// use flaneur::prefetch::pvs::{Cell, Position, PvsSource, ViewcellGrid};
/// use flaneur_bench::pvs_prefetch::PvsTable;
/// let grid = ViewcellGrid::new(Position::new(0.0, 0.0), 20.0, 1, 2)?;
/// let mut table = PvsTable::new(grid, 10)?;
/// table.insert(Cell::new(0, 0), vec![4, 1, 2])?;
/// assert_eq!(table.pvs(Cell::new(0, 0))?, [1, 2, 4]);
/// assert!(!table.is_viewcell(Cell::new(0, 1))?); // inside a building, say
/// assert!(table.pvs(Cell::new(0, 1)).is_err());
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct PvsTable {
    grid: ViewcellGrid,
    scene_objects: u64,
    /// Row-major over the grid; `None` where no viewcell lies.
    rows: Vec<Option<Box<[ObjectId]>>>,
}

impl PvsTable {
    /// An empty table over `grid` (no viewcells yet) for a scene of `scene_objects`;
    /// an error for a grid of more than [`MAX_CELLS`] cells.
    pub fn new(grid: ViewcellGrid, scene_objects: u64) -> Result<PvsTable> {
        let cells = u64::from(grid.rows()) * u64::from(grid.cols());
        if cells > MAX_CELLS {
            return Err(Error::Pvs(format!(
                "a PVS table over {} × {} cells is too large to hold in memory (at most {MAX_CELLS} cells)",
                grid.rows(),
                grid.cols()
            )));
        }
        Ok(PvsTable {
            grid,
            scene_objects,
            rows: vec![None; cells as usize],
        })
    }

    /// Makes `cell` a viewcell whose PVS is `objects` (sorted and deduplicated here),
    /// replacing what it had.
    pub fn insert(&mut self, cell: Cell, mut objects: Vec<ObjectId>) -> Result<()> {
        let i = self.index(cell)?;
        objects.sort_unstable();
        objects.dedup();
        if let Some(&last) = objects.last() {
            if last >= self.scene_objects {
                return Err(Error::Pvs(format!(
                    "object {last} in the PVS of cell {cell} is not one of the scene's {} objects",
                    self.scene_objects
                )));
            }
        }
        self.rows[i] = Some(objects.into_boxed_slice());
        Ok(())
    }

    /// The PVS of `cell`, borrowed; `None` where no viewcell lies or outside the grid.
    pub fn get(&self, cell: Cell) -> Option<&[ObjectId]> {
        let i = self.index(cell).ok()?;
        self.rows[i].as_deref()
    }

    /// Every viewcell, row by row.
    pub fn viewcells(&self) -> impl Iterator<Item = Cell> + '_ {
        let cols = self.grid.cols() as usize;
        self.rows.iter().enumerate().filter_map(move |(i, r)| {
            r.as_ref()
                .map(|_| Cell::new((i / cols) as u32, (i % cols) as u32))
        })
    }

    fn index(&self, cell: Cell) -> Result<usize> {
        if !self.grid.contains(cell) {
            return Err(Error::Pvs(format!(
                "cell {cell} lies outside the {} × {} viewcell grid",
                self.grid.rows(),
                self.grid.cols()
            )));
        }
        Ok(cell.row as usize * self.grid.cols() as usize + cell.col as usize)
    }
}

impl PvsSource for PvsTable {
    fn grid(&self) -> &ViewcellGrid {
        &self.grid
    }

    fn scene_objects(&self) -> u64 {
        self.scene_objects
    }

    fn is_viewcell(&self, cell: Cell) -> Result<bool> {
        Ok(self.rows[self.index(cell)?].is_some())
    }

    fn pvs(&self, cell: Cell) -> Result<Vec<ObjectId>> {
        match &self.rows[self.index(cell)?] {
            Some(r) => Ok(r.to_vec()),
            None => Err(Error::Pvs(format!("cell {cell} has no viewcell"))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flaneur::prefetch::pvs::Position;

    #[test]
    fn rows_are_sorted_and_checked() {
        let grid = ViewcellGrid::new(Position::new(0.0, 0.0), 10.0, 2, 3).unwrap();
        let mut t = PvsTable::new(grid, 100).unwrap();
        t.insert(Cell::new(1, 2), vec![9, 3, 9, 0]).unwrap();
        t.insert(Cell::new(0, 1), vec![]).unwrap();
        assert_eq!(t.pvs(Cell::new(1, 2)).unwrap(), [0, 3, 9]);
        assert_eq!(t.get(Cell::new(0, 1)), Some(&[][..]));
        assert_eq!(
            t.viewcells().collect::<Vec<_>>(),
            [Cell::new(0, 1), Cell::new(1, 2)]
        );
        assert!(t
            .insert(Cell::new(0, 0), vec![100])
            .unwrap_err()
            .to_string()
            .contains("object 100"));
        let e = t.is_viewcell(Cell::new(2, 0)).unwrap_err().to_string();
        assert!(e.contains("outside"), "{e}");
        assert!(t
            .pvs(Cell::new(0, 0))
            .unwrap_err()
            .to_string()
            .contains("no viewcell"));
        assert_eq!(t.get(Cell::new(5, 5)), None);
        let huge = ViewcellGrid::new(Position::new(0.0, 0.0), 1.0, 1 << 13, 1 << 13).unwrap();
        let e = PvsTable::new(huge, 1).unwrap_err().to_string();
        assert!(e.contains("too large"), "{e}");
    }
}
