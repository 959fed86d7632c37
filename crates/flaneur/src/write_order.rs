//! The order a build writes the objects' meshes and LODs in.
//!
//! Over HTTP every byte run costs a request, and a walk asks for the objects of one
//! cell at a time: those objects should lie together in the file. The input's order
//! rarely does that (citygen numbers its lots row by row across the whole city, so a
//! cell of ten rows is ten runs at least), so by default a build writes objects along a
//! Hilbert curve over the centres of their boxes seen from above (x and z), the curve
//! whose stretches stay most compact among the space-filling curves (Moon, Jagadish,
//! Faloutsos, Saltz 2001). Object ids, the index and every page count stay as they
//! were: only where an object's extents sit in the file changes.

use std::fmt;
use std::str::FromStr;

use crate::error::{Error, Result};

/// Cells of the grid the curve runs over, per side, as a power of two: 2¹⁶ cells over
/// a city 10 km across are 15 cm wide, finer than any two objects' centres.
const CURVE_ORDER: u8 = 16;

/// The order in which a build writes objects.
///
/// ```
/// use flaneur::WriteOrder;
/// assert_eq!(WriteOrder::default(), WriteOrder::Hilbert);
/// assert_eq!("input".parse::<WriteOrder>()?, WriteOrder::Input);
/// assert!("zorder".parse::<WriteOrder>().is_err());
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum WriteOrder {
    /// Along a Hilbert curve over the objects' positions (the default): a cell's objects
    /// lie in a few byte runs.
    #[default]
    Hilbert,
    /// In the order the input gives them (the layout of earlier builds).
    Input,
}

impl WriteOrder {
    /// The name `--order` takes.
    pub fn name(self) -> &'static str {
        match self {
            WriteOrder::Hilbert => "hilbert",
            WriteOrder::Input => "input",
        }
    }
}

impl fmt::Display for WriteOrder {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for WriteOrder {
    type Err = Error;

    fn from_str(s: &str) -> Result<WriteOrder> {
        match s {
            "hilbert" => Ok(WriteOrder::Hilbert),
            "input" => Ok(WriteOrder::Input),
            _ => Err(Error::Invalid(format!(
                "write order '{s}': expected hilbert or input"
            ))),
        }
    }
}

/// The indices of `centres` (x, z) in the order of a Hilbert curve over the square that
/// holds them all; centres in one cell of the curve's grid keep their input order.
pub(crate) fn hilbert_order(centres: &[[f32; 2]]) -> Vec<usize> {
    let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
    for c in centres {
        for k in 0..2 {
            lo[k] = lo[k].min(c[k]);
            hi[k] = hi[k].max(c[k]);
        }
    }
    // One scale for both axes, so that the curve's cells are square on the ground.
    let side = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(f32::MIN_POSITIVE) as f64;
    let last = ((1u32 << CURVE_ORDER) - 1) as f64;
    let cell =
        |v: f32, k: usize| (((v - lo[k]) as f64 / side * last).round() as u32).min(last as u32);
    let mut keyed: Vec<(u64, usize)> = centres
        .iter()
        .enumerate()
        .map(|(i, c)| {
            (
                fast_hilbert::xy2h(cell(c[0], 0), cell(c[1], 1), CURVE_ORDER),
                i,
            )
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_is_visited_cell_by_cell_each_step_to_a_neighbour() {
        // An 8 × 8 grid of centres, row by row: along the curve each next centre is
        // one of the four beside the last one.
        let centres: Vec<[f32; 2]> = (0..64)
            .map(|i| [(i % 8) as f32 * 20.0, (i / 8) as f32 * 20.0])
            .collect();
        let order = hilbert_order(&centres);
        let mut seen = order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..64).collect::<Vec<_>>());
        for w in order.windows(2) {
            let (a, b) = (centres[w[0]], centres[w[1]]);
            let step = (a[0] - b[0]).abs() + (a[1] - b[1]).abs();
            assert_eq!(step, 20.0, "{a:?} to {b:?}");
        }
    }

    #[test]
    fn any_quarter_of_the_city_is_one_run() {
        // The curve fills one quadrant before the next: the 16 centres of any quarter
        // of a 8 × 8 grid are 16 consecutive places in the order.
        let centres: Vec<[f32; 2]> = (0..64).map(|i| [(i % 8) as f32, (i / 8) as f32]).collect();
        let order = hilbert_order(&centres);
        for (qx, qz) in [(0.0, 0.0), (4.0, 0.0), (0.0, 4.0), (4.0, 4.0)] {
            let mut places: Vec<usize> = order
                .iter()
                .enumerate()
                .filter(|(_, &i)| {
                    let c = centres[i];
                    (qx..qx + 4.0).contains(&c[0]) && (qz..qz + 4.0).contains(&c[1])
                })
                .map(|(p, _)| p)
                .collect();
            places.sort_unstable();
            assert_eq!(places.len(), 16);
            assert_eq!(
                places[15] - places[0],
                15,
                "quarter at {qx},{qz}: {places:?}"
            );
        }
    }

    #[test]
    fn degenerate_inputs_keep_their_order() {
        assert!(hilbert_order(&[]).is_empty());
        assert_eq!(hilbert_order(&[[3.0, 3.0]; 4]), [0, 1, 2, 3]);
    }
}
