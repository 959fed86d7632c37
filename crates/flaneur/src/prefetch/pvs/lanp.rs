//! LANP, the latency-aware neighbour prefetch (ours, after Zheng 2007 §7.2.2 and the
//! thesis's own closing remark, §7.6, that a prediction from both position and speed
//! would prefetch in time at highly variable speeds).
//!
//! PBNP asks for a neighbour once the viewer stands within a band of the border to it,
//! so its answer has the time the viewer takes to cross the band, about one step. When
//! answers take longer, the viewer is in the cell before its objects are. LANP asks for
//! every cell within PBNP's band of the path the viewer will walk while an answer is on
//! its way: from its position along its last step's heading, as far as it goes in the
//! measured round trip (the longest of the recent answers, in steps) at its measured
//! speed (its longest recent step), less the band, which already covers one step.
//! Neither is given to it: the client measures both (`Observed`). Before any answer,
//! or standing still, the path is empty and LANP is PBNP.
//!
//! Turns: the viewer may leave the path sideways. A turn into the next street is
//! foreseen by widening the path sideways by `turn` times what is left of the reach at
//! each point (a viewer that turns there has that much of the round trip left to walk
//! sideways); 0 foresees none, 1 every turn at the measured speed.

use super::area::{Area, Observed, PrefetchArea};
use super::grid::{check_border, Cell, Position, ViewcellGrid, DEFAULT_BORDER};
use crate::error::{Error, Result};

/// The spacing of the points the path is sampled at, as a share of the band: fine
/// enough that the band around the samples covers the band around the path.
const SAMPLES_PER_BAND: f64 = 4.0;

/// The latency-aware neighbour prefetch.
///
/// ```
/// use flaneur::prefetch::pvs::{Cell, Lanp, Observed, Position, PrefetchArea, ViewcellGrid};
/// let grid = ViewcellGrid::new(Position::new(0.0, 0.0), 20.0, 5, 5)?;
/// let lanp = Lanp::new(0.25, 0.0)?;
/// let p = Position::new(50.0, 50.0); // the middle of cell (2, 2)
/// let everywhere = |_: Cell| Ok(true);
/// // No answer yet: PBNP's area, the cell alone.
/// let still = lanp.area_seen(&grid, p, &Observed::default(), &everywhere)?;
/// assert_eq!(still.cells, [Cell::new(2, 2)]);
/// // Walking east at 4 m a step with answers 8 steps away: 36 m on, two cells east.
/// let seen = Observed { round_trip: 8, heading: (4.0, 0.0), speed: 4.0 };
/// let ahead = lanp.area_seen(&grid, p, &seen, &everywhere)?;
/// assert_eq!(ahead.cells, [Cell::new(2, 2), Cell::new(2, 3), Cell::new(2, 4)]);
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lanp {
    border: f64,
    turn: f64,
}

impl Lanp {
    /// LANP with PBNP's band `border` (a share of the cell's side, in (0, 0.5]) and
    /// turns foreseen `turn` (in [0, 1]) of the way.
    pub fn new(border: f64, turn: f64) -> Result<Lanp> {
        check_border(border)?;
        if !(0.0..=1.0).contains(&turn) {
            return Err(Error::Pvs(format!(
                "LANP's turn {turn} must lie between 0 (no turn foreseen) and 1"
            )));
        }
        Ok(Lanp { border, turn })
    }

    /// PBNP's band, a share of the cell's side.
    pub fn border(&self) -> f64 {
        self.border
    }

    /// How far sideways turns are foreseen, a share of the reach left.
    pub fn turn(&self) -> f64 {
        self.turn
    }
}

impl Default for Lanp {
    fn default() -> Lanp {
        Lanp {
            border: DEFAULT_BORDER,
            turn: DEFAULT_TURN,
        }
    }
}

