//! LOD selection, the walk's last stage before drawing: each object in view drawn at the
//! coarsest of its stored levels whose simplification error, seen from the eye, stays
//! under a screen-space threshold.
//!
//! The criterion is the one the LOD core's refinement uses (Zheng 2007 §3.4): a level of
//! error ε (metres) is fine enough at distance d when ε < 2τ·tan(α)·d, with α half the
//! vertical field of view and τ a fraction of the viewport (the thesis's 0.1 %). d is
//! the distance from the eye to the object's box, so an object the eye is inside, or
//! touching, is drawn at full detail.
//!
//! The mesh the walk loaded into its object buffer is the object's level 0, or the
//! coarser level the walk chose for it ([`Loaded::level`], VISUAL's), which selection
//! never draws finer unless the walk allows it ([`Loaded::finest`]), nor, for VISUAL's
//! screen rule ([`Loaded::finer_of`]), coarser: it is then drawn at the finer of the
//! level the walk chose (eq. 5.6's) and the screen-space one (under τ stretched by
//! [`Loaded::tau_scale`] for a faint object), the finer level read like
//! a coarse one; the coarser ones are read from the database's LOD chains when
//! first chosen (only the pages of that level), and kept while the object stays in the
//! buffer. A group of objects drawn as one (an HDoV node) is drawn as loaded. A database without LODs, or an object
//! without them, is drawn at full detail. The pages read are counted apart from the
//! walk's own figures: the walk reports what its retrieval method reads. The walk
//! session runs it once a frame's figures are finished, under the τ its viewer wants
//! ([`FrameSink::lod_tau`](super::FrameSink::lod_tau)), and hands the viewer what to
//! draw; a renderer reads no LOD page.
//!
//! Large objects, those the build stored a progressive mesh and DAG for, are refined
//! view by view instead ([`REFINED`]): the LOD core's constant-time traversal under the
//! same τ, the thesis's N = 500 and a 60,000-triangle budget each, its selective mesh
//! kept in compact arrays whose changed ranges a renderer uploads
//! ([`LodSelector::refined`]). Their progressive mesh and DAG are read when the object
//! is first drawn, but decoded on the thread pool: decoding a landmark's takes tens of
//! milliseconds, which would stall the frame. Until it is done the object is drawn at
//! its discrete levels like any other.

mod adapt_ahead;

use std::collections::HashMap;
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::Arc;

use crate::database::Database;
use crate::error::{Error, Result};
use crate::geom::{Aabb, Camera};
use crate::lod::stored;
use crate::lod::stored::LodEntry;
use crate::lod::{
    distance_to, level_for, LevelInfo, MeshChanges, RefineParams, Refiner, Traversal, View,
    THESIS_BUDGET,
};
use crate::scene::Mesh;
use crate::store::PageKind;

use super::buffer::{Loaded, ObjectBuffer};
use adapt_ahead::AdaptAhead;

/// The thesis's screen-space error: 0.1 % of the viewport.
pub const DEFAULT_TAU: f32 = 0.001;
/// The level of an object refined view by view: its mesh is the refiner's.
pub const REFINED: usize = usize::MAX;
/// The most a DoV stretches an object's τ ([`dov_tau`]).
pub const DOV_TAU_STRETCH: f32 = 8.0;

/// The screen-space error an object refined view by view is refined under when its
/// DoV from the viewer's cell is `dov` (ours, not the thesis's): τ as it is for an
/// object of DoV at least MAXDOV (half the view's sphere), stretched by MAXDOV/DoV up
/// to [`DOV_TAU_STRETCH`] times for one barely visible, so that a landmark seen through
/// a gap refines less. Without a DoV, τ.
///
/// ```
/// use flaneur::walk::lod_select::{dov_tau, DOV_TAU_STRETCH};
/// assert_eq!(dov_tau(0.001, None), 0.001);
/// assert_eq!(dov_tau(0.001, Some(0.5)), 0.001);
/// assert!((dov_tau(0.001, Some(0.25)) - 0.002).abs() < 1e-9);
/// assert_eq!(dov_tau(0.001, Some(1e-6)), 0.001 * DOV_TAU_STRETCH);
/// ```
pub fn dov_tau(tau: f32, dov: Option<f32>) -> f32 {
    match dov {
        Some(d) if d > 0.0 => tau * (crate::hdov::MAXDOV / d).clamp(1.0, DOV_TAU_STRETCH),
        Some(_) => tau * DOV_TAU_STRETCH,
        None => tau,
    }
}

