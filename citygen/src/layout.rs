// Where object `id` stands: the street grid. Lots are numbered row-major over the whole
// city (so consecutive ids are neighbours, which keeps spatial indexes and page caches
// honest about locality), grouped into square blocks of `block`×`block` lots with a
// street around every block. Positions are computed in f64 and rounded once, so a lot
// far from the origin is placed as exactly as one near it.

use std::ops::Range;

use crate::config::CityConfig;

/// Metres left free between the footprints of neighbouring lots.
pub(crate) const LOT_GAP: f32 = 2.0;

/// One building lot: the square `center ± half` (in x and z) that its object must stay
/// inside, which way its front faces, and how central it is.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lot {
    /// Centre of the lot on the ground, `[x, z]`.
    pub center: [f32; 2],
    /// Half the side of the square the object may occupy (lot pitch minus the gap).
    pub half: f32,
    /// Whether the front faces +z (towards the street north of the block) rather than −z.
    pub faces_north: bool,
    /// 1 at the centre of the city, falling to 0 at its corners.
    pub centrality: f32,
}

impl Lot {
    /// The lot's size relative to one of the default 20 m pitch: archetypes scale their
    /// bay widths by it, so an object's detail does not depend on the city's spacing.
    pub fn scale(&self) -> f32 {
        self.half / 9.0
    }
}

/// The street grid of one city.
#[derive(Clone, Debug)]
pub(crate) struct Layout {
    lots_per_row: u64,
    rows: u64,
    block: u64,
    spacing: f64,
    street: f64,
    /// World position of the grid's corner (the outer edge of its first street).
    origin: [f64; 2],
    /// The grid's size (x, z) in metres.
    used: [f64; 2],
}

impl Layout {
    /// The grid for a config, or `None` when an explicit extent cannot hold every lot.
    /// The config's other fields must be in range.
    pub(crate) fn new(c: &CityConfig) -> Option<Layout> {
        let block = c.block as u64;
        let pitch = Self::block_pitch(c);
        let (blocks_x, extent) = match c.extent {
            None => {
                let b = Self::blocks_per_side(c);
                (b, c.street_width as f64 + b as f64 * pitch)
            }
            Some(e) => {
                let e = e as f64;
                let b = ((e - c.street_width as f64) / pitch).floor();
                if b < 1.0 {
                    return None;
                }
                (b as u64, e)
            }
        };
        let lots_per_row = blocks_x * block;
        let rows = c.objects.div_ceil(lots_per_row);
        let blocks_z = rows.div_ceil(block);
        let street = c.street_width as f64;
        let used = [
            street + blocks_x as f64 * pitch,
            street + blocks_z as f64 * pitch,
        ];
        if used[1] > extent * (1.0 + 1e-9) {
            return None;
        }
        Some(Layout {
            lots_per_row,
            rows,
            block,
            spacing: c.spacing as f64,
            street,
            origin: [(extent - used[0]) / 2.0, (extent - used[1]) / 2.0],
            used,
        })
    }

    /// The smallest square side that holds every lot of `c`, with its blocks and streets.
    pub(crate) fn derived_extent(c: &CityConfig) -> f64 {
        c.street_width as f64 + Self::blocks_per_side(c) as f64 * Self::block_pitch(c)
    }

    fn block_pitch(c: &CityConfig) -> f64 {
        c.block as f64 * c.spacing as f64 + c.street_width as f64
    }

    fn blocks_per_side(c: &CityConfig) -> u64 {
        let mut side = (c.objects as f64).sqrt() as u64;
        while side * side < c.objects {
            side += 1;
        }
        side.max(1).div_ceil(c.block as u64)
    }

    /// The centre coordinate of lot `i` along one axis.
    fn axis(&self, i: u64, origin: f64) -> f64 {
        let (b, w) = (i / self.block, i % self.block);
        origin
            + self.street
            + b as f64 * (self.block as f64 * self.spacing + self.street)
            + (w as f64 + 0.5) * self.spacing
    }

