//! The viewcell grid as the prefetcher sees it (Zheng 2007 §7.2): uniform square cells
//! addressed by (row, column), and the nine regions of a cell that PBNP reads a
//! tendency from (Fig. 7.2).
//!
//! Orientation: columns grow along +x (east) and rows along +z (south), so that, as in
//! the thesis's Fig. 7.1, cell (a − 1, b + 1) is the north-east neighbour of (a, b).
//! Positions are on the ground plane, in metres, as f64 so that a long route's
//! positions sit exactly where its steps put them.

use std::fmt;

use crate::error::{Error, Result};

/// A point on the ground plane, metres (x east, z south; the world's y is up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Position {
    /// East, metres.
    pub x: f64,
    /// South, metres.
    pub z: f64,
}

impl Position {
    /// The point (`x`, `z`).
    pub const fn new(x: f64, z: f64) -> Position {
        Position { x, z }
    }

    /// The straight-line distance to `other`, metres.
    pub fn distance(self, other: Position) -> f64 {
        (self.x - other.x).hypot(self.z - other.z)
    }

    fn is_finite(self) -> bool {
        self.x.is_finite() && self.z.is_finite()
    }
}

impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "({}, {})", self.x, self.z)
    }
}

/// A cell of the grid: (row, column), row 0 the northernmost, column 0 the westernmost.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Cell {
    /// The row: 0 is the northernmost.
    pub row: u32,
    /// The column: 0 is the westernmost.
    pub col: u32,
}

impl Cell {
    /// The cell (`row`, `col`).
    pub const fn new(row: u32, col: u32) -> Cell {
        Cell { row, col }
    }

    /// The thesis's replacement test (§7.4): max(Dr, Dc), where Dr and Dc are the
    /// absolute differences of the rows and of the columns. A cell is its own
    /// neighbour's neighbour when this is at most 1.
    pub fn chebyshev(self, other: Cell) -> u32 {
        self.row
            .abs_diff(other.row)
            .max(self.col.abs_diff(other.col))
    }

    /// Whether `other` is this cell or one of its eight neighbours (Dr ≤ 1 and Dc ≤ 1).
    pub fn is_neighbour(self, other: Cell) -> bool {
        self.chebyshev(other) <= 1
    }
}

impl fmt::Display for Cell {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "({}, {})", self.row, self.col)
    }
}

/// The nine regions of a cell (Fig. 7.2(a)): the middle, four sides, four corners.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Region {
    /// The middle.
    M,
    /// The north side.
    N,
    /// The south side.
    S,
    /// The east side.
    E,
    /// The west side.
    W,
    /// The north-west corner.
    NW,
    /// The north-east corner.
    NE,
    /// The south-east corner.
    SE,
    /// The south-west corner.
    SW,
}

impl Region {
    /// The nine regions, the middle first.
    pub const ALL: [Region; 9] = [
        Region::M,
        Region::N,
        Region::S,
        Region::E,
        Region::W,
        Region::NW,
        Region::NE,
        Region::SE,
        Region::SW,
    ];

    /// The direction the region leans towards, as (row, column) steps: N is (−1, 0),
    /// SE is (1, 1), M is (0, 0).
    pub fn direction(self) -> (i32, i32) {
        match self {
            Region::M => (0, 0),
            Region::N => (-1, 0),
            Region::S => (1, 0),
            Region::E => (0, 1),
            Region::W => (0, -1),
            Region::NW => (-1, -1),
            Region::NE => (-1, 1),
            Region::SE => (1, 1),
            Region::SW => (1, -1),
        }
    }

    fn from_direction(dr: i32, dc: i32) -> Region {
        match (dr, dc) {
            (-1, 0) => Region::N,
            (1, 0) => Region::S,
            (0, 1) => Region::E,
            (0, -1) => Region::W,
            (-1, -1) => Region::NW,
            (-1, 1) => Region::NE,
            (1, 1) => Region::SE,
            (1, -1) => Region::SW,
            _ => Region::M,
        }
    }

