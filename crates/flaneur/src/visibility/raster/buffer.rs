//! A face's item buffer: each pixel's nearest object and its depth, and over them the
//! coarse depth buffer of hierarchical depth (Greene et al. 1993's z-pyramid cut to one
//! level): for each 4×4 tile, the farthest depth any of its pixels holds, so that a box
//! nearer than nothing it covers can be skipped without touching its triangles.
//!
//! Depth is stored as `w = 1/z` (z the distance along the face's axis): it is affine
//! across a triangle's projection, and the sky is `w = 0`, farther than everything.

use crate::visibility::cube::SKY;

use super::face::Footprint;

/// Pixels along a side of a coarse-depth tile.
pub(super) const TILE: u32 = 4;

/// One face's buffers, cleared for each face drawn.
pub(super) struct ItemBuffer {
    pub n: u32,
    /// `1/z` of each pixel's nearest surface so far, row-major; 0 for sky.
    pub depth: Vec<f32>,
    /// The object of each pixel's nearest surface, or [`SKY`].
    pub ids: Vec<u32>,
    tiles_per_side: u32,
    /// Per tile, the least `w` (the farthest depth) of its pixels, when not `stale`.
    tile_far: Vec<f32>,
    /// Tiles drawn into since their `tile_far` was last taken.
    stale: Vec<bool>,
}

impl ItemBuffer {
    pub fn new(n: u32) -> ItemBuffer {
        let pixels = (n as usize).pow(2);
        let tiles_per_side = n.div_ceil(TILE);
        let tiles = (tiles_per_side as usize).pow(2);
        ItemBuffer {
            n,
            depth: vec![0.0; pixels],
            ids: vec![SKY; pixels],
            tiles_per_side,
            tile_far: vec![0.0; tiles],
            stale: vec![false; tiles],
        }
    }

    /// All sky again.
    pub fn clear(&mut self) {
        self.depth.fill(0.0);
        self.ids.fill(SKY);
        self.tile_far.fill(0.0);
        self.stale.fill(false);
    }

    /// Marks the tiles of row `j` from column `first` to `last` as drawn into.
    #[inline]
    pub fn touch(&mut self, j: u32, first: u32, last: u32) {
        let row = (j / TILE * self.tiles_per_side) as usize;
        self.stale[row + (first / TILE) as usize..=row + (last / TILE) as usize].fill(true);
    }

    /// Marks every tile as drawn into.
    pub fn touch_all(&mut self) {
        self.stale.fill(true);
    }

    /// Whether everything the footprint covers is already nearer than its box's nearest
    /// point: then nothing in the box can show. Ties are not hidden.
    pub fn hides(&mut self, f: &Footprint) -> bool {
        if f.near_w == f32::INFINITY {
            return false;
        }
        for ty in f.rows.0 / TILE..=f.rows.1 / TILE {
            for tx in f.cols.0 / TILE..=f.cols.1 / TILE {
                let t = (ty * self.tiles_per_side + tx) as usize;
                if self.stale[t] {
                    self.tile_far[t] = self.farthest_in(tx, ty);
                    self.stale[t] = false;
                }
                if self.tile_far[t] <= f.near_w {
                    return false;
                }
            }
        }
        true
    }

    /// Whether every pixel of columns `cols` and rows `rows` (inclusive, on the face)
    /// already holds a `w` of at least `w_max`: then a triangle nearer than that nowhere
    /// can take none of them (a pixel takes only a strictly greater `w`). Tiles drawn
    /// into since their farthest depth was taken count as not hidden: refreshing them
    /// for every triangle would cost more than drawing it.
    #[inline]
    pub fn hides_rect(&self, cols: (u32, u32), rows: (u32, u32), w_max: f32) -> bool {
        for ty in rows.0 / TILE..=rows.1 / TILE {
            let row = (ty * self.tiles_per_side) as usize;
            for t in row + (cols.0 / TILE) as usize..=row + (cols.1 / TILE) as usize {
                if self.stale[t] || self.tile_far[t] < w_max {
                    return false;
                }
            }
        }
        true
    }

    fn farthest_in(&self, tx: u32, ty: u32) -> f32 {
        let n = self.n as usize;
        let (x0, y0) = ((tx * TILE) as usize, (ty * TILE) as usize);
        let (x1, y1) = ((x0 + TILE as usize).min(n), (y0 + TILE as usize).min(n));
        (y0..y1)
            .flat_map(|y| &self.depth[y * n + x0..y * n + x1])
            .fold(f32::INFINITY, |m, &w| m.min(w))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_is_hidden_only_behind_every_pixel_it_covers() {
        let mut b = ItemBuffer::new(16);
        let at = |cols, rows, near_w| Footprint {
            cols,
            rows,
            near_w,
            distance2: 0.0,
        };
        let far_box = at((0, 7), (0, 7), 0.1);
        assert!(!b.hides(&far_box), "the sky hides nothing");
        for j in 0..8 {
            for i in 0..8 {
                b.depth[j * 16 + i] = 0.5;
            }
            b.touch(j as u32, 0, 7);
        }
        assert!(b.hides(&far_box));
        assert!(!b.hides(&at((0, 7), (0, 7), 0.5)), "a tie shows");
        assert!(!b.hides(&at((0, 8), (0, 7), 0.1)), "column 8 is sky");
        b.depth[3 * 16 + 3] = 0.05;
        b.touch(3, 3, 3);
        assert!(!b.hides(&far_box), "one farther pixel lets it show");
    }

    #[test]
    fn a_triangle_is_hidden_only_behind_fresh_tiles_at_least_as_near() {
        let mut b = ItemBuffer::new(16);
        b.depth[..16 * TILE as usize].fill(0.5);
        b.touch_all();
        assert!(
            !b.hides_rect((0, 3), (0, 3), 0.1),
            "a stale tile hides nothing"
        );
        assert!(b.hides(&Footprint {
            cols: (0, 15),
            rows: (0, TILE - 1),
            near_w: 0.1,
            distance2: 0.0,
        }));
        assert!(
            b.hides_rect((0, 15), (0, TILE - 1), 0.5),
            "w never above 0.5 takes none"
        );
        assert!(!b.hides_rect((0, 15), (0, TILE - 1), 0.6));
        assert!(!b.hides_rect((0, 15), (0, TILE), 0.1), "row TILE is sky");
    }
}
