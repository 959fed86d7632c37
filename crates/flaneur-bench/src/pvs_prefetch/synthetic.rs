//! The synthetic city and PVS table of Zheng 2007 §7.5: 900 buildings 100 m square on a
//! 30 × 30 grid, streets 60 m wide between them (and round the edge), cut into 20 m
//! viewcells; each viewcell's PVS about 5 % of the scene, adjacent viewcells sharing
//! about 60 % of their visible objects. The thesis states only those two figures, from
//! Cohen-Or et al. and Nadler et al.; how the table is drawn is ours:
//!
//! - Every building is one object. Its visibility is a scatter of rectangular patches of
//!   cells, its object visible from the street cells its patches cover. A cell's PVS is
//!   the buildings whose patches cover it; cells inside buildings have no viewcell.
//! - Patch sides are ⌊L⌋ or ⌈L⌉ cells, drawn per axis with mean L = 1 / (1 − overlap):
//!   a patch covering a cell covers its neighbour along an axis with probability
//!   (w − 1) / w, which over patches weighted by their width is 1 − 1/L, the overlap.
//!   The share then falls off with distance as real coherence does (about 20 % two
//!   cells apart at the default).
//! - Patches are scattered uniformly over the whole grid (their corners from one side
//!   less than the grid up to its far edge, so that edge cells are covered as often),
//!   as many per building as make the chance that a building covers a cell equal to
//!   the PVS share. Uniform scattering keeps both figures the same in every part of the
//!   city; it does not make near buildings likelier to be seen than far ones, which
//!   none of the prefetcher's counts depends on.
//! - Drawn from a ChaCha8 generator seeded by `seed`: the same settings give the same
//!   table on every machine.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use flaneur::error::{Error, Result};
use flaneur::prefetch::pvs::routes::StreetGrid;
use flaneur::prefetch::pvs::{Cell, ObjectId, Position, PvsSource, ViewcellGrid};

use super::table::PvsTable;

/// The settings of a synthetic city; the defaults are the thesis's.
#[derive(Clone, Debug, PartialEq)]
pub struct SyntheticConfig {
    /// Buildings along each side (900 buildings for 30).
    pub blocks: u32,
    /// Side of a building's square base, metres.
    pub building: f64,
    /// Width of a street, metres.
    pub street: f64,
    /// Side of a viewcell, metres; must divide the building and the street.
    pub cell: f64,
    /// Mean PVS size as a share of the buildings, in (0, 0.5].
    pub pvs_share: f64,
    /// Share of a viewcell's PVS that a side neighbour also sees, in [0, 0.9].
    pub overlap: f64,
    pub seed: u64,
}

impl Default for SyntheticConfig {
    fn default() -> SyntheticConfig {
        SyntheticConfig {
            blocks: 30,
            building: 100.0,
            street: 60.0,
            cell: 20.0,
            pvs_share: 0.05,
            overlap: 0.6,
            seed: 1,
        }
    }
}

/// Grids larger than this many cells are refused (the table is held in memory).
const MAX_GRID_CELLS: u64 = 1 << 22;

/// Tables expected to hold more object ids than this are refused (memory and time).
const MAX_ENTRIES: f64 = 2e7;

/// The city's plan in cells: streets along every row and column band of `street`
/// cells, one every `pitch` cells, the first at 0 and the last on the far edge.
#[derive(Clone, Copy, Debug)]
struct Plan {
    street: u32,
    pitch: u32,
    side: u32,
}

impl Plan {
    fn is_street(&self, cell: Cell) -> bool {
        cell.row % self.pitch < self.street || cell.col % self.pitch < self.street
    }
}

impl SyntheticConfig {
    /// A clear error for settings that make no city.
    pub fn validate(&self) -> Result<()> {
        self.plan().map(|_| ())
    }