    /// The region's name as Fig. 7.2 and Table 7.1 write it: "M", "N", … "SW".
    pub fn name(self) -> &'static str {
        match self {
            Region::M => "M",
            Region::N => "N",
            Region::S => "S",
            Region::E => "E",
            Region::W => "W",
            Region::NW => "NW",
            Region::NE => "NE",
            Region::SE => "SE",
            Region::SW => "SW",
        }
    }
}

/// A cell's eight neighbours, as (row, column) offsets: SNP's block and the steps of
/// LANP's flood fill.
pub(crate) const NEIGHBOURS: [(i32, i32); 8] = [
    (-1, -1),
    (-1, 0),
    (-1, 1),
    (0, -1),
    (0, 1),
    (1, -1),
    (1, 0),
    (1, 1),
];

/// The default width of a cell's side and corner regions, as a fraction of the cell's
/// side: a quarter, so the middle region is half the side across (a quarter of the
/// cell's area). On the thesis's 20 m cells that is a 5 m band, more than one 4 m
/// step, so a walker cannot step over a band into the next cell before PBNP has seen
/// it lean that way.
pub const DEFAULT_BORDER: f64 = 0.25;

/// Checks a region border width: a fraction of the cell side in (0, 0.5]. At 0.5 the
/// middle region is empty and every position lies in a corner region.
pub fn check_border(border: f64) -> Result<()> {
    if border.is_finite() && border > 0.0 && border <= 0.5 {
        Ok(())
    } else {
        Err(Error::Pvs(format!(
            "region border {border} must be a fraction of the cell side greater than 0 and at most 0.5"
        )))
    }
}

/// A uniform grid of square viewcells over a rectangle of the ground.
///
/// ```
/// use flaneur::prefetch::pvs::{Cell, Position, Region, ViewcellGrid};
/// // 20 m cells, 10 rows by 12 columns, the north-west corner at the origin.
/// let grid = ViewcellGrid::new(Position::new(0.0, 0.0), 20.0, 10, 12)?;
/// assert_eq!(grid.cell_of(Position::new(45.0, 3.0))?, Cell::new(0, 2));
/// // 2 m from the cell's north edge and 1 m from its east edge, with 5 m bands.
/// assert_eq!(grid.locate(Position::new(59.0, 2.0), 0.25)?, (Cell::new(0, 2), Region::NE));
/// assert!(grid.cell_of(Position::new(-1.0, 3.0)).is_err());
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ViewcellGrid {
    origin: Position,
    cell_size: f64,
    rows: u32,
    cols: u32,
}

impl ViewcellGrid {
    /// A grid of `rows` × `cols` cells of side `cell_size` metres whose north-west
    /// corner is `origin`.
    pub fn new(origin: Position, cell_size: f64, rows: u32, cols: u32) -> Result<ViewcellGrid> {
        if !(cell_size.is_finite() && cell_size > 0.0) {
            return Err(Error::Pvs(format!(
                "viewcell size {cell_size} must be a positive number of metres"
            )));
        }
        if rows == 0 || cols == 0 {
            return Err(Error::Pvs(format!(
                "a viewcell grid needs at least one row and one column, got {rows} × {cols}"
            )));
        }
        let far = Position::new(
            origin.x + cell_size * cols as f64,
            origin.z + cell_size * rows as f64,
        );
        if !origin.is_finite() || !far.is_finite() {
            return Err(Error::Pvs(format!(
                "viewcell grid from {origin} of {rows} × {cols} cells of {cell_size} m is not finite"
            )));
        }
        Ok(ViewcellGrid {
            origin,
            cell_size,
            rows,
            cols,
        })
    }

    /// The grid's north-west corner.
    pub fn origin(&self) -> Position {
        self.origin
    }

    /// The side of a cell, metres.
    pub fn cell_size(&self) -> f64 {
        self.cell_size
    }

    /// Rows of cells.
    pub fn rows(&self) -> u32 {
        self.rows
    }