/// One object as a frame draws it: at which level, and that level's mesh.
#[derive(Clone, Debug)]
pub struct Drawn {
    /// The object's id.
    pub id: u64,
    /// Its box.
    pub bounds: Aabb,
    /// 0: full detail; each higher level is coarser; [`REFINED`]: refined view by
    /// view (the mesh is then the full one the buffer holds, the triangles the
    /// selective mesh's).
    pub level: usize,
    /// The mesh of that level.
    pub mesh: Arc<Mesh>,
    /// Triangles drawn.
    pub triangles: usize,
}

impl Drawn {
    /// Whether it is drawn at one of its coarser stored levels (not at full detail,
    /// nor refined view by view).
    pub fn is_coarse(&self) -> bool {
        self.level > 0 && self.level != REFINED
    }

    /// An object drawn as the walk loaded it: at full detail, or at the level the walk
    /// chose ([`Loaded::level`]).
    pub fn full(o: &Loaded) -> Drawn {
        Drawn {
            id: o.entry.id,
            bounds: o.entry.bounds,
            level: o.level,
            mesh: o.mesh.clone(),
            triangles: o.mesh.triangle_count(),
        }
    }
}

/// What LOD selection read and chose over a walk.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct LodCounts {
    /// Objects drawn at a coarser level than full detail, summed over frames.
    pub coarse_draws: u64,
    /// Levels read from the database.
    pub levels_read: u64,
    /// Pages those reads (and the level directories) took.
    pub pages: u64,
    /// Objects drawn refined view by view, summed over frames.
    pub refined_draws: u64,
    /// The vertex splits and edge collapses their refinement applied.
    pub refine_ops: u64,
    /// Objects whose progressive mesh and DAG were decoded off the frame's thread.
    pub decoded: u64,
    /// Draws at discrete levels of objects whose progressive mesh and DAG were still
    /// being decoded.
    pub drawn_while_decoding: u64,
    /// Objects drawn as refined elsewhere (a stream server's landmarks,
    /// [`RemoteRefinements`](crate::walk::RemoteRefinements)), summed over frames.
    pub streamed_draws: u64,
}

/// The stored levels of the objects a walk has drawn.
struct ObjectLevels {
    /// Where its LOD data lies, looked up once; `None` for an object without any.
    entry: Option<LodEntry>,
    levels: Vec<LevelInfo>,
    /// Level k's mesh once read; level 0 is never read (the buffer holds it).
    meshes: Vec<Option<Arc<Mesh>>>,
}

impl ObjectLevels {
    /// An object drawn at full detail only.
    fn full_only() -> ObjectLevels {
        ObjectLevels {
            entry: None,
            levels: Vec::new(),
            meshes: Vec::new(),
        }
    }

    /// Level `level`'s mesh: kept, or read from `db` (counted in `reads`; the full
    /// mesh's pages, which are not LOD pages, in `pages`).
    fn mesh(
        &mut self,
        db: &Database,
        level: usize,
        reads: &mut u64,
        pages: &mut u64,
    ) -> Result<Arc<Mesh>> {
        if let Some(m) = &self.meshes[level] {
            return Ok(m.clone());
        }
        let entry = self.entry.as_ref().expect("an object with levels has data");
        let m = Arc::new(stored::level_mesh(db.store(), entry, level)?);
        *reads += 1;
        if level == 0 {
            *pages += entry.mesh.page_count as u64;
        }
        self.meshes[level] = Some(m.clone());
        Ok(m)
    }
}