    fn plan(&self) -> Result<Plan> {
        let bad = |what: String| Err(Error::Pvs(format!("synthetic city: {what}")));
        if self.blocks == 0 {
            return bad("it needs at least one building along each side".into());
        }
        for (name, v) in [
            ("building side", self.building),
            ("street width", self.street),
            ("viewcell size", self.cell),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(format!("{name} {v} must be a positive number of metres"));
            }
        }
        let cells_in = |m: f64| {
            let n = (m / self.cell).round();
            ((m / self.cell - n).abs() < 1e-9 && (1.0..=1e6).contains(&n)).then_some(n as u32)
        };
        let (Some(building), Some(street)) = (cells_in(self.building), cells_in(self.street))
        else {
            return bad(format!(
                "the viewcell size {} m must divide the building side {} m and the street width {} m",
                self.cell, self.building, self.street
            ));
        };
        let pitch = building + street;
        let side = u64::from(self.blocks) * u64::from(pitch) + u64::from(street);
        if side * side > MAX_GRID_CELLS {
            return bad(format!(
                "a grid of {side} × {side} viewcells is too large (at most {MAX_GRID_CELLS} cells)"
            ));
        }
        if !(self.pvs_share > 0.0 && self.pvs_share <= 0.5) {
            return bad(format!(
                "PVS share {} must be greater than 0 and at most 0.5",
                self.pvs_share
            ));
        }
        if !(0.0..=0.9).contains(&self.overlap) {
            return bad(format!(
                "neighbour overlap {} must be between 0 and 0.9",
                self.overlap
            ));
        }
        let buildings = u64::from(self.blocks) * u64::from(self.blocks);
        let street_cells = side * side - buildings * u64::from(building) * u64::from(building);
        let entries = street_cells as f64 * buildings as f64 * self.pvs_share;
        if entries > MAX_ENTRIES {
            return bad(format!(
                "its PVS table would hold about {entries:.0} object ids (at most {MAX_ENTRIES:.0}); use fewer buildings or a smaller PVS share"
            ));
        }
        Ok(Plan {
            street,
            pitch,
            side: side as u32,
        })
    }
}

/// A generated city: its plan and its PVS table.
///
/// ```
/// use flaneur::prefetch::pvs::PvsSource;
/// use flaneur_bench::pvs_prefetch::{SyntheticCity, SyntheticConfig};
/// let city = SyntheticCity::generate(&SyntheticConfig { blocks: 4, ..Default::default() })?;
/// assert_eq!(city.scene_objects(), 16);
/// let here = city.intersection(1, 2);
/// let cell = city.grid().cell_of(here)?;
/// assert!(city.is_viewcell(cell)?);
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Debug)]
pub struct SyntheticCity {
    config: SyntheticConfig,
    plan: Plan,
    table: PvsTable,
}

impl SyntheticCity {
    /// Draws the city's PVS table (about a tenth of a second at the thesis's size).
    pub fn generate(config: &SyntheticConfig) -> Result<SyntheticCity> {
        let plan = config.plan()?;
        let side = plan.side;
        let grid = ViewcellGrid::new(Position::new(0.0, 0.0), config.cell, side, side)?;
        let objects = u64::from(config.blocks) * u64::from(config.blocks);

        // Street cells only, row-major, each with the buildings that cover it.
        let mut slot = vec![u32::MAX; side as usize * side as usize];
        let mut rows: Vec<Vec<ObjectId>> = Vec::new();
        for r in 0..side {
            for c in 0..side {
                if plan.is_street(Cell::new(r, c)) {
                    slot[(r * side + c) as usize] = rows.len() as u32;
                    rows.push(Vec::new());
                }
            }
        }

        let mean_side = 1.0 / (1.0 - config.overlap);
        let short = mean_side.floor();
        let long_chance = mean_side - short;
        // A building covers a cell with chance 1 − e^(−λ) when its patches cover it λ
        // times on average: λ makes that chance the PVS share.
        let lambda = -(1.0 - config.pvs_share).ln();
        let span = f64::from(side) + mean_side - 1.0;
        let patches = (lambda * span * span / (mean_side * mean_side))
            .round()
            .max(1.0) as u64;
        let mut rng = ChaCha8Rng::seed_from_u64(config.seed);
        let draw_side = |rng: &mut ChaCha8Rng| short as i64 + i64::from(rng.gen_bool(long_chance));
        for object in 0..objects {
            for _ in 0..patches {
                let (h, w) = (draw_side(&mut rng), draw_side(&mut rng));
                let r0 = rng.gen_range(1 - h..i64::from(side));
                let c0 = rng.gen_range(1 - w..i64::from(side));
                for r in r0.max(0)..(r0 + h).min(i64::from(side)) {
                    for c in c0.max(0)..(c0 + w).min(i64::from(side)) {
                        let s = slot[(r * i64::from(side) + c) as usize];
                        if s != u32::MAX {
                            rows[s as usize].push(object);
                        }
                    }
                }
            }
        }

        let mut table = PvsTable::new(grid, objects)?;
        let mut rows = rows.into_iter();
        for r in 0..side {
            for c in 0..side {
                if slot[(r * side + c) as usize] != u32::MAX {
                    let pvs = rows.next().expect("one row per street cell");
                    table.insert(Cell::new(r, c), pvs)?;
                }
            }
        }
        Ok(SyntheticCity {
            config: config.clone(),
            plan,
            table,
        })
    }

    pub fn config(&self) -> &SyntheticConfig {
        &self.config
    }

    pub fn table(&self) -> &PvsTable {
        &self.table
    }

    /// Metres from one street to the next (a building and a street).
    pub fn pitch(&self) -> f64 {
        self.config.building + self.config.street
    }

    /// The city's side, metres (streets round the edge included).
    pub fn side(&self) -> f64 {
        f64::from(self.plan.side) * self.config.cell
    }