    /// Columns of cells.
    pub fn cols(&self) -> u32 {
        self.cols
    }

    /// Whether `cell` lies in the grid.
    pub fn contains(&self, cell: Cell) -> bool {
        cell.row < self.rows && cell.col < self.cols
    }

    /// The cell `dr` rows and `dc` columns from `cell`, if it lies in the grid.
    pub fn offset(&self, cell: Cell, dr: i32, dc: i32) -> Option<Cell> {
        let row = u32::try_from(i64::from(cell.row) + i64::from(dr)).ok()?;
        let col = u32::try_from(i64::from(cell.col) + i64::from(dc)).ok()?;
        let c = Cell { row, col };
        self.contains(c).then_some(c)
    }

    /// The centre of `cell`.
    pub fn centre(&self, cell: Cell) -> Position {
        Position::new(
            self.origin.x + (cell.col as f64 + 0.5) * self.cell_size,
            self.origin.z + (cell.row as f64 + 0.5) * self.cell_size,
        )
    }

    /// The cell holding `p`. Cells are half-open: a point on the border between two
    /// cells belongs to the eastern (southern) one.
    pub fn cell_of(&self, p: Position) -> Result<Cell> {
        self.local(p).map(|(cell, _, _)| cell)
    }

    /// The cell holding `p` and the region of it that `p` lies in, the side and corner
    /// regions being bands `border` of the cell's side wide (see [`DEFAULT_BORDER`]).
    pub fn locate(&self, p: Position, border: f64) -> Result<(Cell, Region)> {
        check_border(border)?;
        let (cell, u, v) = self.local(p)?;
        let lean = |t: f64| {
            if t < border {
                -1
            } else if t >= 1.0 - border {
                1
            } else {
                0
            }
        };
        Ok((cell, Region::from_direction(lean(v), lean(u))))
    }

