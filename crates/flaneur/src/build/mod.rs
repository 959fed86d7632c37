//! `flaneur build`: a scene file or OBJ files in, one database file out.
//!
//! Objects stream through: each mesh is written as an extent as soon as it is read,
//! and only its index entry (56 bytes) stays in memory until the R-tree is packed over
//! all of them. The store writes to a temporary file and renames it into place only
//! when the build is complete.
//!
//! With LODs on (the default), each object is also simplified on the thread pool while
//! the build reads on, and its coarse levels (and, for large objects, its progressive
//! mesh and DAG) are appended a batch behind its mesh; the table that finds them by id
//! is written at the end (`lod::stored`). Simplifying is most of the time of
//! such a build.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::catalog::{object_entry, save_codec, save_meta, write_object, KindCounts};
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::hdov::{build_hdov, HdovOptions, HdovReport};
use crate::lod::{LodOptions, LodReport, LodWriter};
use crate::names::store_names;
use crate::progress::{Progress, Silent, Step};
use crate::rtree::ObjectEntry;
use crate::rtree::{RTree, DEFAULT_FILL};
use crate::scene::{
    GltfObjects, Mesh, MeshCodec, ObjAxes, OsmOptions, OsmReport, Placed, SceneObject, SceneReader,
    KIND_IMPORTED,
};
use crate::store::{Extent, PageKind, Segment, Store};
use crate::visibility::{
    encode_table, merge_shards, precompute, ShardCells, VisibilityOptions, VISIBILITY_SEGMENT,
};
use crate::write_order::{hilbert_order, WriteOrder};

mod check;
mod models;
mod shards;

use check::{check_costs, Survey, Work};
use models::{load_models, Models};
pub use models::{model_format, ModelFormat};
pub use shards::{build_visibility_shard, merge_visibility_shards};

/// How to build.
///
/// ```
/// use flaneur::BuildOptions;
/// // Small pages, no LODs: a quick index of the meshes alone.
/// let opts = BuildOptions { page_size: 1024, lod: None, ..BuildOptions::default() };
/// assert!(opts.visibility.is_none()); // the long step runs only when asked for
/// ```
#[derive(Clone, Debug)]
pub struct BuildOptions {
    /// Page size in bytes (power of two, 1 KiB to 64 KiB).
    pub page_size: usize,
    /// Share of a node's fan-out that bulk loading fills.
    pub fill: f32,
    /// Build the index by one-by-one insertion with the linear split (the thesis's
    /// setting) instead of packing it.
    pub insertion: bool,
    /// Store each object's LODs, made this way; `None` stores none (`--no-lod`).
    pub lod: Option<LodOptions>,
    /// Precompute the viewcells' visibility this way; `None` computes none (the
    /// default: it is the long step of a build).
    pub visibility: Option<VisibilityOptions>,
    /// Build the HDoV-tree over the objects, their LODs and the visibility this way
    /// (it needs `visibility`); `None` builds none.
    pub hdov: Option<HdovOptions>,
    /// The order objects' meshes and LODs are written in (`--order`): along a Hilbert
    /// curve over their positions by default, so that a cell's objects lie in few byte
    /// runs; ids, the index and page counts do not depend on it.
    pub order: WriteOrder,
    /// What one object of a glTF input is: each node with a mesh (the default), or each
    /// mesh with all its placements (`--gltf-objects`).
    pub gltf_objects: GltfObjects,
    /// The up axis and the scale to metres of OBJ inputs (`--up`, `--scale`); glTF is
    /// y-up in metres by its specification.
    pub obj_axes: ObjAxes,
    /// How OpenStreetMap footprints become buildings: storey height, default and
    /// maximum heights (`--storey-height`, `--default-height`, `--max-height`).
    pub osm: OsmOptions,
    /// Store no build times in the file (the visibility table's and the HDoV-tree's
    /// seconds are 0), so that the file is a function of its inputs and options: two
    /// builds, or a build and a merge of visibility shards, give the same bytes
    /// (`--reproducible`).
    pub reproducible: bool,
    /// How meshes are stored (`--codec`): by default meshoptimizer's codecs over
    /// quantised vertices with zstd around them (format version 2), or raw floats, a
    /// file of format version 1 as earlier builds wrote it.
    pub codec: MeshCodec,
}