    /// Streets along each axis (`blocks` + 1, the edge ones included).
    pub fn streets(&self) -> u32 {
        self.config.blocks + 1
    }

    /// The city's streets as route 2 walks them.
    pub fn street_grid(&self) -> StreetGrid {
        StreetGrid {
            blocks: self.config.blocks,
            pitch: self.pitch(),
            street: self.config.street,
            side: self.side(),
        }
    }

    /// The centre of the crossing of street `i` (counted west to east) and street `j`
    /// (north to south).
    pub fn intersection(&self, i: u32, j: u32) -> Position {
        let half = self.config.street / 2.0;
        Position::new(
            f64::from(i) * self.pitch() + half,
            f64::from(j) * self.pitch() + half,
        )
    }

    /// Whether `p` lies on a walkway: the middle third of a street (with 60 m streets
    /// and 20 m cells, its middle lane), where every neighbour of the viewer's cell is
    /// a viewcell too. The routes keep to them.
    pub fn on_walkway(&self, p: Position) -> bool {
        if !self.is_street(p) {
            return false;
        }
        let street = self.config.street;
        let middle = |t: f64| {
            let t = t.rem_euclid(self.pitch());
            t >= street / 3.0 && t < 2.0 * street / 3.0
        };
        middle(p.x) || middle(p.z)
    }

    /// Whether `p` lies on a street (in a viewcell) of the city.
    pub fn is_street(&self, p: Position) -> bool {
        self.table
            .grid()
            .cell_of(p)
            .is_ok_and(|c| self.plan.is_street(c))
    }
}

impl PvsSource for SyntheticCity {
    fn grid(&self) -> &ViewcellGrid {
        self.table.grid()
    }

    fn scene_objects(&self) -> u64 {
        self.table.scene_objects()
    }

    fn is_viewcell(&self, cell: Cell) -> Result<bool> {
        self.table.is_viewcell(cell)
    }

    fn pvs(&self, cell: Cell) -> Result<Vec<ObjectId>> {
        self.table.pvs(cell)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_table() {
        let cfg = SyntheticConfig {
            blocks: 5,
            ..Default::default()
        };
        let a = SyntheticCity::generate(&cfg).unwrap();
        let b = SyntheticCity::generate(&cfg).unwrap();
        let c = SyntheticCity::generate(&SyntheticConfig { seed: 2, ..cfg }).unwrap();
        let rows = |x: &SyntheticCity| {
            x.table()
                .viewcells()
                .map(|v| x.pvs(v).unwrap())
                .collect::<Vec<_>>()
        };
        assert_eq!(rows(&a), rows(&b));
        assert_ne!(rows(&a), rows(&c));
    }

    #[test]
    fn buildings_have_no_viewcells() {
        let city = SyntheticCity::generate(&SyntheticConfig {
            blocks: 3,
            ..Default::default()
        })
        .unwrap();
        // The middle of the first building, and the first street crossing.
        let inside = Position::new(60.0 + 50.0, 60.0 + 50.0);
        assert!(!city.is_street(inside));
        assert!(!city
            .is_viewcell(city.grid().cell_of(inside).unwrap())
            .unwrap());
        assert!(city.is_street(city.intersection(0, 0)));
        assert!(city.is_street(city.intersection(3, 3)));
        assert!(!city.is_street(Position::new(-1.0, 10.0)));
        // Walkways: the middle lane of a street, along it and across the crossings.
        assert!(city.on_walkway(city.intersection(1, 1)));
        assert!(city.on_walkway(Position::new(160.0 + 30.0, 100.0)));
        assert!(city.on_walkway(Position::new(160.0 + 20.0, 100.0)));
        assert!(!city.on_walkway(Position::new(160.0 + 40.0, 100.0)));
        assert!(!city.on_walkway(Position::new(160.0 + 10.0, 100.0)));
        assert!(!city.on_walkway(inside));
    }

    #[test]
    fn bad_settings_are_named() {
        let err = |f: fn(&mut SyntheticConfig)| {
            let mut c = SyntheticConfig::default();
            f(&mut c);
            SyntheticCity::generate(&c).unwrap_err().to_string()
        };
        assert!(err(|c| c.blocks = 0).contains("at least one building"));
        assert!(err(|c| c.cell = 0.0).contains("viewcell size 0"));
        assert!(err(|c| c.street = f64::NAN).contains("street width"));
        assert!(err(|c| c.cell = 30.0).contains("must divide"));
        assert!(err(|c| c.pvs_share = 0.0).contains("PVS share"));
        assert!(err(|c| c.pvs_share = f64::NAN).contains("PVS share"));
        assert!(err(|c| c.overlap = 0.95).contains("overlap"));
        assert!(err(|c| c.blocks = 10_000).contains("too large"));
        assert!(err(|c| c.blocks = 200).contains("object ids"));
    }
}
