//! `Database`: one open database file — its store, its R-tree, its LOD table — and the
//! queries a library user runs on it. No window, no GPU, no global state. What it
//! answers of its precomputed visibility and HDoV-tree is `visibility`'s.

mod build_input;
mod hdov_sizes;
mod visibility;

use std::path::Path;

use crate::catalog::{load_codec, load_meta, save_meta, write_object};
use crate::error::{Error, Result};
use crate::geom::{Aabb, Camera};
use crate::hdov::{self, HdovTree};
use crate::lod::stored::LodTable;
use crate::lod::{stored, Dag, LevelInfo, LodStats, ProgressiveMesh};
use crate::names::NameTable;
use crate::rtree::{BoxIndex, Coverlap, History, ObjectEntry, QueryResult, RTree, TreeStats};
use crate::scene::{Mesh, MeshCodec};
use crate::store::{Backend, HttpOptions, IoStats, PageKind, RemoteStats, RequestTimes, Store};
use crate::visibility::VisibilityTable;

pub use crate::catalog::KindCounts;
pub use build_input::BuildInput;

/// What `flaneur info` prints.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # citygen::write_city(&citygen::CityConfig { objects: 40, landmarks: 0.0, ..Default::default() }, &scene)?;
/// # flaneur::build_from_scene(&scene, &path, &Default::default())?;
/// let info = flaneur::Database::open(&path)?.info()?;
/// assert_eq!(info.objects, 40);
/// assert_eq!(info.file_bytes, info.pages * info.page_size as u64);
/// assert!(info.lod.is_some() && info.visibility.is_none());
/// # Ok(()) }
/// ```
#[derive(Clone, Debug, serde::Serialize)]
pub struct DatabaseInfo {
    /// Objects in the database.
    pub objects: u64,
    /// Triangles over all objects' full meshes.
    pub triangles: u64,
    /// Bytes per page.
    pub page_size: usize,
    /// Pages of the file, the header included.
    pub pages: u64,
    /// The database's length: pages × page size.
    pub file_bytes: u64,
    /// Bytes in the file past the database's pages (see
    /// [`Store::uncommitted_bytes`](crate::store::Store::uncommitted_bytes)): what an
    /// interrupted writer left, or bytes appended by something else; never read.
    pub uncommitted_bytes: u64,
    /// Pages written per kind.
    pub pages_by_kind: KindCounts,
    /// The file's format version (1 or 2).
    pub format_version: u32,
    /// How its meshes are coded.
    pub codec: MeshCodec,
    /// Bytes of the zstd dictionaries its meshes and levels are compressed with (0 when
    /// it has none).
    pub dictionary_bytes: u64,
    /// Bytes of each kind's pages per full-detail triangle: the currency a walk pays
    /// in.
    pub bytes_per_triangle: BytesPerTriangle,
    /// The box around every object: its min x, y, z, then its max x, y, z.
    pub bounds: [f32; 6],
    /// The R-tree's shape: nodes and entries per level, and their fill.
    pub tree: TreeStats,
    /// The most entries a leaf node holds.
    pub fanout_leaf: usize,
    /// The most entries an internal node holds.
    pub fanout_internal: usize,
    /// Objects with a name from the file they were imported from (0 without a names
    /// table: see [`Database::object_name`]).
    pub named_objects: u64,
    /// What the database holds as LODs; `None` when it holds none (built with
    /// `--no-lod`, or before LODs were stored).
    pub lod: Option<LodStats>,
    /// The precomputed visibility; `None` when the build computed none.
    pub visibility: Option<VisibilityInfo>,
    /// The HDoV-tree; absent (and left out of the JSON) when the build made none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hdov: Option<HdovInfo>,
}

/// Bytes of pages per full-detail triangle, the whole file and by kind (`flaneur info`).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct BytesPerTriangle {
    /// The whole file.
    pub whole: f64,
    /// The objects' meshes.
    pub mesh: f64,
    /// The LODs: chains, progressive meshes and DAGs, the LOD table.
    pub lod: f64,
    /// The R-tree's nodes.
    pub rtree: f64,
    /// The visibility table.
    pub visibility: f64,
}

