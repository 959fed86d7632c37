//! What a database answers of its precomputed visibility: the viewcells and their PVS
//! records, and the HDoV-tree built over them.

use super::{Database, VisibilityInfo};
use crate::error::{Error, Result};
use crate::hdov::{self, HdovTree, Scheme, ScreenRule, SearchResult, TreeHead};
use crate::visibility::{CellPvs, TableHead};

impl Database {
    /// Whether the database holds precomputed visibility (reads nothing).
    pub fn has_visibility(&self) -> bool {
        self.visibility.is_some()
    }

    /// The viewcell grid, how the visibility was computed, and the walkable cells;
    /// `None` for a database built without `--visibility`. Reads the table's head the
    /// first time.
    pub fn visibility(&self) -> Result<Option<&TableHead>> {
        self.visibility
            .as_ref()
            .map(|t| t.head(&self.store))
            .transpose()
    }

    /// The potentially visible set of viewcell `cell`, with each object's degree of
    /// visibility: `None` when the database has no visibility or the cell is not a
    /// walkable one. Reads the pages of that cell's record.
    ///
    /// ```
    /// # fn main() -> flaneur::Result<()> {
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
    ///
    /// let db = flaneur::Database::open(&path)?;
    /// let head = db.visibility()?.expect("built with visibility");
    /// let cell = head.cells[0].id;
    /// let pvs = db.pvs(cell)?.expect("a walkable cell");
    /// assert!(pvs.dov.iter().all(|&d| d > 0.0 && d <= 1.0));
    /// assert!(pvs.ids.windows(2).all(|w| w[0] < w[1]));
    /// # Ok(()) }
    /// ```
    pub fn pvs(&self, cell: u32) -> Result<Option<CellPvs>> {
        match &self.visibility {
            Some(t) => t.pvs(&self.store, cell),
            None => Ok(None),
        }
    }

    /// The PVS records of viewcells `cells` are about to be read ([`pvs`](Self::pvs)):
    /// over HTTP their pages are fetched together. A hint: reads nothing on a local
    /// file, and nothing without visibility.
    pub fn announce_pvs(&self, cells: &[u32]) -> Result<()> {
        match &self.visibility {
            Some(t) => t.announce(&self.store, cells),
            None => Ok(()),
        }
    }

    /// The walkable viewcell under `p`, if there is one (and visibility at all).
    pub fn viewcell_at(&self, p: glam::Vec3) -> Result<Option<u32>> {
        match &self.visibility {
            Some(t) => t.cell_at(&self.store, p),
            None => Ok(None),
        }
    }

    /// The HDoV-tree's head (its nodes, fan-out, cells and schemes); `None` for a
    /// database built without `--hdov`. Reads the head the first time.
    pub fn hdov(&self) -> Result<Option<&TreeHead>> {
        self.hdov.as_ref().map(|t| t.head(&self.store)).transpose()
    }

    /// [`Database::hdov`] for a caller that needs the tree: an error naming the
    /// database when it was built without `--hdov`.
    pub fn hdov_head(&self) -> Result<&TreeHead> {
        self.hdov_tree()?.head(&self.store)
    }

    /// The HDoV-tree search (Shou 2002 Fig. 5.4) from viewcell `cell` under the DoV
    /// threshold `eta`, through the smallest storage scheme built (indexed-vertical,
    /// then vertical, then horizontal): what is visible from the cell, each object or
    /// group of objects with the detail it deserves. Every page it reads is counted
    /// ([`Database::io`]); the result says how many nodes and V-pages. An error for a
    /// database without an HDoV-tree or a cell that is not walkable.
    ///
    /// ```
    /// # fn main() -> flaneur::Result<()> {
    /// use flaneur::{hdov::HdovOptions, visibility::VisibilityOptions, BuildOptions};
    /// let dir = tempfile::tempdir().unwrap();
    /// let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
    /// let city = citygen::CityConfig { objects: 60, landmarks: 0.0, ..Default::default() };
    /// citygen::write_city(&city, &scene)?;
    /// let opts = BuildOptions {
    ///     visibility: Some(VisibilityOptions { resolution: 16, ..Default::default() }),
    ///     hdov: Some(HdovOptions::default()),
    ///     ..Default::default()
    /// };
    /// flaneur::build_from_scene(&scene, &path, &opts)?;
    ///
    /// let db = flaneur::Database::open(&path)?;
    /// let cell = db.hdov()?.expect("built with --hdov").cells[0];
    /// let all = db.hdov_search(cell, 0.0)?; // η = 0: the cell's PVS, every object
    /// assert_eq!(all.objects().count(), db.pvs(cell)?.unwrap().ids.len());
    /// let coarse = db.hdov_search(cell, 0.01)?; // groups of barely seen objects stop early
    /// assert!(coarse.nodes_read <= all.nodes_read);
    /// # Ok(()) }
    /// ```
    pub fn hdov_search(&self, cell: u32, eta: f32) -> Result<SearchResult> {
        let smallest = self.hdov_head()?.smallest_scheme()?;
        self.hdov_search_with(cell, eta, smallest)
    }

    /// [`Database::hdov_search`] through the storage scheme `scheme`.
    pub fn hdov_search_with(&self, cell: u32, eta: f32, scheme: Scheme) -> Result<SearchResult> {
        self.hdov_search_cached(cell, eta, scheme, None)
    }

