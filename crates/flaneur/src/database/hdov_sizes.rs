//! What an HDoV-tree's storage schemes would take at other fan-outs, from an open
//! database's objects and visibility: `flaneur bench hdov-storage --fanouts`.

use super::Database;
use crate::error::{Error, Result};
use crate::hdov::{sizes_at, FanoutSizes};

impl Database {
    /// The V-page storage of an HDoV-tree over this database's objects and viewcells at
    /// fan-out `fanout` (entries a node holds), under each scheme (Shou 2002 eqs.
    /// 5.7–5.9), without building the tree: no internal LODs, nothing written. Reads every
    /// cell's PVS. An error for a database built without `--visibility`.
    ///
    /// ```
    /// # fn main() -> flaneur::Result<()> {
    /// use flaneur::{hdov::Scheme, visibility::VisibilityOptions, BuildOptions};
    /// let dir = tempfile::tempdir().unwrap();
    /// let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
    /// let city = citygen::CityConfig { objects: 60, landmarks: 0.0, ..Default::default() };
    /// citygen::write_city(&city, &scene)?;
    /// let opts = BuildOptions {
    ///     visibility: Some(VisibilityOptions { resolution: 16, ..Default::default() }),
    ///     lod: None,
    ///     ..Default::default()
    /// };
    /// flaneur::build_from_scene(&scene, &path, &opts)?;
    /// let db = flaneur::Database::open(&path)?;
    /// let small = db.hdov_sizes_at(4)?;
    /// let large = db.hdov_sizes_at(16)?;
    /// assert!(small.nodes > large.nodes);
    /// // A cell sees at most every node of the tree.
    /// assert!(small.visible_share() <= 1.0 && small.share_of_horizontal(Scheme::Indexed) > 0.0);
    /// # Ok(()) }
    /// ```
    pub fn hdov_sizes_at(&self, fanout: u32) -> Result<FanoutSizes> {
        let head = self.visibility()?.ok_or_else(|| {
            Error::Invalid(
                "the HDoV-tree's storage needs the viewcells' visibility: build with --visibility"
                    .into(),
            )
        })?;
        let cells: Vec<u32> = head.cells.iter().map(|c| c.id).collect();
        let mut objects = self.range(&self.bounds())?.objects;
        // By id, as the build hands them to packing, so that the tree's own fan-out
        // packs the same nodes.
        objects.sort_unstable_by_key(|o| o.id);
        sizes_at(objects, &cells, fanout, |id| {
            let pvs = self.pvs(id)?.ok_or_else(|| {
                Error::Invalid(format!("viewcell {id} is in the directory but has no PVS"))
            })?;
            Ok((pvs.ids, pvs.dov))
        })
    }
}