impl BytesPerTriangle {
    fn of(kinds: &KindCounts, pages: u64, page_size: usize, triangles: u64) -> BytesPerTriangle {
        let per = |p: u64| p as f64 * page_size as f64 / triangles.max(1) as f64;
        BytesPerTriangle {
            whole: per(pages),
            mesh: per(kinds.mesh),
            lod: per(kinds.lod),
            rtree: per(kinds.rtree),
            visibility: per(kinds.visibility),
        }
    }
}

/// What `flaneur info` reports of the HDoV-tree.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// use flaneur::{hdov::{HdovOptions, Scheme}, visibility::VisibilityOptions, BuildOptions};
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # citygen::write_city(&citygen::CityConfig { objects: 40, landmarks: 0.0, ..Default::default() }, &scene)?;
/// let opts = BuildOptions {
///     visibility: Some(VisibilityOptions { resolution: 16, ..Default::default() }),
///     hdov: Some(HdovOptions { schemes: vec![Scheme::Indexed], ..Default::default() }),
///     ..Default::default()
/// };
/// flaneur::build_from_scene(&scene, &path, &opts)?;
/// let hdov = flaneur::Database::open(&path)?.info()?.hdov.expect("built with --hdov");
/// assert_eq!(hdov.schemes.len(), 1);
/// assert!(hdov.cells > 0 && hdov.nodes >= 1);
/// # Ok(()) }
/// ```
#[derive(Clone, Debug, serde::Serialize)]
pub struct HdovInfo {
    /// Nodes, levels, and the entries packing put in a node (M).
    pub nodes: u32,
    /// Levels of nodes.
    pub height: u32,
    /// The entries packing put in a node (M, the base of h's log).
    pub fanout: u32,
    /// Viewcells, and N_vnode summed over them.
    pub cells: usize,
    /// Visible nodes summed over the cells (N_vnode).
    pub visible_nodes: u64,
    /// Pages of the internal LODs.
    pub lod_pages: u64,
    /// Each scheme stored, and its bytes.
    pub schemes: Vec<(hdov::Scheme, u64)>,
    /// The build's seconds for the tree.
    pub seconds: f64,
}

/// What `flaneur info` reports of the precomputed visibility.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VisibilityInfo {
    /// Rows of the viewcell grid.
    pub rows: u32,
    /// Columns of the viewcell grid.
    pub columns: u32,
    /// Walkable cells, each with a PVS.
    pub cells: usize,
    /// The side of a viewcell, metres.
    pub cell_size: f32,
    /// The eye heights a viewcell covers, metres above the ground.
    pub eye: [f32; 2],
    /// Pixels per side of a cube face for the DoV (N).
    pub resolution: u32,
    /// The conservative test's widest sampled patch, in metres.
    pub sample_spacing: f32,
    /// The conservative test's occluder radius, in metres: occluders further from a
    /// sample (in plan) were not used.
    pub occluder_radius: f32,
    /// Mean objects per PVS.
    pub mean_pvs: f64,
    /// The mean objects per PVS as a share of the scene's objects.
    pub mean_share: f64,
    /// Seconds of the whole precomputation.
    pub seconds: f64,
    /// Seconds of the whole precomputation per cell.
    pub seconds_per_cell: f64,
    /// Seconds spent casting the DoV's rays, per cell.
    pub dov_seconds_per_cell: f64,
    /// DoV rays cast.
    pub rays: u64,
    /// DoV rays cast per second of casting them.
    pub rays_per_second: f64,
}