    /// The lot of object `id`. Ids at or past the object count continue the grid.
    pub(crate) fn lot(&self, id: u64) -> Lot {
        let (row, col) = (id / self.lots_per_row, id % self.lots_per_row);
        let x = self.axis(col, self.origin[0]);
        let z = self.axis(row, self.origin[1]);
        let mid = [
            self.origin[0] + self.used[0] / 2.0,
            self.origin[1] + self.used[1] / 2.0,
        ];
        let reach = (self.used[0].powi(2) + self.used[1].powi(2)).sqrt() / 2.0;
        let d = ((x - mid[0]).powi(2) + (z - mid[1]).powi(2)).sqrt();
        Lot {
            center: [x as f32, z as f32],
            half: (self.spacing as f32 - LOT_GAP) / 2.0,
            faces_north: (row % self.block) * 2 >= self.block && self.block > 1,
            centrality: (1.0 - d / reach.max(1e-9)).clamp(0.0, 1.0) as f32,
        }
    }

    /// The ids whose lot square (the full pitch around its centre) overlaps the x–z
    /// rectangle `[min, max]`, ascending, limited to `0..objects`.
    pub(crate) fn ids_overlapping(
        &self,
        min: [f32; 2],
        max: [f32; 2],
        objects: u64,
    ) -> impl Iterator<Item = u64> + '_ {
        let r = self.spacing / 2.0;
        let cols = self.overlapping(0..self.lots_per_row, self.origin[0], min[0], max[0], r);
        let rows = self.overlapping(0..self.rows, self.origin[1], min[1], max[1], r);
        let lots_per_row = self.lots_per_row;
        rows.into_iter()
            .flat_map(move |row| {
                cols.clone()
                    .into_iter()
                    .map(move |col| row * lots_per_row + col)
            })
            .filter(move |&id| id < objects)
    }

    fn overlapping(&self, range: Range<u64>, origin: f64, lo: f32, hi: f32, r: f64) -> Vec<u64> {
        range
            .filter(|&i| {
                let c = self.axis(i, origin);
                c + r >= lo as f64 && c - r <= hi as f64
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lots_fill_the_square_and_do_not_overlap() {
        for objects in [1, 7, 100, 1000, 12345] {
            let c = CityConfig {
                objects,
                ..Default::default()
            };
            let l = Layout::new(&c).unwrap();
            let e = c.extent();
            let mut prev: Option<Lot> = None;
            for id in 0..objects {
                let lot = l.lot(id);
                for v in lot.center {
                    assert!(
                        v - lot.half >= 0.0 && v + lot.half <= e,
                        "id {id} of {objects}"
                    );
                }
                if let Some(p) = prev {
                    let dx = (lot.center[0] - p.center[0]).abs();
                    let dz = (lot.center[1] - p.center[1]).abs();
                    assert!(dx >= c.spacing - 1e-3 || dz >= c.spacing - 1e-3);
                }
                prev = Some(lot);
            }
        }
    }

    #[test]
    fn an_explicit_extent_spreads_the_grid_inside_it() {
        let c = CityConfig {
            objects: 300,
            extent: Some(1000.0),
            ..Default::default()
        };
        c.validate().unwrap();
        let l = Layout::new(&c).unwrap();
        for id in 0..c.objects {
            let lot = l.lot(id);
            for v in lot.center {
                assert!(v - lot.half >= 0.0 && v + lot.half <= 1000.0);
            }
        }
        // Wider rows than the derived square's.
        assert!(
            l.lots_per_row
                > Layout::new(&CityConfig { extent: None, ..c })
                    .unwrap()
                    .lots_per_row
        );
    }

    #[test]
    fn region_query_finds_the_lots() {
        let c = CityConfig {
            objects: 400,
            ..Default::default()
        };
        let l = Layout::new(&c).unwrap();
        let lot = l.lot(123);
        let ids: Vec<u64> = l
            .ids_overlapping(lot.center, lot.center, c.objects)
            .collect();
        assert_eq!(ids, vec![123]);
        let e = c.extent();
        assert_eq!(l.ids_overlapping([0.0, 0.0], [e, e], 400).count(), 400);
    }
}