/// A large object refined view by view, and the changes not yet uploaded.
pub struct RefinedObject {
    /// The object's refiner: its selective mesh ([`Refiner::mesh`]), refined frame by
    /// frame.
    pub refiner: Refiner<'static>,
    /// The ranges of the selective mesh's arrays changed since a renderer last took
    /// them, to upload.
    pub pending: MeshChanges,
    /// The arrays' largest sizes: every vertex and triangle of the full mesh.
    pub capacity: (usize, usize),
}

impl RefinedObject {
    /// As a renderer uploads it, its changes taken.
    pub fn view(&mut self) -> RefinedView<'_> {
        RefinedView {
            pending: std::mem::take(&mut self.pending),
            mesh: self.refiner.mesh(),
            capacity: self.capacity,
        }
    }
}

/// A large object's refiner as its decoding on the thread pool left it.
type Decoded = (u64, Result<RefinedObject>);

/// Whether `tau` can be LOD selection's threshold: a fraction of the viewport above 0
/// and below 1. For a viewer that says which τ it wants before the walk selects under it.
pub fn check_tau(tau: f32) -> Result<()> {
    if !(tau > 0.0 && tau < 1.0) {
        return Err(Error::Invalid(format!(
            "LOD threshold τ = {tau}: give a fraction of the viewport above 0 and below 1 (the thesis's is {DEFAULT_TAU})"
        )));
    }
    Ok(())
}

/// An object drawn [`REFINED`] as a renderer uploads it: its selective mesh, the ranges
/// changed since the renderer last asked (now taken), and the most vertices and
/// triangles the mesh may reach (every one of the full mesh), to size its buffers once.
#[derive(Debug)]
pub struct RefinedView<'r> {
    /// The selective mesh.
    pub mesh: &'r crate::lod::CompactMesh,
    /// The ranges of its arrays changed since the renderer last asked.
    pub pending: MeshChanges,
    /// Every vertex and triangle of the full mesh: the arrays' largest sizes.
    pub capacity: (usize, usize),
}

/// Where a renderer finds the refinement of an object drawn [`REFINED`]: its selective
/// mesh, and the changes not yet uploaded.
pub trait Refinements {
    /// Object `id`'s refinement, when it is drawn refined view by view; its changes are
    /// taken, so that the next call has only those made after.
    fn refined(&mut self, id: u64) -> Option<RefinedView<'_>>;

    /// The renderer has taken this frame's changes and reads the selective meshes no
    /// more until the next frame: what adapts ahead may start
    /// ([`LodSelector::launch_ahead`]).
    fn uploaded(&mut self) -> Result<()> {
        Ok(())
    }
}

impl Refinements for LodSelector<'_> {
    fn refined(&mut self, id: u64) -> Option<RefinedView<'_>> {
        LodSelector::refined(self, id).map(RefinedObject::view)
    }

    fn uploaded(&mut self) -> Result<()> {
        self.launch_ahead()
    }
}

/// Chooses each drawn object's level, and keeps the coarse levels read so far.
pub struct LodSelector<'a> {
    db: &'a Database,
    tau: f32,
    objects: HashMap<u64, ObjectLevels>,
    refined: HashMap<u64, RefinedObject>,
    /// Objects whose progressive mesh and DAG are being decoded, and where the thread
    /// pool sends them.
    decoding: std::collections::HashSet<u64>,
    decoded: (Sender<Decoded>, Receiver<Decoded>),
    /// Whether an object whose LOD data cannot be read is drawn at full detail rather
    /// than the frame failing, and what was found so since [`LodSelector::take_damaged`].
    tolerant: bool,
    damaged: Vec<String>,
    /// Whether a large object is refined from the frame it is first drawn, the frame
    /// waiting for its decoding.
    settling: bool,
    /// The refined objects' traversals run ahead on the thread pool, when it adapts
    /// ahead ([`LodSelector::adapting_ahead`]), and the camera of the last selection.
    ahead: Option<AdaptAhead>,
    camera: Option<Camera>,
    /// What it read and chose so far.
    pub counts: LodCounts,
}