impl BuildOptions {
    /// Checks every option before any work, so that a bad one fails in a moment, not
    /// after the long steps before the one that takes it: the page size, the fill
    /// factor, the LOD, visibility and HDoV-tree settings, and that an HDoV-tree comes
    /// with visibility. The error names the bad one. What the visibility options cost
    /// over a city ([`VisibilityOptions::cost`]) every build checks too, after one pass
    /// over its objects' bounds and before its LODs.
    pub fn validate(&self) -> Result<()> {
        self.obj_axes.validate()?;
        self.osm.validate()?;
        if !crate::store::valid_page_size(self.page_size) {
            return Err(Error::Invalid(format!(
                "page size {} (--page-size) is not a power of two in {}..={}",
                self.page_size,
                crate::store::MIN_PAGE_SIZE,
                crate::store::MAX_PAGE_SIZE
            )));
        }
        if !(0.1..=1.0).contains(&self.fill) {
            return Err(Error::Invalid(format!(
                "fill factor {} (--fill) is outside 0.1..=1",
                self.fill
            )));
        }
        if let Some(lod) = &self.lod {
            lod.validate()?;
        }
        if let Some(v) = &self.visibility {
            v.validate()?;
        }
        if let Some(h) = &self.hdov {
            h.validate()?;
            let payload = self.page_size.saturating_sub(crate::store::PAGE_HEADER_LEN);
            h.node_capacity(crate::hdov::node::capacity(payload), self.page_size)?;
            if self.visibility.is_none() {
                return Err(Error::Invalid(
                    "the HDoV-tree needs the viewcells' visibility: build with --visibility too"
                        .into(),
                ));
            }
        }
        Ok(())
    }
}

impl Default for BuildOptions {
    fn default() -> BuildOptions {
        BuildOptions {
            page_size: 4096,
            fill: DEFAULT_FILL,
            insertion: false,
            lod: Some(LodOptions::default()),
            visibility: None,
            hdov: None,
            order: WriteOrder::default(),
            gltf_objects: GltfObjects::default(),
            obj_axes: ObjAxes::default(),
            osm: OsmOptions::default(),
            reproducible: false,
            codec: MeshCodec::default(),
        }
    }
}

/// What a build wrote.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, db) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # citygen::write_city(&citygen::CityConfig { objects: 20, landmarks: 0.0, ..Default::default() }, &scene)?;
/// let built = flaneur::build_from_scene(&scene, &db, &Default::default())?;
/// assert_eq!(built.objects, 20);
/// assert_eq!(built.bytes, built.pages * 4096);
/// assert!(built.lod.is_some() && built.visibility.is_none());
/// # Ok(()) }
/// ```
#[derive(Clone, Debug, serde::Serialize)]
pub struct BuildSummary {
    /// Objects written.
    pub objects: u64,
    /// Triangles over all objects' full meshes.
    pub triangles: u64,
    /// Pages of the file, header included.
    pub pages: u64,
    /// Bytes of the file: pages × page size.
    pub bytes: u64,
    /// Levels of the R-tree, leaves included.
    pub height: u32,
    /// Wall-clock seconds of the whole build, LODs included.
    pub seconds: f64,
    /// What was stored as LODs; `None` when the build stored none.
    pub lod: Option<LodReport>,
    /// What the visibility precomputation made; `None` when it did not run.
    pub visibility: Option<VisibilityReport>,
    /// What the HDoV-tree took; `None` when none was built.
    pub hdov: Option<HdovReport>,
    /// How OBJ inputs were placed (turned z-up to y-up, scaled); `None` without any.
    pub obj_placed: Option<Placed>,
    /// What the OpenStreetMap import made of its extract; `None` without one.
    pub osm: Option<OsmReport>,
}

/// What `flaneur build --visibility` computed.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VisibilityReport {
    /// Walkable cells, each with a PVS, of the grid's rows × columns.
    pub cells: usize,
    /// Rows of the viewcell grid.
    pub rows: u32,
    /// Columns of the viewcell grid.
    pub columns: u32,
    /// Objects over all PVSs.
    pub entries: u64,
    /// Objects with an occluder box.
    pub occluders: usize,
    /// DoV rays cast.
    pub rays: u64,
    /// Seconds of the whole precomputation.
    pub seconds: f64,
    /// Of those, the seconds spent casting DoV rays.
    pub dov_seconds: f64,
    /// Pages the table takes.
    pub pages: u64,
}

