//! LANP, the latency-aware neighbour prefetch (ours, after Zheng 2007 §7.2.2 and the
//! thesis's own closing remark, §7.6, that a prediction from both position and speed
//! would prefetch in time at highly variable speeds).
//!
//! PBNP asks for a neighbour once the viewer stands within a band of the border to it,
//! so its answer has the time the viewer takes to cross the band, about one step. When
//! answers take longer, the viewer is in the cell before its objects are. An answer
//! asked now is first drawn round trip + 1 steps on, and by then the viewer may have
//! gone anywhere within its speed times those steps: a walker turns round, or into a
//! side street, without warning. So LANP asks for PBNP's area and every walkable cell
//! within that reach of the viewer (its nearest point no farther; reached through
//! walkable cells, eight ways, as a step can cut a corner), the nearest first and,
//! between equally near ones, those ahead of its last step first. The round trip (the
//! longest of the recent answers, in steps) and the speed (its longest recent step)
//! are measured by the client (`Observed`), never given; before the viewer has moved
//! its speed is taken to be `start_speed`, what the viewer may set off at.
//!
//! Why a disc and not the path ahead: a path along the last heading (LANP's first
//! form, with turns foreseen where streets open) missed 173 objects at a round trip of
//! 5 steps on the thesis's random route, every one on a reversal or a new heading taken
//! mid-street, which no heading foresees.
//!
//! The reach holds more cells than the thesis's 9-entry cache at round trips beyond
//! about 4 steps of 4 m on 20 m cells: the cache grows to hold the whole area
//! (`grows_cache`), and the peak it reaches is what LANP pays in memory for hiding
//! the latency. With no round trip, at a step no longer than PBNP's band, the disc lies
//! inside PBNP's area and LANP is PBNP.

use super::area::{Area, Observed, PrefetchArea};
use super::grid::{check_border, Cell, Position, ViewcellGrid, NEIGHBOURS};
use super::pbnp::Pbnp;
use crate::error::{Error, Result};

/// The latency-aware neighbour prefetch.
///
/// ```
/// use flaneur::prefetch::pvs::{Cell, Lanp, Observed, Position, PrefetchArea, ViewcellGrid};
/// let grid = ViewcellGrid::new(Position::new(0.0, 0.0), 20.0, 5, 5)?;
/// let lanp = Lanp::new(0.25, 0.0)?;
/// let p = Position::new(50.0, 50.0); // the middle of cell (2, 2)
/// let everywhere = |_: Cell| Ok(true);
/// // No answer yet and standing still: PBNP's area, the cell alone.
/// let still = lanp.area_seen(&grid, p, &Observed::default(), &everywhere)?;
/// assert_eq!(still.cells, [Cell::new(2, 2)]);
/// // Walking east at 4 m a step with answers 2 steps away: 12 m round, so the four
/// // side neighbours (10 m away), east first; the corners are 14.1 m away.
/// let seen = Observed { round_trip: 2, heading: (4.0, 0.0), speed: 4.0 };
/// let ahead = lanp.area_seen(&grid, p, &seen, &everywhere)?;
/// assert_eq!(ahead.cells[..2], [Cell::new(2, 2), Cell::new(2, 3)]);
/// assert_eq!(ahead.cells.len(), 5);
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lanp {
    pbnp: Pbnp,
    start_speed: f64,
}

impl Lanp {
    /// LANP with PBNP's band `border` (a share of the cell's side, in (0, 0.5]) and the
    /// viewer taken to set off at `start_speed` metres a step (0 or more; 0: PBNP's
    /// area until it has moved).
    pub fn new(border: f64, start_speed: f64) -> Result<Lanp> {
        check_border(border)?;
        if !(start_speed.is_finite() && start_speed >= 0.0) {
            return Err(Error::Pvs(format!(
                "LANP's start speed {start_speed} must be a finite number of metres a step, 0 or more"
            )));
        }
        Ok(Lanp {
            pbnp: Pbnp::new(border)?,
            start_speed,
        })
    }

    /// PBNP's band, a share of the cell's side.
    pub fn border(&self) -> f64 {
        self.pbnp.border()
    }

