//! A viewpoint's DoVs as its pixels are summed: [`DovSums`], which every pixel's weight is
//! credited to by the object it shows, and what they come to, [`PointDov`]. The ray-cast
//! (`dov`) and the rasteriser (`raster`) both sum into them, and `dov` builds on the
//! rasteriser as one of its sources, so they lie below both.

use super::cube::SKY;

/// What one viewpoint sees.
#[derive(Clone, Debug, PartialEq)]
pub struct PointDov {
    /// `(object index, DoV)` for every object that at least one pixel shows, by index.
    /// The DoVs and [`sky`](Self::sky) sum to 1, to float rounding.
    pub objects: Vec<(u32, f32)>,
    /// The share of directions that meet nothing.
    pub sky: f32,
}

/// Pixels' weights summed by the object they show, as a viewpoint's pixels are credited:
/// in f64, because at N = 256 a DoV adds up to 393,216 terms near 10⁻⁶. What the ray-cast
/// and the rasteriser both sum their pixels into.
pub(super) struct DovSums {
    sums: Vec<f64>,
    seen: Vec<u32>,
    sky: f64,
}

impl DovSums {
    /// Sums for `objects` objects, all zero.
    pub(super) fn new(objects: usize) -> DovSums {
        DovSums {
            sums: vec![0.0; objects],
            seen: Vec::new(),
            sky: 0.0,
        }
    }

    /// Credits weight `w` to object `id`, or to the sky for [`SKY`].
    pub(super) fn credit(&mut self, id: u32, w: f64) {
        if id == SKY {
            self.sky += w;
            return;
        }
        let sum = &mut self.sums[id as usize];
        // Every weight is positive, so a zero sum is an object not yet seen.
        if *sum == 0.0 {
            self.seen.push(id);
        }
        *sum += w;
    }

    /// The DoVs of the objects credited, by index, and the sky's.
    pub(super) fn finish(mut self) -> PointDov {
        self.seen.sort_unstable();
        PointDov {
            objects: self
                .seen
                .iter()
                .map(|&o| (o, self.sums[o as usize] as f32))
                .collect(),
            sky: self.sky as f32,
        }
    }
}