/// An open database.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # citygen::write_city(&citygen::CityConfig { objects: 40, landmarks: 0.0, ..Default::default() }, &scene)?;
/// # flaneur::build_from_scene(&scene, &path, &Default::default())?;
/// let db = flaneur::Database::open(&path)?;
/// let hits = db.range(&db.bounds())?;
/// assert_eq!(hits.objects.len(), 40);
/// println!("{} objects, {} pages read", hits.objects.len(), hits.pages.len());
/// # Ok(()) }
/// ```
pub struct Database {
    store: Store,
    tree: RTree,
    objects: u64,
    triangles: u64,
    bounds: Aabb,
    kinds: KindCounts,
    lod: Option<LodTable>,
    visibility: Option<VisibilityTable>,
    hdov: Option<HdovTree>,
    names: Option<NameTable>,
    /// Every object's box in memory, read the first time a walk asks for its misses.
    boxes: std::sync::OnceLock<BoxIndex>,
}

impl Database {
    /// Opens read-only with the default (mmap) backend.
    pub fn open(path: &Path) -> Result<Database> {
        Database::open_with(path, Backend::default())
    }

    /// Opens read-only with the given backend. A file that is not a database but a
    /// build's input (a scene file, a model: see [`BuildInput`]) is
    /// [`Error::NotADatabase`] saying what it is.
    pub fn open_with(path: &Path, backend: Backend) -> Result<Database> {
        Database::from_store(Store::open(path, backend).map_err(build_input::explain)?)
    }

    /// Opens a database on an HTTP server, read by byte ranges through a client page
    /// cache, with the default [`HttpOptions`]: any static server that honours `Range`
    /// (nginx, an object store, a CDN) will do. Every query answers as it would on the
    /// local file, pages counted the same; [`Database::remote_stats`] says what the
    /// network cost. See [`Store::open_url`] for the errors.
    ///
    /// ```no_run
    /// # fn main() -> flaneur::Result<()> {
    /// let db = flaneur::Database::open_url("https://example.org/cities/demo.flaneur")?;
    /// println!("{} objects", db.objects());
    /// println!("{:?}", db.remote_stats());
    /// # Ok(()) }
    /// ```
    pub fn open_url(url: &str) -> Result<Database> {
        Database::open_url_with(url, &HttpOptions::default())
    }

    /// [`Database::open_url`] with the client's cache, timeouts and retries chosen.
    pub fn open_url_with(url: &str, opts: &HttpOptions) -> Result<Database> {
        Database::from_store(Store::open_url(url, opts).map_err(build_input::explain)?)
    }

    /// Opens `location`: a URL (`http://…`, `https://…`) over HTTP with `http`'s
    /// settings, else a file path with `backend`. What a command that takes "a database"
    /// calls.
    pub fn open_location(location: &str, backend: Backend, http: &HttpOptions) -> Result<Database> {
        if crate::store::is_url(location) {
            Database::open_url_with(location, http)
        } else {
            Database::open_with(Path::new(location), backend)
        }
    }

    /// What reading this database over HTTP has cost so far; `None` for a local file.
    pub fn remote_stats(&self) -> Option<RemoteStats> {
        self.store.remote_stats()
    }

    /// What a reader of this database over HTTP should be told once, at the open (see
    /// [`RemoteStats::warnings`]): a server that names no version of the file, a page
    /// cache capped by the memory available. Empty for a local file.
    pub fn remote_warnings(&self) -> Vec<String> {
        self.remote_stats()
            .map(|s| s.warnings(&self.store.path().to_string_lossy()))
            .unwrap_or_default()
    }

    /// How long each of this reader's requests over HTTP took (sent to last body byte),
    /// for p50/p99 figures; `None` for a local file.
    pub fn remote_request_times(&self) -> Option<RequestTimes> {
        self.store.remote_request_times()
    }

    /// Opens for [`Database::insert`], holding the database's write lock until dropped:
    /// one writer at a time, while readers go on (see [`Store::open_writable`]).
    pub fn open_writable(path: &Path, backend: Backend) -> Result<Database> {
        Database::from_store(Store::open_writable(path, backend)?)
    }