impl<'a> LodSelector<'a> {
    /// A selector for `db` under `tau` (a fraction of the viewport, above 0 and below 1).
    pub fn new(db: &'a Database, tau: f32) -> Result<LodSelector<'a>> {
        check_tau(tau)?;
        Ok(LodSelector {
            db,
            tau,
            objects: HashMap::new(),
            refined: HashMap::new(),
            decoding: Default::default(),
            decoded: channel(),
            tolerant: false,
            damaged: Vec::new(),
            settling: false,
            ahead: None,
            camera: None,
            counts: LodCounts::default(),
        })
    }

    /// The same selector drawing an object at full detail from the frame its LOD data
    /// turns out unreadable (a damaged page), instead of failing the frame; what it
    /// found is told by [`LodSelector::take_damaged`]. For a viewer that would rather
    /// walk on.
    pub fn tolerating_damage(self) -> LodSelector<'a> {
        LodSelector {
            tolerant: true,
            ..self
        }
    }

    /// The same selector refining a large object from the frame it is first drawn: the
    /// frame waits for its progressive mesh and DAG to decode instead of drawing it at
    /// its discrete levels meanwhile. A walk's pictures then depend on its path alone,
    /// not on how fast the thread pool decodes; for a viewer that compares pictures
    /// rather than one that must not wait.
    pub fn settling(self) -> LodSelector<'a> {
        LodSelector {
            settling: true,
            ..self
        }
    }

    /// The same selector adapting ahead (El-Sana–Varshney's Adapt and Display): once a
    /// frame's refined meshes are uploaded ([`LodSelector::launch_ahead`]), each object
    /// it drew refined view by view is refined on the thread pool for the view
    /// predicted for the next frame, while the frame draws and the walk retrieves and
    /// culls the next; the next selection takes the result instead of running the
    /// traversal on the frame's thread. The next view is
    /// predicted from the last two frames' cameras, to first order (Zheng 2007 §6.3,
    /// one frame ahead); an object is drawn as refined for it.
    pub fn adapting_ahead(self) -> LodSelector<'a> {
        LodSelector {
            ahead: Some(AdaptAhead::new()),
            ..self
        }
    }

    /// The last selection's refined meshes are uploaded (or its frame done): when
    /// adapting ahead, the traversals of the objects it drew refined start on the
    /// thread pool for the next frame's predicted view, once a frame. Nothing
    /// otherwise. Until the next selection those objects are not
    /// [`refined`](LodSelector::refined).
    pub fn launch_ahead(&mut self) -> Result<()> {
        match (&mut self.ahead, &self.camera) {
            (Some(a), Some(camera)) => a.launch(&mut self.refined, camera),
            _ => Ok(()),
        }
    }

    /// The objects whose LOD data was found unreadable since the last call, each with
    /// why (only when [tolerating damage](LodSelector::tolerating_damage)).
    pub fn take_damaged(&mut self) -> Vec<String> {
        std::mem::take(&mut self.damaged)
    }

    /// `e` about object `id`: the frame's error, or (tolerating damage) told of as
    /// object `id` being drawn `how` from now on.
    fn damage(&mut self, id: u64, e: Error, how: &str) -> Result<()> {
        if !self.tolerant {
            return Err(e);
        }
        self.damaged.push(format!("object {id} drawn {how}: {e}"));
        Ok(())
    }

    /// The screen-space error it selects under, a fraction of the viewport.
    pub fn tau(&self) -> f32 {
        self.tau
    }

    /// `drawn` (the objects of `buffer` in view of `camera`), each at its level. Forgets
    /// the levels of objects `buffer` no longer holds.
    pub fn select(
        &mut self,
        camera: &Camera,
        buffer: &ObjectBuffer,
        drawn: &[&Loaded],
    ) -> Result<Vec<Drawn>> {
        // The objects adapting ahead come back first, to be kept or forgotten with the
        // rest.
        if let Some(a) = &mut self.ahead {
            a.collect(&mut self.refined, &mut self.counts.refine_ops)?;
        }
        self.camera = Some(*camera);
        self.objects.retain(|id, _| buffer.contains(*id));
        self.refined.retain(|id, _| buffer.contains(*id));
        // An object evicted while decoding is forgotten; its result, when it comes, is
        // dropped.
        self.decoding.retain(|id| buffer.contains(*id));
        if !self.db.has_lods() {
            return Ok(drawn.iter().map(|o| Drawn::full(o)).collect());
        }
        self.take_decoded()?;
        // The walk's prefetching may read index and mesh pages meanwhile; LOD pages
        // are this selection's alone.
        let before = self.db.io().reads_of(PageKind::Lod);
        let mut out = Vec::with_capacity(drawn.len());
        for o in drawn {
            let id = o.entry.id;
            // A group drawn as one (an HDoV node's internal LOD) has no levels of its own
            // beyond the one the walk chose.
            if o.is_group() {
                out.push(Drawn::full(o));
                continue;
            }
            if !self.objects.contains_key(&id) && !self.refined.contains_key(&id) {
                if let Err(e) = self.first_sight(o) {
                    self.damage(id, e, "at full detail")?;
                    self.decoding.remove(&id);
                    self.objects.insert(id, ObjectLevels::full_only());
                }
                if self.settling {
                    self.settle()?;
                }
            }
            if let Some(d) = self.refine(camera, o)? {
                out.push(d);
                continue;
            }
            let levels = self.objects.get_mut(&id).expect("seen above");
            if self.decoding.contains(&id) {
                self.counts.drawn_while_decoding += 1;
            }
            let d = distance_to(&o.entry.bounds, camera.position);
            // Never finer than the walk allows (the level it loaded, unless it says); for
            // VISUAL's screen rule, the finer of the level it loaded and τ's.
            let level = match levels.levels.is_empty() {
                // No levels to choose from (none stored, or unreadable): as loaded.
                true => o.level,
                false => {
                    let tau = self.tau * o.tau_scale;
                    let by_tau = level_for(&levels.levels, d, camera.fov_y, tau);
                    match o.finer_of {
                        true => by_tau.min(o.level),
                        false => by_tau.max(o.finest),
                    }
                }
            };
            let mesh = if level == o.level {
                o.mesh.clone()
            } else {
                let (reads, pages) = (&mut self.counts.levels_read, &mut self.counts.pages);
                match levels.mesh(self.db, level, reads, pages) {
                    Ok(m) => m,
                    Err(e) => {
                        *levels = ObjectLevels::full_only();
                        self.damage(id, e, "at full detail")?;
                        out.push(Drawn::full(o));
                        continue;
                    }
                }
            };
            if level > 0 {
                self.counts.coarse_draws += 1;
            }
            out.push(Drawn {
                id,
                bounds: o.entry.bounds,
                level,
                triangles: mesh.triangle_count(),
                mesh,
            });
        }
        self.counts.pages += self.db.io().reads_of(PageKind::Lod) - before;
        Ok(out)
    }
}