    /// The speed the viewer is taken to set off at, metres a step.
    pub fn start_speed(&self) -> f64 {
        self.start_speed
    }

    /// How far the viewer may be when an answer asked now is first drawn, metres.
    pub fn reach(&self, seen: &Observed) -> f64 {
        let speed = if seen.speed > 0.0 && seen.speed.is_finite() {
            seen.speed
        } else {
            self.start_speed
        };
        speed * (f64::from(seen.round_trip) + 1.0)
    }
}

impl Default for Lanp {
    fn default() -> Lanp {
        Lanp {
            pbnp: Pbnp::default(),
            start_speed: 0.0,
        }
    }
}

impl PrefetchArea for Lanp {
    fn area(&self, grid: &ViewcellGrid, p: Position) -> Result<Area> {
        self.area_seen(grid, p, &Observed::default(), &|_| Ok(true))
    }

    fn area_seen(
        &self,
        grid: &ViewcellGrid,
        p: Position,
        seen: &Observed,
        walkable: &dyn Fn(Cell) -> Result<bool>,
    ) -> Result<Area> {
        let mut area = self.pbnp.area(grid, p)?;
        let reach = self.reach(seen);
        if reach <= 0.0 {
            return Ok(area);
        }
        let size = grid.cell_size();
        let o = grid.origin();
        let gap = |c: Cell| {
            let (x0, z0) = (o.x + f64::from(c.col) * size, o.z + f64::from(c.row) * size);
            let dx = (x0 - p.x).max(p.x - x0 - size).max(0.0);
            let dz = (z0 - p.z).max(p.z - z0 - size).max(0.0);
            dx.hypot(dz)
        };
        // Flooded from the current cell through walkable cells within the reach.
        let mut found: Vec<(f64, Cell)> = vec![(0.0, area.current)];
        let mut next = 0;
        while next < found.len() {
            let c = found[next].1;
            next += 1;
            for (dr, dc) in NEIGHBOURS {
                let Some(n) = grid.offset(c, dr, dc) else {
                    continue;
                };
                if found.iter().any(|&(_, f)| f == n) {
                    continue;
                }
                let d = gap(n);
                if d <= reach && walkable(n)? {
                    found.push((d, n));
                }
            }
        }
        let (hx, hz) = seen.heading;
        let behind = |c: Cell| {
            let q = grid.centre(c);
            -((q.x - p.x) * hx + (q.z - p.z) * hz)
        };
        found.sort_by(|a, b| {
            a.0.total_cmp(&b.0)
                .then(behind(a.1).total_cmp(&behind(b.1)))
                .then(a.1.cmp(&b.1))
        });
        for (_, c) in found {
            if !area.cells.contains(&c) {
                area.cells.push(c);
            }
        }
        Ok(area)
    }

    /// Its area reaches past the neighbours, and the neighbours it does not want may
    /// give up their room to the cells it does.
    fn replaces_neighbours(&self) -> bool {
        true
    }

    /// Its area is what the viewer may reach before an answer asked now arrives: all of
    /// it must be held.
    fn grows_cache(&self) -> bool {
        true
    }

    fn name(&self) -> &'static str {
        "LANP"
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;

    use super::*;
    use crate::prefetch::pvs::DEFAULT_BORDER;

    fn grid() -> ViewcellGrid {
        ViewcellGrid::new(Position::new(0.0, 0.0), 20.0, 9, 9).unwrap()
    }

    fn set(a: &Area) -> BTreeSet<Cell> {
        a.cells.iter().copied().collect()
    }

    /// With nothing measured, or no round trip at a step no wider than the band, LANP
    /// asks for what PBNP asks for, everywhere in a cell.
    #[test]
    fn without_latency_it_is_pbnp() {
        let g = grid();
        let pbnp = Pbnp::new(0.25).unwrap();
        let lanp = Lanp::new(0.25, 4.9).unwrap();
        let quick = Observed {
            round_trip: 0,
            heading: (3.0, -2.0),
            speed: 4.0,
        };
        for i in 0..40 {
            for j in 0..40 {
                let p = Position::new(80.0 + i as f64 * 0.5, 80.0 + j as f64 * 0.5);
                let want = set(&pbnp.area(&g, p).unwrap());
                assert_eq!(set(&Lanp::default().area(&g, p).unwrap()), want, "{p}");
                // Standing still, set off at just under the band's width: still PBNP.
                assert_eq!(set(&lanp.area(&g, p).unwrap()), want, "{p}");
                assert_eq!(
                    set(&lanp.area_seen(&g, p, &quick, &|_| Ok(true)).unwrap()),
                    want,
                    "{p}"
                );
            }
        }
    }