    fn from_store(store: Store) -> Result<Database> {
        let tree = RTree::load(&store)?;
        let meta = load_meta(&store)?;
        let lod = LodTable::open(&store)?;
        let visibility = VisibilityTable::open(&store)?;
        let hdov = HdovTree::open(&store)?;
        let names = NameTable::open(&store)?;
        let kinds = KindCounts {
            lod: lod.as_ref().map_or(0, LodTable::pages),
            visibility: visibility.as_ref().map_or(0, VisibilityTable::pages),
            ..meta.kinds
        };
        if meta.objects != tree.objects {
            return Err(Error::CorruptPage {
                path: store.path().to_path_buf(),
                page: 0,
                what: format!(
                    "header counts {} objects but the R-tree {}",
                    meta.objects, tree.objects
                ),
            });
        }
        Ok(Database {
            tree,
            objects: meta.objects,
            triangles: meta.triangles,
            bounds: meta.bounds,
            kinds,
            lod,
            visibility,
            hdov,
            names,
            store,
            boxes: std::sync::OnceLock::new(),
        })
    }

    /// What object `id` was called in the file it was imported from: its OpenStreetMap
    /// element (`way/123`, `relation/45`), its glTF node's or OBJ object's name. `None`
    /// for an object without one: from a scene file, unnamed, or inserted later.
    /// Reads the pages that hold that one name.
    ///
    /// ```
    /// # fn main() -> flaneur::Result<()> {
    /// # let dir = tempfile::tempdir().unwrap();
    /// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
    /// # citygen::write_city(&citygen::CityConfig { objects: 10, ..Default::default() }, &scene)?;
    /// flaneur::build_from_scene(&scene, &path, &Default::default())?;
    /// // A generated city's objects have ids, not names.
    /// assert_eq!(flaneur::Database::open(&path)?.object_name(3)?, None);
    /// # Ok(()) }
    /// ```
    pub fn object_name(&self, id: u64) -> Result<Option<String>> {
        match &self.names {
            Some(t) => t.name(&self.store, id),
            None => Ok(None),
        }
    }

    /// Objects with an entry in the names table (0 without a table).
    pub fn named_objects(&self) -> u64 {
        self.names.as_ref().map_or(0, NameTable::len)
    }

    /// BOX: every object whose box overlaps `query`.
    pub fn range(&self, query: &Aabb) -> Result<QueryResult> {
        self.tree.range(&self.store, query)
    }

    /// Every object's box in memory: the ground truth of a walk's visual misses, apart
    /// from the pages a walk counts. Built the first time it is asked for, from a range
    /// query over the whole city (read then, before the walk resets its counters), and
    /// kept by the handle, so that walks one after another read the R-tree once.
    pub(crate) fn box_index(&self) -> Result<&BoxIndex> {
        if let Some(index) = self.boxes.get() {
            return Ok(index);
        }
        let index = BoxIndex::new(&self.range(&self.bounds)?.objects);
        Ok(self.boxes.get_or_init(|| index))
    }

    /// The objects whose boxes meet `camera`'s view frustum: a range query over the
    /// frustum's box, then the frustum test. What a full-detail picture from `camera`
    /// draws (each object's mesh through [`Database::mesh`]).
    pub fn in_view(&self, camera: &Camera) -> Result<Vec<ObjectEntry>> {
        let frustum = camera.frustum();
        let mut found = self.range(&frustum.aabb())?.objects;
        found.retain(|o| frustum.overlaps_aabb(&o.bounds));
        Ok(found)
    }

    /// CSearch: the objects overlapping `cell` and none of the `history` cells.
    pub fn csearch(&self, cell: &Aabb, history: &[Aabb]) -> Result<QueryResult> {
        self.tree.csearch(&self.store, cell, history)
    }

    /// One CSearch step of a walk, filtering and extending `history`.
    pub fn csearch_step(&self, history: &mut History, cell: &Aabb) -> Result<QueryResult> {
        self.tree
            .csearch_step(&self.store, history, cell, Coverlap::default())
    }

    /// CSearch with an explicit descent rule; same result, different pages.
    pub fn csearch_with(
        &self,
        cell: &Aabb,
        history: &[Aabb],
        rule: Coverlap,
    ) -> Result<QueryResult> {
        self.tree.csearch_with(&self.store, cell, history, rule)
    }

    /// Reads an object's mesh (counted like every read).
    pub fn mesh(&self, object: &ObjectEntry) -> Result<Mesh> {
        crate::catalog::read_mesh(&self.store, object)
    }

