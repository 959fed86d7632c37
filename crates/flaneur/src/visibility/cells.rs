//! Viewcells: a uniform grid of boxes over the walkable part of a city (Shou 2002 §5.5,
//! Zheng 2007 §7.2). A cell is a 3D box, the eye's height range over a square of
//! ground; its 8 corners are where visibility is sampled (paper-notes).
//!
//! Choices made here:
//! - The grid covers the city's bounds in x and z from their lower corner; row r runs
//!   along z, column c along x, and a cell's id is `r × columns + c`, stable for a given
//!   city and cell size.
//! - A cell is walkable when its centre, at the middle of the eye's range, lies outside
//!   every object's box: on a street or an open square, not in a building. Its box may
//!   still reach into buildings beside the street; the visibility computed for the box
//!   holds for every point in it, so it holds for the walkable part.
//! - The eye's range defaults to 1.2–2.0 m above the city's ground (its lowest point).

use glam::Vec3;

use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::scene::Mesh;

/// Default side of a viewcell in metres.
pub const DEFAULT_CELL_SIZE: f32 = 40.0;
/// Default eye heights above the ground, in metres.
pub const DEFAULT_EYE_RANGE: [f32; 2] = [1.2, 2.0];

/// The grid of viewcells over a city.
///
/// ```
/// use flaneur::geom::Aabb;
/// use flaneur::visibility::ViewcellGrid;
/// let city = Aabb::new([0.0, 0.0, 0.0], [100.0, 30.0, 60.0])?;
/// let grid = ViewcellGrid::new(&city, 20.0, [1.2, 2.0])?;
/// assert_eq!((grid.rows(), grid.columns()), (3, 5));
/// let (row, col) = grid.locate(glam::Vec3::new(45.0, 1.7, 25.0)).unwrap();
/// assert_eq!((row, col), (1, 2));
/// assert_eq!(grid.id(row, col), 7);
/// assert!(grid.locate(glam::Vec3::new(-1.0, 1.7, 25.0)).is_none());
/// # Ok::<(), flaneur::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewcellGrid {
    /// The grid's lower corner: x, ground height, z.
    pub origin: Vec3,
    /// The side of a cell in metres.
    pub size: f32,
    /// Eye heights above the ground covered by each cell.
    pub eye: [f32; 2],
    rows: u32,
    columns: u32,
}

/// One viewcell: its id, place in the grid, and box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewcell {
    /// The cell's id in its grid: `row × columns + column`.
    pub id: u32,
    /// The cell's row (along z).
    pub row: u32,
    /// The cell's column (along x).
    pub column: u32,
    /// The cell's box: its patch of ground, between the grid's two eye heights.
    pub bounds: Aabb,
}

impl ViewcellGrid {
    /// Checks a cell size and an eye range as [`ViewcellGrid::new`] takes them, before
    /// any city is at hand.
    pub fn check(size: f32, eye: [f32; 2]) -> Result<()> {
        if !(size.is_finite() && size > 0.0) {
            return Err(Error::Invalid(format!(
                "viewcell size {size} m (--cell-size): it must be a positive number of metres"
            )));
        }
        if !(eye[0].is_finite() && eye[1].is_finite() && 0.0 <= eye[0] && eye[0] < eye[1]) {
            return Err(Error::Invalid(format!(
                "eye range {}–{} m: it must be finite, from 0 up, and not empty",
                eye[0], eye[1]
            )));
        }
        Ok(())
    }

    /// The grid of `size`-metre cells over `city`'s bounds, for eyes between `eye[0]`
    /// and `eye[1]` metres above its ground.
    pub fn new(city: &Aabb, size: f32, eye: [f32; 2]) -> Result<ViewcellGrid> {
        city.validate()?;
        ViewcellGrid::check(size, eye)?;
        let extent = city.extent();
        let count = |len: f32| (len / size).ceil().max(1.0);
        let (columns, rows) = (count(extent.x), count(extent.z));
        if columns * rows > u32::MAX as f32 / 2.0 {
            return Err(Error::Invalid(format!(
                "viewcell size {size} m makes {columns} × {rows} cells over the city: \
                 choose a larger size"
            )));
        }
        Ok(ViewcellGrid {
            origin: city.min,
            size,
            eye,
            rows: rows as u32,
            columns: columns as u32,
        })
    }

    /// Rows of cells (along z).
    pub fn rows(&self) -> u32 {
        self.rows
    }

    /// Columns of cells (along x).
    pub fn columns(&self) -> u32 {
        self.columns
    }

    /// The number of cells, walkable or not.
    pub fn len(&self) -> usize {
        self.rows as usize * self.columns as usize
    }

    /// Whether the grid has no cell (never, for a grid [`ViewcellGrid::new`] made).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The id of the cell at (`row`, `column`).
    pub fn id(&self, row: u32, column: u32) -> u32 {
        row * self.columns + column
    }

    /// The (row, column) of cell `id`.
    pub fn place(&self, id: u32) -> (u32, u32) {
        (id / self.columns, id % self.columns)
    }

    /// The box of the cell at (`row`, `column`).
    pub fn cell_bounds(&self, row: u32, column: u32) -> Aabb {
        let min = self.origin
            + Vec3::new(
                column as f32 * self.size,
                self.eye[0],
                row as f32 * self.size,
            );
        Aabb {
            min,
            max: min + Vec3::new(self.size, self.eye[1] - self.eye[0], self.size),
        }
    }

    /// The cell whose ground square holds `p` (whatever its height), or `None` when `p`
    /// is outside the grid or not finite.
    pub fn locate(&self, p: Vec3) -> Option<(u32, u32)> {
        if !p.is_finite() {
            return None;
        }
        let c = ((p.x - self.origin.x) / self.size).floor();
        let r = ((p.z - self.origin.z) / self.size).floor();
        (c >= 0.0 && r >= 0.0 && c < self.columns as f32 && r < self.rows as f32)
            .then_some((r as u32, c as u32))
    }