    /// Every walkable cell within the reach, and no other: the reach grows with the
    /// round trip and the speed, in every direction.
    #[test]
    fn reach_grows_with_round_trip_and_speed() {
        let g = grid();
        let lanp = Lanp::new(0.25, 0.0).unwrap();
        let p = Position::new(90.0, 90.0); // the middle of (4, 4)
        let cells = |round_trip, speed| {
            let seen = Observed {
                round_trip,
                heading: (1.0, 0.0),
                speed,
            };
            set(&lanp.area_seen(&g, p, &seen, &|_| Ok(true)).unwrap())
        };
        // The side neighbours lie 10 m off, the corners 14.1 m, the next ring 30 m.
        assert_eq!(cells(1, 4.0).len(), 1);
        assert_eq!(cells(2, 4.0).len(), 5);
        assert_eq!(cells(3, 4.0).len(), 9);
        assert_eq!(cells(1, 8.0).len(), 9);
        assert_eq!(cells(6, 4.0).len(), 9);
        assert_eq!(cells(5, 5.0).len(), 13);
        // The cells are exactly those whose nearest point lies within the reach.
        let seen = Observed {
            round_trip: 9,
            heading: (1.0, 0.0),
            speed: 4.0,
        };
        let got = set(&lanp.area_seen(&g, p, &seen, &|_| Ok(true)).unwrap());
        for r in 0..9 {
            for c in 0..9 {
                let (dr, dc) = ((r as f64 - 4.0).abs(), (c as f64 - 4.0).abs());
                let gap = ((dr * 20.0 - 10.0).max(0.0)).hypot((dc * 20.0 - 10.0).max(0.0));
                assert_eq!(got.contains(&Cell::new(r, c)), gap <= 40.0, "({r}, {c})");
            }
        }
        // Standing still at the start, the start speed sets the reach.
        let off = Lanp::new(0.25, 4.0).unwrap();
        let still = Observed {
            round_trip: 2,
            ..Observed::default()
        };
        assert_eq!(
            off.area_seen(&g, p, &still, &|_| Ok(true))
                .unwrap()
                .cells
                .len(),
            5
        );
    }

    /// Cells behind a building are reached only round it, and the nearest come first,
    /// ahead before behind.
    #[test]
    fn flooded_through_walkable_cells_nearest_first() {
        let g = grid();
        let lanp = Lanp::new(0.25, 0.0).unwrap();
        let p = Position::new(90.0, 90.0);
        let seen = Observed {
            round_trip: 9,
            heading: (4.0, 0.0),
            speed: 4.0,
        };
        // 40 m round, but a street along row 4 only, and a lone walkable cell at
        // (2, 4), 30 m off beyond the buildings of row 3.
        let street = |c: Cell| Ok(c.row == 4 || c == Cell::new(2, 4));
        let a = lanp.area_seen(&g, p, &seen, &street).unwrap();
        assert!(!a.cells.contains(&Cell::new(2, 4)));
        assert!(a.cells.iter().all(|c| c.row == 4));
        // Columns 2 to 6, the nearer first, east before west.
        let row4 = |cols: [u32; 5]| cols.map(|c| Cell::new(4, c));
        assert_eq!(a.cells, row4([4, 5, 3, 6, 2]));
    }

    #[test]
    fn bad_settings_are_errors() {
        assert!(Lanp::new(0.0, 0.0).is_err());
        for s in [-0.1, f64::NAN, f64::INFINITY] {
            let e = Lanp::new(0.25, s).unwrap_err().to_string();
            assert!(e.contains("start speed"), "{e}");
        }
        assert_eq!(Lanp::default().border(), DEFAULT_BORDER);
        assert_eq!(Lanp::new(0.3, 2.0).unwrap().start_speed(), 2.0);
    }
}