    /// Whether the database holds LOD data (reads nothing).
    pub fn has_lods(&self) -> bool {
        self.lod.is_some()
    }

    /// What the build stored as LODs, `None` for a database without them. Reads the LOD
    /// table's head the first time.
    pub fn lod_stats(&self) -> Result<Option<LodStats>> {
        self.lod.as_ref().map(|t| t.stats(&self.store)).transpose()
    }

    /// The levels of detail of object `id`, level 0 (its full mesh, error 0) first,
    /// each coarser one after: `None` when the object has no LOD data (a database built
    /// without LODs, an object added by [`Database::insert`], one the simplifier
    /// refused, or no such object). Reads the LOD table's entry page and the first page
    /// of the object's chain.
    ///
    /// ```
    /// # fn main() -> flaneur::Result<()> {
    /// let dir = tempfile::tempdir().unwrap();
    /// let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
    /// let city = citygen::CityConfig { objects: 40, landmarks: 0.0, ..Default::default() };
    /// citygen::write_city(&city, &scene)?;
    /// flaneur::build_from_scene(&scene, &path, &flaneur::BuildOptions::default())?;
    ///
    /// let db = flaneur::Database::open(&path)?;
    /// let levels = db.lod_levels(0)?.expect("object 0 has LODs");
    /// assert_eq!(levels[0].error, 0.0);
    /// assert!(levels.windows(2).all(|w| w[1].triangles < w[0].triangles));
    /// assert!(db.lod_levels(1_000_000)?.is_none());
    /// # Ok(()) }
    /// ```
    pub fn lod_levels(&self, id: u64) -> Result<Option<Vec<LevelInfo>>> {
        match self.lod_entry(id)? {
            Some(e) => Ok(Some(stored::levels(&self.store, &e)?)),
            None => Ok(None),
        }
    }

    /// Every coarse level `id` has stored (all but its full mesh), finest first, each
    /// with its error in metres: what a build hands the DoV's rasteriser for far
    /// objects. Empty for an object with no LOD data or no coarse level.
    ///
    /// ```
    /// # fn main() -> flaneur::Result<()> {
    /// # let dir = tempfile::tempdir().unwrap();
    /// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
    /// # let city = citygen::CityConfig { objects: 40, landmarks: 0.0, ..Default::default() };
    /// # citygen::write_city(&city, &scene)?;
    /// # flaneur::build_from_scene(&scene, &path, &flaneur::BuildOptions::default())?;
    /// let db = flaneur::Database::open(&path)?;
    /// let levels = db.lod_levels(0)?.unwrap();
    /// let coarse = db.lod_coarse_levels(0)?;
    /// assert_eq!(coarse.len(), levels.len() - 1);
    /// assert_eq!(coarse[0].1, levels[1].error);
    /// # Ok(()) }
    /// ```
    pub fn lod_coarse_levels(&self, id: u64) -> Result<Vec<(Mesh, f32)>> {
        match self.lod_entry(id)? {
            Some(e) => stored::coarse_levels(&self.store, &e),
            None => Ok(Vec::new()),
        }
    }