    /// [`Database::hdov_search_with`], reading the tree's nodes through `cache` when
    /// given: the node cache of Shou 2002 §5.7, which holds the view-invariant nodes
    /// (not the V-pages, which change with the cell, nor the objects) under the pool's
    /// policy (LRU, DoV or DoV-Time, each told the node's DoV in the cell).
    ///
    /// ```no_run
    /// # fn main() -> flaneur::Result<()> {
    /// use flaneur::cache::{policy_by_name, BufferPool};
    /// let db = flaneur::Database::open("city.flaneur".as_ref())?;
    /// let cache = BufferPool::new(db.store(), 100 * 4096, policy_by_name("dov")?)?;
    /// let cell = db.hdov()?.expect("built with --hdov").cells[0];
    /// let scheme = flaneur::hdov::Scheme::Indexed;
    /// db.hdov_search_cached(cell, 0.0001, scheme, Some(&cache))?;
    /// println!("node cache hit rate {:.2}", cache.stats().hit_rate());
    /// # Ok(()) }
    /// ```
    pub fn hdov_search_cached(
        &self,
        cell: u32,
        eta: f32,
        scheme: Scheme,
        cache: Option<&crate::cache::BufferPool<'_>>,
    ) -> Result<SearchResult> {
        self.hdov_search_screened(cell, eta, Some(scheme), cache, None)
    }

    /// [`Database::hdov_search_cached`] with the selection rule: under `screen` (ours) a
    /// node's internal LOD is used only where its stored error also passes the rule's
    /// test; `None` is the thesis's search. `scheme` `None`: the smallest one built.
    ///
    /// ```no_run
    /// # fn main() -> flaneur::Result<()> {
    /// let db = flaneur::Database::open("city.flaneur".as_ref())?;
    /// let cell = db.hdov()?.expect("built with --hdov").cells[0];
    /// // The thesis's search through the smallest scheme built, without a node cache;
    /// // a VISUAL walk passes its screen rule (`hdov::ScreenRule`) instead of `None`.
    /// let result = db.hdov_search_screened(cell, 0.001, None, None, None)?;
    /// println!("{} finds", result.found.len());
    /// # Ok(()) }
    /// ```
    pub fn hdov_search_screened(
        &self,
        cell: u32,
        eta: f32,
        scheme: Option<Scheme>,
        cache: Option<&crate::cache::BufferPool<'_>>,
        screen: Option<&ScreenRule<'_>>,
    ) -> Result<SearchResult> {
        let tree = self.hdov_tree()?;
        let head = tree.head(&self.store)?;
        let slot = head.slot(cell).ok_or_else(|| {
            Error::Invalid(format!(
                "viewcell {cell} is not a walkable cell of the HDoV-tree"
            ))
        })?;
        let scheme = match scheme {
            Some(s) => s,
            None => head.smallest_scheme()?,
        };
        let stored = tree.scheme(&self.store, scheme)?;
        hdov::search(&self.store, (tree, stored), slot, eta, cache, screen)
    }

    /// What an HDoV search found, read at the detail it deserves: an object at the
    /// stored level eq. 5.6 picks, a node at the internal LOD eq. 5.5 picks
    /// (`hdov::level_for_detail`). Every page counted.
    pub fn hdov_load(&self, found: &hdov::Found) -> Result<hdov::Representation> {
        hdov::load(&self.store, self.lod.as_ref(), self.hdov.as_ref(), found)
    }

    /// A reader of what HDoV searches find, remembering their levels (a walk's).
    pub(crate) fn hdov_loader(&self) -> hdov::Loader<'_> {
        hdov::Loader::new(&self.store, self.lod.as_ref(), self.hdov.as_ref())
    }

    pub(crate) fn hdov_tree(&self) -> Result<&HdovTree> {
        self.hdov.as_ref().ok_or_else(|| {
            Error::Invalid(format!(
                "{} has no HDoV-tree: build it with --visibility --hdov",
                self.store.path().display()
            ))
        })
    }

    /// What `info` reports of the visibility; `None` without one. Reads the head.
    pub fn visibility_info(&self) -> Result<Option<VisibilityInfo>> {
        let Some(h) = self.visibility()? else {
            return Ok(None);
        };
        let cells = h.cells.len();
        let per = |v: f64, n: usize| if n == 0 { 0.0 } else { v / n as f64 };
        let mean_pvs = per(h.stats.entries as f64, cells);
        Ok(Some(VisibilityInfo {
            rows: h.grid.rows(),
            columns: h.grid.columns(),
            cells,
            cell_size: h.grid.size,
            eye: h.grid.eye,
            resolution: h.settings.resolution,
            sample_spacing: h.settings.samples.spacing,
            occluder_radius: h.settings.samples.radius,
            mean_pvs,
            mean_share: per(mean_pvs, h.stats.objects as usize),
            seconds: h.stats.seconds,
            seconds_per_cell: per(h.stats.seconds, cells),
            dov_seconds_per_cell: per(h.stats.dov_seconds, cells),
            rays: h.stats.rays,
            rays_per_second: if h.stats.dov_seconds > 0.0 {
                h.stats.rays as f64 / h.stats.dov_seconds
            } else {
                0.0
            },
        }))
    }
}
