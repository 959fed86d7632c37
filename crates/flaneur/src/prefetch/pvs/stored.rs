//! The prefetcher over a database's precomputed visibility: the server's table T read
//! through the store, one cell's record per request, every page counted.

use super::grid::{Cell, Position, ViewcellGrid};
use super::source::{ObjectId, PvsSource};
use crate::database::Database;
use crate::error::{Error, Result};

/// A database's viewcells and PVSs as a [`PvsSource`].
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// use flaneur::prefetch::pvs::{Pbnp, PvsClient, StoredPvs, DEFAULT_BORDER, THESIS_CAPACITY};
/// use flaneur::visibility::VisibilityOptions;
/// let dir = tempfile::tempdir().unwrap();
/// let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// let city = citygen::CityConfig { objects: 40, landmarks: 0.0, ..Default::default() };
/// citygen::write_city(&city, &scene)?;
/// let opts = flaneur::BuildOptions {
///     lod: None,
///     visibility: Some(VisibilityOptions { resolution: 16, ..Default::default() }),
///     ..Default::default()
/// };
/// flaneur::build_from_scene(&scene, &path, &opts)?;
/// let db = flaneur::Database::open(&path)?;
/// let source = StoredPvs::new(&db)?;
/// let start = source.walkable_centres()?[0];
/// let pbnp = Pbnp::new(DEFAULT_BORDER)?;
/// let mut client = PvsClient::new(&source, &pbnp, THESIS_CAPACITY)?;
/// // The first position fetches its area from an empty cache: one transaction.
/// let first = client.step(start)?;
/// assert!(first.transaction.is_some());
/// // Standing still fetches nothing more.
/// assert!(client.step(start)?.transaction.is_none());
/// # Ok(()) }
/// ```
pub struct StoredPvs<'a> {
    db: &'a Database,
    grid: ViewcellGrid,
}

impl<'a> StoredPvs<'a> {
    /// The source over `db`; an error when it was built without visibility.
    pub fn new(db: &'a Database) -> Result<StoredPvs<'a>> {
        let head = db.visibility()?.ok_or_else(|| {
            Error::Pvs(format!(
                "{} has no precomputed visibility: build it with --visibility",
                db.store().path().display()
            ))
        })?;
        let g = &head.grid;
        let grid = ViewcellGrid::new(
            Position::new(g.origin.x as f64, g.origin.z as f64),
            g.size as f64,
            g.rows(),
            g.columns(),
        )?;
        Ok(StoredPvs { db, grid })
    }

    fn id(&self, cell: Cell) -> Result<u32> {
        let head = self.db.visibility()?.expect("checked in new");
        if cell.row >= head.grid.rows() || cell.col >= head.grid.columns() {
            return Err(Error::Pvs(format!("cell {cell:?} is outside the grid")));
        }
        Ok(head.grid.id(cell.row, cell.col))
    }

    /// The centre of every walkable cell, in id order: where a route may go.
    pub fn walkable_centres(&self) -> Result<Vec<Position>> {
        let head = self.db.visibility()?.expect("checked in new");
        Ok(head
            .cells
            .iter()
            .map(|c| {
                let (r, col) = head.grid.place(c.id);
                let m = head.grid.cell_bounds(r, col).center();
                Position::new(m.x as f64, m.z as f64)
            })
            .collect())
    }
}

impl PvsSource for StoredPvs<'_> {
    fn grid(&self) -> &ViewcellGrid {
        &self.grid
    }

    fn scene_objects(&self) -> u64 {
        self.db.objects()
    }

    fn is_viewcell(&self, cell: Cell) -> Result<bool> {
        let id = self.id(cell)?;
        let head = self.db.visibility()?.expect("checked in new");
        Ok(head.cell(id).is_some())
    }

    fn announce(&self, cells: &[Cell]) -> Result<()> {
        let ids = cells
            .iter()
            .map(|&c| self.id(c))
            .collect::<Result<Vec<u32>>>()?;
        self.db.announce_pvs(&ids)
    }

    fn pvs(&self, cell: Cell) -> Result<Vec<ObjectId>> {
        let id = self.id(cell)?;
        self.db
            .pvs(id)?
            .map(|p| p.ids)
            .ok_or_else(|| Error::Pvs(format!("no viewcell lies at {cell:?}")))
    }
}