    /// The cell of `p` and where `p` lies in it, as fractions of the side from its
    /// west (u) and north (v) edges, each in [0, 1).
    fn local(&self, p: Position) -> Result<(Cell, f64, f64)> {
        if !p.is_finite() {
            return Err(Error::Pvs(format!("position {p} is not finite")));
        }
        let u = (p.x - self.origin.x) / self.cell_size;
        let v = (p.z - self.origin.z) / self.cell_size;
        if !(u >= 0.0 && v >= 0.0 && u < self.cols as f64 && v < self.rows as f64) {
            return Err(Error::Pvs(format!(
                "position {p} lies outside the viewcell grid (x {} to {}, z {} to {})",
                self.origin.x,
                self.origin.x + self.cell_size * self.cols as f64,
                self.origin.z,
                self.origin.z + self.cell_size * self.rows as f64
            )));
        }
        let (col, row) = (u.floor(), v.floor());
        Ok((
            Cell {
                row: row as u32,
                col: col as u32,
            },
            u - col,
            v - row,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> ViewcellGrid {
        ViewcellGrid::new(Position::new(100.0, -40.0), 20.0, 4, 5).unwrap()
    }

    #[test]
    fn positions_fall_in_their_cells() {
        let g = grid();
        assert_eq!(
            g.cell_of(Position::new(100.0, -40.0)).unwrap(),
            Cell::new(0, 0)
        );
        assert_eq!(
            g.cell_of(Position::new(119.99, -20.01)).unwrap(),
            Cell::new(0, 0)
        );
        assert_eq!(
            g.cell_of(Position::new(120.0, -20.0)).unwrap(),
            Cell::new(1, 1)
        );
        assert_eq!(
            g.cell_of(Position::new(199.9, 39.9)).unwrap(),
            Cell::new(3, 4)
        );
        assert_eq!(g.centre(Cell::new(1, 2)), Position::new(150.0, -10.0));
        assert_eq!(
            g.cell_of(g.centre(Cell::new(3, 4))).unwrap(),
            Cell::new(3, 4)
        );
    }

    #[test]
    fn nine_regions_with_the_given_border() {
        let g = grid();
        let c = g.centre(Cell::new(1, 1));
        let at = |dx: f64, dz: f64, b: f64| g.locate(Position::new(c.x + dx, c.z + dz), b).unwrap();
        // 5 m bands on 20 m cells: the middle is 10 m across.
        assert_eq!(at(0.0, 0.0, 0.25), (Cell::new(1, 1), Region::M));
        assert_eq!(at(4.9, -4.9, 0.25).1, Region::M);
        assert_eq!(at(0.0, -5.0, 0.25).1, Region::M);
        assert_eq!(at(0.0, -5.01, 0.25).1, Region::N);
        assert_eq!(at(0.0, 5.0, 0.25).1, Region::S);
        assert_eq!(at(5.0, 0.0, 0.25).1, Region::E);
        assert_eq!(at(-5.1, 0.0, 0.25).1, Region::W);
        assert_eq!(at(-9.0, -9.0, 0.25).1, Region::NW);
        assert_eq!(at(9.0, -9.0, 0.25).1, Region::NE);
        assert_eq!(at(9.0, 9.0, 0.25).1, Region::SE);
        assert_eq!(at(-9.0, 9.0, 0.25).1, Region::SW);
        // A narrower band makes the same point a middle one.
        assert_eq!(at(6.0, 0.0, 0.1).1, Region::M);
        // At 0.5 there is no middle: every point leans to a corner.
        assert_eq!(at(0.0, 0.0, 0.5).1, Region::SE);
        assert_eq!(at(-0.1, -0.1, 0.5).1, Region::NW);
        for r in Region::ALL {
            let (dr, dc) = r.direction();
            assert_eq!(Region::from_direction(dr, dc), r);
        }
    }

    #[test]
    fn neighbours_and_offsets() {
        let g = grid();
        let c = Cell::new(0, 0);
        assert_eq!(g.offset(c, -1, 0), None);
        assert_eq!(g.offset(c, 1, 1), Some(Cell::new(1, 1)));
        assert_eq!(g.offset(Cell::new(3, 4), 0, 1), None);
        assert!(c.is_neighbour(Cell::new(1, 1)) && c.is_neighbour(c));
        assert!(!c.is_neighbour(Cell::new(0, 2)));
        assert_eq!(Cell::new(5, 1).chebyshev(Cell::new(2, 3)), 3);
    }

    #[test]
    fn bad_settings_and_positions_are_errors() {
        let o = Position::new(0.0, 0.0);
        for size in [0.0, -20.0, f64::NAN, f64::INFINITY] {
            let e = ViewcellGrid::new(o, size, 3, 3).unwrap_err().to_string();
            assert!(e.contains("viewcell size"), "{e}");
        }
        assert!(ViewcellGrid::new(o, 20.0, 0, 3)
            .unwrap_err()
            .to_string()
            .contains("at least one row"));
        assert!(ViewcellGrid::new(Position::new(f64::NAN, 0.0), 20.0, 3, 3).is_err());
        assert!(ViewcellGrid::new(o, 1e308, 3, 3).is_err());
        let g = grid();
        for p in [
            Position::new(f64::NAN, 0.0),
            Position::new(110.0, f64::INFINITY),
        ] {
            let e = g.cell_of(p).unwrap_err().to_string();
            assert!(e.contains("not finite"), "{e}");
        }
        for p in [
            Position::new(99.9, 0.0),
            Position::new(200.0, 0.0),
            Position::new(150.0, 40.0),
            Position::new(150.0, -40.1),
        ] {
            let e = g.cell_of(p).unwrap_err().to_string();
            assert!(e.contains("outside the viewcell grid"), "{e}");
        }
        let inside = g.centre(Cell::new(0, 0));
        for b in [0.0, -0.1, 0.51, 1.0, f64::NAN] {
            let e = g.locate(inside, b).unwrap_err().to_string();
            assert!(e.contains("region border"), "{e}");
        }
    }
}