    /// The stored level a viewer at `eye` should see `object` at: the coarsest whose
    /// error stays under `tau` of the viewport for a vertical field of view `fov_y`
    /// (radians), as a walk's LOD selection chooses it ([`crate::lod::level_for`], the
    /// distance taken to the object's box). Level 0, the full mesh, when the object has
    /// no LOD data or the eye is inside its box. Reads only the object's LOD entry and
    /// its chain's directory; [`Database::lod_mesh`] then reads that level.
    ///
    /// ```
    /// # fn main() -> flaneur::Result<()> {
    /// # let dir = tempfile::tempdir().unwrap();
    /// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
    /// # let city = citygen::CityConfig { objects: 40, landmarks: 0.0, ..Default::default() };
    /// # citygen::write_city(&city, &scene)?;
    /// # flaneur::build_from_scene(&scene, &path, &flaneur::BuildOptions::default())?;
    /// use glam::Vec3;
    /// let db = flaneur::Database::open(&path)?;
    /// let house = db.range(&db.bounds())?.objects[0];
    /// let fov = 60f32.to_radians();
    /// let near = db.lod_level_for(&house, house.bounds.center(), fov, 0.001)?;
    /// let far = db.lod_level_for(&house, house.bounds.center() + Vec3::X * 5_000.0, fov, 0.001)?;
    /// assert_eq!(near.level, 0); // standing inside it: full detail
    /// assert!(far.level > 0 && far.triangles < near.triangles);
    /// let mesh = db.lod_mesh(house.id, far.level)?;
    /// assert_eq!(mesh.triangle_count(), far.triangles as usize);
    /// # Ok(()) }
    /// ```
    pub fn lod_level_for(
        &self,
        object: &ObjectEntry,
        eye: glam::Vec3,
        fov_y: f32,
        tau: f32,
    ) -> Result<LevelInfo> {
        let full = LevelInfo {
            level: 0,
            triangles: object.triangles,
            error: 0.0,
        };
        let Some(levels) = self.lod_levels(object.id)? else {
            return Ok(full);
        };
        let level = crate::lod::level_for(
            &levels,
            crate::lod::distance_to(&object.bounds, eye),
            fov_y,
            tau,
        );
        Ok(levels.get(level).copied().unwrap_or(full))
    }

    /// Level `level` of object `id` as a mesh (0: the full mesh). Reads the LOD table's
    /// entry page, then for a coarse level only the pages of the object's chain that
    /// hold its directory and that level — the coarser the level, the fewer pages.
    /// Counted like every read. An `Error::Invalid` when the object has no LOD data or
    /// no such level; a `CorruptPage` naming the page and the object when the data is
    /// damaged.
    ///
    /// ```
    /// # fn main() -> flaneur::Result<()> {
    /// # let dir = tempfile::tempdir().unwrap();
    /// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
    /// # let city = citygen::CityConfig { objects: 40, landmarks: 0.0, ..Default::default() };
    /// # citygen::write_city(&city, &scene)?;
    /// # flaneur::build_from_scene(&scene, &path, &flaneur::BuildOptions::default())?;
    /// let db = flaneur::Database::open(&path)?;
    /// let levels = db.lod_levels(0)?.unwrap();
    /// let coarsest = db.lod_mesh(0, levels.len() - 1)?;
    /// assert_eq!(coarsest.triangle_count(), levels.last().unwrap().triangles as usize);
    /// println!("{} pages read", db.io().page_reads);
    /// # Ok(()) }
    /// ```
    pub fn lod_mesh(&self, id: u64, level: usize) -> Result<Mesh> {
        let e = self.lod_entry(id)?.ok_or_else(|| {
            Error::Invalid(format!(
                "{}: object {id} has no LOD data",
                self.store.path().display()
            ))
        })?;
        stored::level_mesh(&self.store, &e, level)
    }