impl LodSelector<'_> {
    /// An object drawn for the first time: its LOD entry looked up once, then its
    /// levels read, and its progressive mesh and DAG when the build stored them (handed
    /// to the thread pool to decode; it is refined once they are).
    fn first_sight(&mut self, o: &Loaded) -> Result<()> {
        let id = o.entry.id;
        let entry = self.db.lod_entry(id)?;
        let store = self.db.store();
        if let Some(bytes) = entry
            .as_ref()
            .map(|e| stored::read_progressive(store, e))
            .transpose()?
            .flatten()
        {
            self.decoding.insert(id);
            let to = self.decoded.0.clone();
            rayon::spawn(move || {
                let id = bytes.id();
                // The selector may be gone by now: nobody wants the result then.
                let _ = to.send((id, refined_object(bytes)));
            });
        }
        let levels = match &entry {
            Some(e) => stored::levels(store, e)?,
            None => Vec::new(),
        };
        self.objects.insert(
            id,
            ObjectLevels {
                entry,
                meshes: vec![None; levels.len()],
                levels,
            },
        );
        Ok(())
    }

    /// Makes refined the objects whose decoding has finished (and are still wanted); a
    /// progressive mesh or DAG that failed to decode is the frame's error.
    fn take_decoded(&mut self) -> Result<()> {
        // The selector holds a sender, so the channel is never disconnected.
        while let Ok((id, result)) = self.decoded.1.try_recv() {
            self.adopt(id, result)?;
        }
        Ok(())
    }

    /// Waits until every object being decoded is refined (for a walk that must be the
    /// same from run to run, whatever the threads' timing).
    pub fn settle(&mut self) -> Result<()> {
        while !self.decoding.is_empty() {
            let (id, result) = self
                .decoded
                .1
                .recv()
                .map_err(|_| Error::Invalid("the LOD decoding threads stopped".into()))?;
            self.adopt(id, result)?;
        }
        Ok(())
    }

    /// Object `id` refined from now on, if it is still wanted (and, tolerating damage,
    /// at its discrete levels still when its data did not decode).
    fn adopt(&mut self, id: u64, result: Result<RefinedObject>) -> Result<()> {
        if self.decoding.remove(&id) {
            match result {
                Ok(r) => {
                    self.refined.insert(id, r);
                    self.objects.remove(&id);
                    self.counts.decoded += 1;
                }
                Err(e) => self.damage(id, e, "at its discrete levels, not refined")?,
            }
        }
        Ok(())
    }

    /// `o` refined for `camera`, when it is refined view by view; `None` for an object
    /// drawn at discrete levels.
    fn refine(&mut self, camera: &Camera, o: &Loaded) -> Result<Option<Drawn>> {
        let id = o.entry.id;
        let Some(r) = self.refined.get_mut(&id) else {
            return Ok(None);
        };
        let view = View::new(
            camera.position,
            camera.forward(),
            camera.fov_x.max(camera.fov_y),
        )?;
        let params = RefineParams {
            tau: dov_tau(self.tau * o.tau_scale, o.dov),
            budget: Some(THESIS_BUDGET),
            ..RefineParams::thesis(Traversal::ConstantTime)
        };
        // Adapted ahead for this frame already, or refined here.
        if !self.ahead.as_mut().is_some_and(|a| a.take_ready(id)) {
            let frame = r.refiner.refine(&view, &params)?;
            self.counts.refine_ops += frame.stats.updates() as u64;
            let c = frame.changes;
            r.pending.vertices.extend(c.vertices);
            r.pending.indices.extend(c.indices);
            r.pending.vertex_len = c.vertex_len;
            r.pending.index_len = c.index_len;
        }
        if let Some(a) = &mut self.ahead {
            a.drawn(id, params);
        }
        self.counts.refined_draws += 1;
        Ok(Some(Drawn {
            id,
            bounds: o.entry.bounds,
            level: REFINED,
            mesh: o.mesh.clone(),
            triangles: r.refiner.mesh().triangle_count(),
        }))
    }

    /// Object `id`'s selective mesh, when it is refined view by view.
    pub fn refined_mesh(&self, id: u64) -> Option<&crate::lod::CompactMesh> {
        self.refined.get(&id).map(|r| r.refiner.mesh())
    }

    /// Object `id`'s refinement, when it is drawn refined: its selective mesh and the
    /// changes since the last call took them.
    pub fn refined(&mut self, id: u64) -> Option<&mut RefinedObject> {
        self.refined.get_mut(&id)
    }
}

/// A refiner over the decoded `bytes`, its arrays sized for the full mesh.
fn refined_object(bytes: stored::ProgressiveBytes) -> Result<RefinedObject> {
    let (pm, dag) = bytes.decode()?;
    let added: usize = pm.splits.iter().map(|s| s.added_triangles()).sum();
    let capacity = (
        pm.base.positions.len() + pm.splits.len(),
        pm.base.triangle_count() + added,
    );
    Ok(RefinedObject {
        refiner: Refiner::shared(Arc::new(pm), Arc::new(dag))?,
        pending: MeshChanges::default(),
        capacity,
    })
}