    /// Every cell whose centre, at the middle of the eye's range, lies in none of
    /// `obstacles` (the objects' boxes), in id order.
    pub fn walkable(&self, obstacles: &[Aabb]) -> Vec<Viewcell> {
        let mut cells = Vec::new();
        self.each_walkable(obstacles, |cell| cells.push(cell));
        cells
    }

    /// How many cells [`walkable`](Self::walkable) would give, without holding them:
    /// what a build checks its memory by before it computes them.
    pub fn walkable_count(&self, obstacles: &[Aabb]) -> u64 {
        let mut count = 0;
        self.each_walkable(obstacles, |_| count += 1);
        count
    }

    /// Hands `found` every walkable cell, in id order.
    fn each_walkable(&self, obstacles: &[Aabb], mut found: impl FnMut(Viewcell)) {
        let index = rstar::RTree::bulk_load(
            obstacles
                .iter()
                .map(|b| {
                    rstar::primitives::Rectangle::from_corners(b.min.to_array(), b.max.to_array())
                })
                .collect(),
        );
        for row in 0..self.rows {
            for column in 0..self.columns {
                let bounds = self.cell_bounds(row, column);
                let c = bounds.center();
                let point = rstar::AABB::from_point(c.to_array());
                if index
                    .locate_in_envelope_intersecting(&point)
                    .next()
                    .is_none()
                {
                    found(Viewcell {
                        id: self.id(row, column),
                        row,
                        column,
                        bounds,
                    });
                }
            }
        }
    }
}

/// Each object's box (its mesh's bounds) and the bounds of them all: the obstacles a
/// [`ViewcellGrid`] finds its walkable cells among, and the city it is laid over. An
/// error names the object whose mesh has no valid box, or says there is no object.
///
/// ```
/// use flaneur::visibility::{object_boxes, ViewcellGrid};
/// let config = citygen::CityConfig { objects: 40, ..Default::default() };
/// let objects = (0..40)
///     .map(|id| citygen::object(&config, id))
///     .collect::<Result<Vec<_>, _>>()?;
/// let (boxes, city) = object_boxes(objects.iter().map(|o| (o.id, &o.mesh)))?;
/// let grid = ViewcellGrid::new(&city, 20.0, [1.2, 2.0])?;
/// let cells = grid.walkable(&boxes);
/// assert!(!cells.is_empty() && cells.len() < grid.len());
/// # Ok::<(), flaneur::Error>(())
/// ```
pub fn object_boxes<'a>(
    objects: impl IntoIterator<Item = (u64, &'a Mesh)>,
) -> Result<(Vec<Aabb>, Aabb)> {
    let boxes = objects
        .into_iter()
        .map(|(id, m)| {
            let (lo, hi) = m.bounds();
            Aabb::new(lo, hi).map_err(|e| Error::Invalid(format!("object {id}: {e}")))
        })
        .collect::<Result<Vec<_>>>()?;
    if boxes.is_empty() {
        return Err(Error::Invalid(
            "visibility of a city with no objects".into(),
        ));
    }
    let city = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(b));
    Ok((boxes, city))
}

impl Viewcell {
    /// The 8 corners of the cell's box, where visibility is sampled.
    pub fn corners(&self) -> [Vec3; 8] {
        corners(&self.bounds)
    }
}

/// The 8 corners of a box: bit 0 of the index picks max x, bit 1 max y, bit 2 max z.
pub fn corners(b: &Aabb) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_tile_the_city_and_skip_buildings() {
        let city = Aabb::new([10.0, 0.0, 20.0], [70.0, 40.0, 61.0]).unwrap();
        let grid = ViewcellGrid::new(&city, 20.0, DEFAULT_EYE_RANGE).unwrap();
        assert_eq!((grid.rows(), grid.columns(), grid.len()), (3, 3, 9));
        for id in 0..9 {
            let (r, c) = grid.place(id);
            assert_eq!(grid.id(r, c), id);
            let b = grid.cell_bounds(r, c);
            assert_eq!(grid.locate(b.center()), Some((r, c)));
            assert_eq!(b.min.y, 1.2);
            assert_eq!(b.max.y, 2.0);
        }
        // A building over the middle cell's centre makes it unwalkable.
        let building = Aabb::new([35.0, 0.0, 45.0], [45.0, 12.0, 55.0]).unwrap();
        let cells = grid.walkable(&[building]);
        assert_eq!(cells.len(), 8);
        assert!(cells.iter().all(|c| c.id != 4));
        assert_eq!(corners(&cells[0].bounds).len(), 8);
    }

    #[test]
    fn bad_settings_are_refused() {
        let city = Aabb::new([0.0; 3], [100.0, 10.0, 100.0]).unwrap();
        for size in [0.0, -5.0, f32::NAN, f32::INFINITY, 1e-6] {
            assert!(
                ViewcellGrid::new(&city, size, DEFAULT_EYE_RANGE).is_err(),
                "{size}"
            );
        }
        for eye in [[2.0, 1.0], [1.0, 1.0], [-1.0, 1.0], [0.0, f32::NAN]] {
            assert!(ViewcellGrid::new(&city, 10.0, eye).is_err(), "{eye:?}");
        }
        let grid = ViewcellGrid::new(&city, 10.0, DEFAULT_EYE_RANGE).unwrap();
        assert_eq!(grid.locate(Vec3::new(f32::NAN, 0.0, 0.0)), None);
        assert_eq!(grid.locate(Vec3::new(100.5, 0.0, 5.0)), None);
    }
}