    /// The coarsest stored level of each of `objects` and its number (0, the full mesh,
    /// for an object with no coarser level or no LOD data), in their order: what a
    /// viewer draws first while finer levels come. The pages each step needs (the LOD
    /// table's entry pages, the chains' first pages, the levels' remaining pages) are
    /// asked for together, so that over HTTP a batch costs three steps of parallel
    /// requests, not a few round trips per object. Counted like every read.
    ///
    /// ```
    /// # fn main() -> flaneur::Result<()> {
    /// # let dir = tempfile::tempdir().unwrap();
    /// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
    /// # let city = citygen::CityConfig { objects: 40, landmarks: 0.0, ..Default::default() };
    /// # citygen::write_city(&city, &scene)?;
    /// # flaneur::build_from_scene(&scene, &path, &flaneur::BuildOptions::default())?;
    /// let db = flaneur::Database::open(&path)?;
    /// let objects = db.range(&db.bounds())?.objects;
    /// let coarse = db.coarsest_meshes(&objects)?;
    /// for (o, (level, mesh)) in objects.iter().zip(&coarse) {
    ///     let levels = db.lod_levels(o.id)?.unwrap();
    ///     assert_eq!(*level, levels.len() - 1);
    ///     assert_eq!(mesh.triangle_count(), levels[*level].triangles as usize);
    /// }
    /// # Ok(()) }
    /// ```
    pub fn coarsest_meshes(&self, objects: &[ObjectEntry]) -> Result<Vec<(usize, Mesh)>> {
        let found: Vec<Option<stored::LodEntry>> = match &self.lod {
            Some(table) => {
                let mut pages = objects
                    .iter()
                    .filter_map(|o| table.entry_page(&self.store, o.id).transpose())
                    .collect::<Result<Vec<u64>>>()?;
                pages.dedup();
                self.store.announce(&pages);
                objects
                    .iter()
                    .map(|o| table.find(&self.store, o.id))
                    .collect::<Result<_>>()?
            }
            None => vec![None; objects.len()],
        };
        // Objects without LOD data (a database built without, or inserted after the
        // build) come at full detail, their meshes asked for together too.
        let bare: Vec<_> = objects
            .iter()
            .zip(&found)
            .filter(|(_, e)| e.is_none())
            .map(|(o, _)| o.mesh)
            .collect();
        let _ = self.store.prefetch(&bare);
        let entries: Vec<_> = found.iter().flatten().copied().collect();
        let mut coarse = stored::coarsest_levels(&self.store, &entries)?.into_iter();
        objects
            .iter()
            .zip(&found)
            .map(|(o, e)| match e {
                None => Ok((0, self.mesh(o)?)),
                Some(_) => coarse.next().ok_or_else(|| {
                    Error::Invalid("a coarse level went missing in the batch".into())
                }),
            })
            .collect()
    }

    /// The progressive mesh and mini-redundant DAG of object `id`, stored for objects
    /// above the build's PM threshold (`--pm-threshold`); `None` for the others. Ready
    /// for [`crate::lod::Refiner::new`]: applying every split gives the object's full
    /// mesh back.
    ///
    /// ```
    /// # fn main() -> flaneur::Result<()> {
    /// # let dir = tempfile::tempdir().unwrap();
    /// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
    /// # let city = citygen::CityConfig { objects: 40, landmarks: 0.0, ..Default::default() };
    /// # citygen::write_city(&city, &scene)?;
    /// let lod = flaneur::lod::LodOptions { pm_threshold: 0, ..Default::default() };
    /// let opts = flaneur::BuildOptions { lod: Some(lod), ..Default::default() };
    /// flaneur::build_from_scene(&scene, &path, &opts)?;
    /// let db = flaneur::Database::open(&path)?;
    /// let (pm, dag) = db.progressive(0)?.expect("every object is above 0 triangles");
    /// let full = pm.cursor_at(pm.splits.len())?;
    /// assert_eq!(full.triangle_count(), db.lod_levels(0)?.unwrap()[0].triangles as usize);
    /// flaneur::lod::Refiner::new(&pm, &dag)?;
    /// # Ok(()) }
    /// ```
    pub fn progressive(&self, id: u64) -> Result<Option<(ProgressiveMesh, Dag)>> {
        match self.lod_entry(id)? {
            Some(e) => stored::progressive(&self.store, &e),
            None => Ok(None),
        }
    }

    pub(crate) fn lod_entry(&self, id: u64) -> Result<Option<crate::lod::stored::LodEntry>> {
        match &self.lod {
            Some(t) => t.find(&self.store, id),
            None => Ok(None),
        }
    }