/// Turns foreseen by default: all of the reach, so a viewer turning at the measured
/// speed into a street that opens beside the path finds its cells asked for in time.
pub const DEFAULT_TURN: f64 = 1.0;

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
        let current = grid.cell_of(p)?;
        let size = grid.cell_size();
        let o = grid.origin();
        let (u, v) = ((p.x - o.x) / size, (p.z - o.z) / size);
        let (hx, hz) = seen.heading;
        let len = hx.hypot(hz);
        // An answer asked now is first drawn round trip + 1 steps on; the band covers
        // the last of them.
        let ahead = if len > 0.0 && seen.speed.is_finite() {
            (seen.speed * (f64::from(seen.round_trip) + 1.0) / size - self.border).max(0.0)
        } else {
            0.0
        };
        let (du, dv) = if len > 0.0 {
            (hx / len, hz / len)
        } else {
            (0.0, 0.0)
        };
        let cell_at = |qu: f64, qv: f64| -> Option<Cell> {
            let (r, c) = (qv.floor(), qu.floor());
            if r < 0.0 || c < 0.0 || r >= f64::from(grid.rows()) || c >= f64::from(grid.cols()) {
                return None;
            }
            Some(Cell::new(r as u32, c as u32))
        };
        // A street opens sideways at a point where the cells one and two out are
        // walkable, and two out the cells a cell back and on along the path too: the
        // middle of a street to turn into, not the edge of the one walked along nor
        // the first or last cell of the one crossed.
        let opens = |qu: f64, qv: f64, su: f64, sv: f64| -> Result<bool> {
            let out = [(1.0, 0.0), (2.0, 0.0), (2.0, -1.0), (2.0, 1.0)];
            for (k, t) in out {
                match cell_at(qu + su * k + du * t, qv + sv * k + dv * t) {
                    Some(c) if walkable(c)? => {}
                    _ => return Ok(false),
                }
            }
            Ok(true)
        };
        let delta = self.border / SAMPLES_PER_BAND;
        let b = self.border;
        let mut cells = vec![current];
        let mut push = |cell: Cell| {
            if !cells.contains(&cell) {
                cells.push(cell);
            }
        };
        let n = (ahead / delta).ceil() as usize;
        let along = |i: usize| ahead.min(i as f64 * delta);
        // The path straight ahead first, the turns after: when the cache cannot take
        // both, going on is likelier than turning.
        for i in 0..=n {
            let (qu, qv) = (u + du * along(i), v + dv * along(i));
            for r in (qv - b).floor() as i64..=(qv + b).floor() as i64 {
                for c in (qu - b).floor() as i64..=(qu + b).floor() as i64 {
                    if let (Ok(row), Ok(col)) = (u32::try_from(r), u32::try_from(c)) {
                        if grid.contains(Cell::new(row, col)) {
                            push(Cell::new(row, col));
                        }
                    }
                }
            }
        }
        // A turn is walked from the path's own cells, so it is widened by the band
        // sideways only: along the path the band would take in the next street's
        // cells too, which a viewer turning in the middle of a street never enters.
        for i in 0..=n {
            let s = along(i);
            let (qu, qv) = (u + du * s, v + dv * s);
            let side = self.turn * (ahead - s);
            if side <= 0.0 {
                continue;
            }
            for (su, sv) in [(-dv, du), (dv, -du)] {
                if !opens(qu, qv, su, sv)? {
                    continue;
                }
                let m = ((side + b) / delta).ceil() as usize;
                for j in 1..=m {
                    let w = (side + b).min(j as f64 * delta);
                    if let Some(cell) = cell_at(qu + su * w, qv + sv * w) {
                        push(cell);
                    }
                }
            }
        }
        Ok(Area { current, cells })
    }

    /// Its area reaches past the neighbours, and the cache of 9 cannot hold that
    /// reach and every neighbour at once.
    fn replaces_neighbours(&self) -> bool {
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
    use crate::prefetch::pvs::Pbnp;

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
        let lanp = Lanp::new(0.25, 1.0).unwrap();
        let quick = Observed {
            round_trip: 0,
            heading: (3.0, -2.0),
            speed: 4.0,
        };
        for i in 0..40 {
            for j in 0..40 {
                let p = Position::new(80.0 + i as f64 * 0.5, 80.0 + j as f64 * 0.5);
                let want = set(&pbnp.area(&g, p).unwrap());
                assert_eq!(set(&lanp.area(&g, p).unwrap()), want, "{p}");
                assert_eq!(
                    set(&lanp.area_seen(&g, p, &quick, &|_| Ok(true)).unwrap()),
                    want,
                    "{p}"
                );
            }
        }
    }

    /// The reach grows with the round trip and with the speed.
    #[test]
    fn reach_grows_with_round_trip_and_speed() {
        let g = grid();
        let lanp = Lanp::new(0.25, 0.0).unwrap();
        let p = g.centre(Cell::new(4, 1));
        let east = |round_trip, speed| {
            let seen = Observed {
                round_trip,
                heading: (1.0, 0.0),
                speed,
            };
            let a = lanp.area_seen(&g, p, &seen, &|_| Ok(true)).unwrap();
            a.cells.iter().map(|c| c.col).max().unwrap() - 1
        };
        // From the middle of a cell, (round trip + 1) × speed ahead: 0.2 cells (the band
        // reaches further), 0.6, 1.2, 2.4, 1.8 and 2.6.
        assert_eq!(east(0, 4.0), 0);
        assert_eq!(east(2, 4.0), 1);
        assert_eq!(east(5, 4.0), 1);
        assert_eq!(east(5, 8.0), 2);
        assert_eq!(east(8, 4.0), 2);
        assert_eq!(east(12, 4.0), 3);
        // Every cell wanted lies in the row walked along: no turn foreseen.
        let seen = Observed {
            round_trip: 8,
            heading: (1.0, 0.0),
            speed: 4.0,
        };
        assert!(lanp
            .area_seen(&g, p, &seen, &|_| Ok(true))
            .unwrap()
            .cells
            .iter()
            .all(|c| c.row == 4));
        // Foreseeing turns asks for the side cells within the reach where a street
        // opens: here rows 2 to 6 of column 2 are a street across, the rest of rows
        // 2, 6 and beyond buildings.
        let turning = Lanp::new(0.25, 1.0).unwrap();
        let street = |c: Cell| Ok((3..=5).contains(&c.row) || (1..=3).contains(&c.col));
        let a = turning.area_seen(&g, p, &seen, &street).unwrap();
        assert!(a.cells.contains(&Cell::new(3, 2)) && a.cells.contains(&Cell::new(5, 2)));
        // Along the street walked, its edge cells are no turn.
        assert!(!a.cells.contains(&Cell::new(3, 1)) && !a.cells.contains(&Cell::new(5, 3)));
        // The path straight ahead comes first.
        assert_eq!(
            a.cells[..3],
            [Cell::new(4, 1), Cell::new(4, 2), Cell::new(4, 3)]
        );
    }

    #[test]
    fn bad_settings_are_errors() {
        assert!(Lanp::new(0.0, 0.0).is_err());
        for t in [-0.1, 1.1, f64::NAN] {
            let e = Lanp::new(0.25, t).unwrap_err().to_string();
            assert!(e.contains("turn"), "{e}");
        }
        assert_eq!(Lanp::default().border(), DEFAULT_BORDER);
    }
}