/// Builds a database from a citygen scene file.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// let dir = tempfile::tempdir().unwrap();
/// let (scene, db) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// let city = citygen::CityConfig { objects: 30, landmarks: 0.0, ..Default::default() };
/// citygen::write_city(&city, &scene)?;
/// flaneur::build_from_scene(&scene, &db, &flaneur::BuildOptions::default())?;
/// assert_eq!(flaneur::Database::open(&db)?.objects(), 30);
/// # Ok(()) }
/// ```
pub fn build_from_scene(scene: &Path, db: &Path, opts: &BuildOptions) -> Result<BuildSummary> {
    build_from_scene_with_progress(scene, db, opts, &Silent)
}

/// [`build_from_scene`], telling `progress` how many objects (then viewcells) are done.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// use std::sync::atomic::{AtomicU64, Ordering};
/// use flaneur::progress::{Progress, Step};
///
/// struct Built(AtomicU64);
/// impl Progress for Built {
///     fn update(&self, step: Step, done: u64, _total: Option<u64>) {
///         if step == Step::Objects {
///             self.0.store(done, Ordering::Relaxed);
///         }
///     }
/// }
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, db) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # citygen::write_city(&citygen::CityConfig { objects: 12, landmarks: 0.0, ..Default::default() }, &scene)?;
/// let built = Built(AtomicU64::new(0));
/// flaneur::build_from_scene_with_progress(&scene, &db, &Default::default(), &built)?;
/// assert_eq!(built.0.load(Ordering::Relaxed), 12); // every object, LODs included
/// # Ok(()) }
/// ```
pub fn build_from_scene_with_progress(
    scene: &Path,
    db: &Path,
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<BuildSummary> {
    scene_build(scene, db, opts, progress, None)
}

/// [`build_from_scene_with_progress`], the visibility taken from `shards` when given.
fn scene_build(
    scene: &Path,
    db: &Path,
    opts: &BuildOptions,
    progress: &dyn Progress,
    shards: Option<&[ShardCells]>,
) -> Result<BuildSummary> {
    opts.validate()?;
    let mut reader = SceneReader::open(scene)?;
    let total = reader.object_count();
    let unpack = |o: SceneObject| (o.id, o.kind.as_u8(), o.mesh);
    let work = Work::of_build(shards.is_some());
    let mut survey = Survey::new(opts);
    match opts.order {
        WriteOrder::Input => {
            if survey.wanted() {
                // The bounds pass the checks need, before the objects stream into the
                // build (the Hilbert order's pass does it on its way).
                for (n, object) in SceneReader::open(scene)?.enumerate() {
                    survey.add(&object?.mesh);
                    progress.update(Step::Ordering, n as u64 + 1, Some(total));
                }
                progress.finish(Step::Ordering);
            }
            check_costs(opts, &survey, work)?;
            let objects = reader.map(|r| r.map(unpack).map_err(Error::from));
            build(objects, Some(total), None, db, opts, progress, shards)
        }
        WriteOrder::Hilbert => {
            // One pass to learn where each object stands (and to check the whole file),
            // then each record read again where it lies, in the curve's order.
            let mut places = Vec::with_capacity(total.min(10_000_000) as usize);
            let mut centres = Vec::with_capacity(places.capacity());
            loop {
                let at = reader.position();
                let Some(object) = reader.next().transpose()? else {
                    break;
                };
                places.push(at);
                centres.push(ground_centre(&object.mesh));
                survey.add(&object.mesh);
                progress.update(Step::Ordering, places.len() as u64, Some(total));
            }
            progress.finish(Step::Ordering);
            check_costs(opts, &survey, work)?;
            let objects = hilbert_order(&centres)
                .into_iter()
                .map(move |i| reader.read_at(places[i]).map(unpack).map_err(Error::from));
            build(objects, Some(total), None, db, opts, progress, shards)
        }
    }
}

/// The centre of a mesh's box seen from above (x, z); the origin for a mesh with no
/// vertices, which the build refuses anyway.
fn ground_centre(mesh: &Mesh) -> [f32; 2] {
    if mesh.positions.is_empty() {
        return [0.0; 2];
    }
    let (min, max) = mesh.bounds();
    [(min[0] + max[0]) / 2.0, (min[2] + max[2]) / 2.0]
}

/// Builds a database from OBJ and glTF files (`.obj`, `.gltf`, `.glb`): every object or
/// group of an OBJ file becomes an object, as does every node with a mesh of a glTF
/// file (or every mesh, by [`BuildOptions::gltf_objects`]), with ids in file order.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// let dir = tempfile::tempdir().unwrap();
/// let obj = dir.path().join("two.obj");
/// // Two tetrahedra, 10 m apart.
/// let tetra = |x: f32| format!("v {x} 0 0\nv {} 0 0\nv {x} 1 0\nv {x} 0 1\n", x + 1.0);
/// let faces = |b: u32| format!("f {} {} {}\nf {} {} {}\nf {} {} {}\nf {} {} {}\n",
///     b, b + 2, b + 1, b, b + 1, b + 3, b, b + 3, b + 2, b + 1, b + 2, b + 3);
/// let text = format!("o a\n{}{}o b\n{}{}", tetra(0.0), faces(1), tetra(10.0), faces(5));
/// std::fs::write(&obj, text).unwrap();
/// let db = dir.path().join("two.flaneur");
/// let built = flaneur::build_from_obj(&[obj], &db, &flaneur::BuildOptions::default())?;
/// assert_eq!((built.objects, built.triangles), (2, 8));
/// # Ok(()) }
/// ```
pub fn build_from_obj(files: &[PathBuf], db: &Path, opts: &BuildOptions) -> Result<BuildSummary> {
    build_from_obj_with_progress(files, db, opts, &Silent)
}

/// [`build_from_obj`], telling `progress` how many objects (then viewcells) are done.
///
/// ```no_run
/// # fn main() -> flaneur::Result<()> {
/// // A program that does not draw bars passes `Silent` (what `build_from_obj` does).
/// let files = ["block.obj".into(), "tower.obj".into()];
/// let opts = flaneur::BuildOptions::default();
/// flaneur::build_from_obj_with_progress(&files, "city.flaneur".as_ref(), &opts, &flaneur::progress::Silent)?;
/// # Ok(()) }
/// ```
pub fn build_from_obj_with_progress(
    files: &[PathBuf],
    db: &Path,
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<BuildSummary> {
    models_build(files, db, opts, progress, None)
}

/// [`build_from_obj_with_progress`], the visibility taken from `shards` when given.
fn models_build(
    files: &[PathBuf],
    db: &Path,
    opts: &BuildOptions,
    progress: &dyn Progress,
    shards: Option<&[ShardCells]>,
) -> Result<BuildSummary> {
    opts.validate()?;
    let Models {
        meshes,
        names,
        obj_placed,
        osm,
    } = load_models(files, opts)?;
    let mut survey = Survey::new(opts);
    meshes.iter().for_each(|m| survey.add(m));
    let work = Work::of_build(shards.is_some());
    check_costs(opts, &survey, work)?;
    let total = meshes.len() as u64;
    let order: Vec<usize> = match opts.order {
        WriteOrder::Input => (0..meshes.len()).collect(),
        WriteOrder::Hilbert => hilbert_order(&meshes.iter().map(ground_centre).collect::<Vec<_>>()),
    };
    let mut meshes: Vec<Option<Mesh>> = meshes.into_iter().map(Some).collect();
    let objects = order.into_iter().map(move |i| {
        let mesh = meshes[i].take().expect("each index once");
        Ok((i as u64, KIND_IMPORTED, mesh))
    });
    // Names are kept when the inputs give any.
    let names = names.iter().any(|n| !n.is_empty()).then_some(names);
    let mut summary = build(
        objects,
        Some(total),
        names.as_deref(),
        db,
        opts,
        progress,
        shards,
    )?;
    summary.obj_placed = obj_placed;
    summary.osm = osm;
    Ok(summary)
}

/// Gives the entries after the first `filled` the mesh extents the LOD writer wrote,
/// which come in the order the objects did.
fn fill_meshes(entries: &mut [ObjectEntry], filled: &mut usize, meshes: Vec<Extent>) {
    for (entry, mesh) in entries[*filled..].iter_mut().zip(&meshes) {
        entry.mesh = *mesh;
    }
    *filled += meshes.len();
}

/// The objects as [`write_objects`] wrote them: their index entries, in the order they
/// came, and what the rest of the build needs of them.
struct Written {
    entries: Vec<ObjectEntry>,
    /// Every mesh, when the visibility is precomputed (its rays are cast at them all).
    kept: Vec<(u64, Mesh)>,
    triangles: u64,
    bounds: Aabb,
    lod: Option<LodReport>,
    kinds: KindCounts,
}

/// Writes every object's mesh, and its levels of detail when the build makes them; an
/// error for an input with no object.
fn write_objects(
    store: &mut Store,
    objects: impl Iterator<Item = Result<(u64, u8, Mesh)>>,
    total: Option<u64>,
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<Written> {
    let codec = opts.codec;
    let mut lods = opts
        .lod
        .as_ref()
        .map(|l| LodWriter::new(l, codec, store))
        .transpose()?;
    // In format version 2 meshes are encoded on the thread pool with their levels, and
    // the LOD writer writes them, a batch side by side.
    let meshes_with_lods = lods.is_some() && codec != MeshCodec::Raw;
    let mut meshes_filled = 0;
    // Objects count as built once their LODs are stored too, which may be a batch later.
    let mut built = 0u64;
    let mut advance = |n: u64| {
        built += n;
        progress.update(Step::Objects, built, total);
    };
    let mut entries = Vec::with_capacity(total.unwrap_or(0).min(10_000_000) as usize);
    let mut kinds = KindCounts::default();
    let mut triangles = 0u64;
    let mut bounds = Aabb::EMPTY;
    // The precomputation casts rays at every mesh, so it keeps them all.
    let mut kept: Vec<(u64, Mesh)> = Vec::new();
    for object in objects {
        let (id, kind, mesh) = object?;
        let entry = if meshes_with_lods {
            object_entry(id, kind, &mesh)?
        } else {
            write_object(store, id, kind, &mesh, codec)?
        };
        if opts.visibility.is_some() {
            kept.push((id, mesh.clone()));
        }
        triangles += entry.triangles as u64;
        bounds = bounds.union(&entry.bounds);
        entries.push(entry);
        // An object counts as built once its LODs are stored too.
        match lods.as_mut() {
            Some(l) => {
                advance(l.push(store, id, entry.mesh, mesh)? as u64);
                fill_meshes(&mut entries, &mut meshes_filled, l.take_meshes());
            }
            None => advance(1),
        }
    }
    let lod = match lods {
        Some(l) => {
            let (report, last, meshes) = l.finish(store)?;
            fill_meshes(&mut entries, &mut meshes_filled, meshes);
            advance(last as u64);
            kinds.lod = report.stats.pages;
            Some(report)
        }
        None => None,
    };
    if meshes_with_lods && meshes_filled != entries.len() {
        return Err(Error::Invalid(format!(
            "the LOD writer wrote {meshes_filled} meshes of {} objects",
            entries.len()
        )));
    }
    kinds.mesh = store.pages_written(PageKind::Mesh);
    // The zstd dictionaries the LOD writer trained, if any.
    kinds.meta += store.pages_written(PageKind::Meta);
    progress.finish(Step::Objects);
    if entries.is_empty() {
        return Err(Error::Invalid("the input holds no objects".into()));
    }
    Ok(Written {
        entries,
        kept,
        triangles,
        bounds,
        lod,
        kinds,
    })
}

fn build(
    objects: impl Iterator<Item = Result<(u64, u8, Mesh)>>,
    total: Option<u64>,
    names: Option<&[String]>,
    db: &Path,
    opts: &BuildOptions,
    progress: &dyn Progress,
    shards: Option<&[ShardCells]>,
) -> Result<BuildSummary> {
    let start = Instant::now();
    opts.validate()?;
    let mut store = Store::create(db, opts.page_size)?;
    save_codec(&mut store, opts.codec)?;
    let Written {
        mut entries,
        mut kept,
        triangles,
        bounds,
        lod,
        mut kinds,
    } = write_objects(&mut store, objects, total, opts, progress)?;
    let visibility = match &opts.visibility {
        Some(v) => {
            kept.sort_unstable_by_key(|(id, _)| *id);
            // The DoV draws far objects through the coarse levels just stored; shards
            // make the same levels themselves (`shards::made_levels`).
            let levels = match (&lod, shards) {
                (Some(_), None) => stored_levels(&store, &kept)?,
                _ => Vec::new(),
            };
            let report = store_visibility(
                &mut store,
                (&kept, &levels),
                (v, shards),
                opts.reproducible,
                progress,
            )?;
            kinds.visibility = report.pages;
            Some(report)
        }
        None => None,
    };
    drop(kept);
    if let Some(names) = names {
        kinds.meta += store_names(&mut store, names)?;
    }
    // What follows sees the objects in id order, whatever order they were written in,
    // so that the index (and the HDoV-tree) are the same for every write order.
    entries.sort_unstable_by_key(|e| e.id);
    let objects = entries.len() as u64;
    let hdov = match &opts.hdov {
        Some(h) => Some(build_hdov(
            &mut store,
            entries.clone(),
            h,
            !opts.reproducible,
            progress,
        )?),
        None => None,
    };
    // The R-tree goes last, its root on the last page: a reader over HTTP fetches the
    // file's tail with its header, and with it the tree's upper levels.
    let before = store.page_count();
    let tree = if opts.insertion {
        let mut tree = RTree::bulk_load(&mut store, Vec::new(), opts.fill)?;
        for e in entries {
            tree.insert(&mut store, e)?;
        }
        tree
    } else {
        RTree::bulk_load(&mut store, entries, opts.fill)?
    };
    kinds.rtree = store.page_count() - before;
    tree.save(&mut store)?;
    save_meta(&mut store, objects, triangles, &bounds, &kinds)?;
    let pages = store.page_count();
    let page_size = store.page_size() as u64;
    store.finish()?;
    Ok(BuildSummary {
        objects,
        triangles,
        pages,
        bytes: pages * page_size,
        height: tree.height,
        seconds: start.elapsed().as_secs_f64(),
        lod,
        visibility,
        hdov,
        obj_placed: None,
        osm: None,
    })
}

/// Precomputes the visibility of `objects` (or merges it from `shards`) and appends its
/// table, telling `progress` the cells done; a reproducible build stores no seconds.
fn store_visibility(
    store: &mut Store,
    (objects, levels): (&[(u64, Mesh)], &[Vec<(Mesh, f32)>]),
    (opts, shards): (&VisibilityOptions, Option<&[ShardCells]>),
    reproducible: bool,
    progress: &dyn Progress,
) -> Result<VisibilityReport> {
    let made = match shards {
        Some(shards) => merge_shards(objects, shards)?,
        None => precompute(objects, levels, opts, &|done, total| {
            progress.update(Step::Visibility, done as u64, Some(total as u64));
        })?,
    };
    progress.finish(Step::Visibility);
    let mut stats = made.stats;
    if reproducible {
        (stats.seconds, stats.dov_seconds) = (0.0, 0.0);
    }
    let bytes = encode_table(&made.grid, &made.settings, &stats, &made.cells)?;
    let extent = store.append_extent(PageKind::Visibility, &bytes)?;
    store.set_segment(Segment::new(
        VISIBILITY_SEGMENT,
        extent.first_page,
        extent.byte_len as u64,
        extent.page_count as u64,
    ))?;
    Ok(VisibilityReport {
        cells: made.cells.len(),
        rows: made.grid.rows(),
        columns: made.grid.columns(),
        entries: made.stats.entries,
        occluders: made.occluders,
        rays: made.stats.rays,
        seconds: made.stats.seconds,
        dov_seconds: made.stats.dov_seconds,
        pages: extent.page_count as u64,
    })
}

/// Each of `objects`' coarse levels with its error in metres, finest first, read back
/// from the LODs `store` holds (none for an object it has none of).
fn stored_levels(store: &Store, objects: &[(u64, Mesh)]) -> Result<Vec<Vec<(Mesh, f32)>>> {
    use crate::lod::stored::{coarse_levels, LodTable};
    let Some(table) = LodTable::open(store)? else {
        return Ok(Vec::new());
    };
    objects
        .iter()
        .map(|(id, _)| match table.find(store, *id)? {
            Some(e) => coarse_levels(store, &e),
            None => Ok(Vec::new()),
        })
        .collect()
}