    /// Adds an object to an open database (opened with [`Database::open_writable`]):
    /// its mesh is appended and the R-tree grows by insertion. The object gets no LOD
    /// data (the LOD table is written once, at build).
    ///
    /// Durable and crash-atomic: the mesh and copies of the changed nodes are appended
    /// and synced, then one header write names the new root and counts, so a crash at
    /// any point leaves the database holding either the objects it had or those and
    /// this one. Each insert appends the tree's height in node pages; the pages it
    /// replaced stay in the file, unused.
    pub fn insert(&mut self, id: u64, mesh: &Mesh) -> Result<ObjectEntry> {
        let codec = load_codec(&self.store)?;
        let meshes = self.store.pages_written(PageKind::Mesh);
        let entry = write_object(
            &mut self.store,
            id,
            crate::scene::KIND_IMPORTED,
            mesh,
            codec,
        )?;
        let before = self.store.page_count();
        self.tree.insert(&mut self.store, entry)?;
        self.boxes = std::sync::OnceLock::new();
        self.kinds.mesh += self.store.pages_written(PageKind::Mesh) - meshes;
        self.kinds.rtree += self.store.page_count() - before;
        self.objects += 1;
        self.triangles += entry.triangles as u64;
        self.bounds = self.bounds.union(&entry.bounds);
        save_meta(
            &mut self.store,
            self.objects,
            self.triangles,
            &self.bounds,
            &self.kinds,
        )?;
        self.store.flush()?;
        Ok(entry)
    }

    /// Objects in the database (from the header; reads nothing).
    pub fn objects(&self) -> u64 {
        self.objects
    }

    /// Triangles over all objects' full meshes (from the header; reads nothing).
    pub fn triangles(&self) -> u64 {
        self.triangles
    }

    /// Pages written per kind (from the header; reads nothing).
    pub fn pages_by_kind(&self) -> KindCounts {
        self.kinds
    }

    /// The box around every object.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The R-tree: its root, height and fan-out. Its queries read through the page source
    /// they are given: the store, or a [`BufferPool`](crate::cache::BufferPool) over it.
    pub fn tree(&self) -> &RTree {
        &self.tree
    }

    /// The page store the database reads through: its header, pages and read counters.
    pub fn store(&self) -> &Store {
        &self.store
    }

    /// Physical page reads so far.
    pub fn io(&self) -> IoStats {
        self.store.stats()
    }

    /// Sets the read counters of [`Database::io`] back to zero.
    pub fn reset_io(&self) {
        self.store.reset_stats()
    }

    /// Objects, triangles, pages by kind, tree shape (walks the whole tree).
    pub fn info(&self) -> Result<DatabaseInfo> {
        // The tables' heads that follow, asked for together: a cold info over HTTP then
        // takes the open's round trip and one more.
        let heads: Vec<u64> = self
            .lod
            .iter()
            .map(LodTable::first_page)
            .chain(self.visibility.iter().flat_map(VisibilityTable::head_pages))
            .collect();
        self.store.announce(&heads);
        let tree = self.tree.stats(&self.store)?;
        let (b, page_size) = (self.bounds, self.store.page_size());
        Ok(DatabaseInfo {
            objects: self.objects,
            triangles: self.triangles,
            page_size,
            pages: self.store.page_count(),
            file_bytes: self.store.page_count() * page_size as u64,
            uncommitted_bytes: self.store.uncommitted_bytes(),
            pages_by_kind: self.kinds,
            format_version: self.store.header().version(),
            codec: load_codec(&self.store)?,
            dictionary_bytes: self
                .store
                .header()
                .segment(crate::store::DICTIONARIES_SEGMENT)
                .map_or(0, |s| s.b),
            bytes_per_triangle: BytesPerTriangle::of(
                &self.kinds,
                self.store.page_count(),
                page_size,
                self.triangles,
            ),
            bounds: [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z],
            tree,
            fanout_leaf: self.tree.fanout.leaf,
            fanout_internal: self.tree.fanout.internal,
            named_objects: self.named_objects(),
            lod: self.lod_stats()?,
            visibility: self.visibility_info()?,
            hdov: self.hdov()?.map(|h| HdovInfo {
                nodes: h.nodes,
                height: h.height,
                fanout: h.fanout,
                cells: h.cells.len(),
                visible_nodes: h.visible_nodes,
                lod_pages: h.lod_pages,
                schemes: h
                    .schemes
                    .iter()
                    .map(|s| (s.0, s.1.byte_len as u64))
                    .collect(),
                seconds: h.seconds,
            }),
        })
    }
}
