//! The object buffer of a walk (Shou 2002 §4.2.2, Fig. 4.8): the objects loaded so far,
//! keyed by object id, under a memory budget in bytes.
//!
//! When the buffer is over budget, the thesis keeps only the objects that overlap the
//! latest disk cell. The walk then restarts its CSearch history at that cell, so that
//! the buffer always holds every object of every cell in the history — the condition
//! under which CSearch's "only what is new" never leaves a hole. Departure: when even
//! the objects of the latest cell do not fit, the farthest from the viewer go too (the
//! budget is a hard limit), and the walk records an overflow.

use std::collections::HashMap;
use std::sync::Arc;

use glam::Vec3;

use crate::geom::Aabb;
use crate::rtree::ObjectEntry;
use crate::scene::Mesh;

/// An object in memory: its index entry and its mesh, at full detail or at the stored
/// level the walk chose for it.
///
/// An HDoV walk also holds groups of objects drawn as one (a tree node at an internal
/// LOD): their ids carry [`GROUP_ID`], so that they never meet an object's.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The object's entry in the R-tree: its id, box and where its mesh lies.
    pub entry: ObjectEntry,
    /// Its mesh at level `level`, as read from the database.
    pub mesh: Arc<Mesh>,
    /// Bytes it takes in memory, as the buffer's budget counts them ([`mesh_bytes`]).
    pub bytes: usize,
    /// The stored level `mesh` is: 0 full detail, each higher one coarser.
    pub level: usize,
    /// The finest level LOD selection may draw it at: `level` (never finer than the walk
    /// loaded it) unless the walk lets the screen-space error ask for more (VISUAL's
    /// `finer_by_tau`), the finer level then read when first wanted.
    pub finest: usize,
    /// LOD selection draws it at the finer of `level` and the screen-space level, never
    /// coarser than loaded (VISUAL's screen rule: the finer of eq. 5.6's level and τ's),
    /// rather than at the coarser of the screen-space level and `finest`.
    pub finer_of: bool,
    /// Its DoV from the viewer's cell, when the walk hands it on for LOD selection
    /// (VISUAL with `dov_tau`): an object refined view by view then takes a τ its DoV
    /// stretches ([`dov_tau`](super::lod_select::dov_tau)).
    pub dov: Option<f32>,
    /// The factor LOD selection stretches its τ by for this object: 1, but for an
    /// object VISUAL's screen rule found with a DoV of at most η
    /// ([`faint_tau_scale`](crate::walk::visual::faint_tau_scale)).
    pub tau_scale: f32,
}

/// The bit an id has when it names a group of objects drawn as one (an HDoV-tree node
/// at one of its internal LODs) rather than an object.
pub const GROUP_ID: u64 = 1 << 63;

impl Loaded {
    /// `entry`'s object with its full mesh.
    pub fn new(entry: ObjectEntry, mesh: Mesh) -> Loaded {
        Loaded::at_level(entry, mesh, 0)
    }

    /// `entry`'s object with `mesh`, its stored level `level`.
    pub fn at_level(entry: ObjectEntry, mesh: Mesh, level: usize) -> Loaded {
        Loaded {
            entry,
            bytes: mesh_bytes(&mesh),
            mesh: Arc::new(mesh),
            level,
            finest: level,
            finer_of: false,
            dov: None,
            tau_scale: 1.0,
        }
    }

    /// Whether it is a group of objects drawn as one ([`GROUP_ID`]).
    pub fn is_group(&self) -> bool {
        self.entry.id & GROUP_ID != 0
    }
}

/// Bytes a mesh takes in memory (positions, normals, indices).
pub fn mesh_bytes(mesh: &Mesh) -> usize {
    mesh.positions.len() * 24 + mesh.indices.len() * 4
}

/// What an eviction did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Eviction {
    /// Objects dropped from the buffer.
    pub evicted: usize,
    /// The latest cell's own objects did not fit: some of them were dropped too.
    pub overflow: bool,
}

/// The object buffer of a walk (Shou 2002 §4.2.2, Fig. 4.8): the objects loaded so far,
/// keyed by object id, under a memory budget in bytes. Over budget, an eviction keeps
/// the objects that overlap the latest disk cell and, when even those do not fit, drops
/// the farthest from the viewer until they do ([`ObjectBuffer::evict_outside`]).
///
/// ```
/// use flaneur::walk::{Loaded, ObjectBuffer};
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, path) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # let city = citygen::CityConfig { objects: 60, ..Default::default() };
/// # citygen::write_city(&city, &scene)?;
/// # let opts = flaneur::BuildOptions { lod: None, ..Default::default() };
/// # flaneur::build_from_scene(&scene, &path, &opts)?;
/// let db = flaneur::Database::open(&path)?;
/// let mut buffer = ObjectBuffer::new(64 << 20);
/// for entry in db.range(&db.bounds())?.objects {
///     let mesh = db.mesh(&entry)?;
///     buffer.insert(Loaded::new(entry, mesh));
/// }
/// assert!(!buffer.is_empty() && !buffer.over_budget());
/// # Ok(()) }
/// ```
#[derive(Debug)]
pub struct ObjectBuffer {
    objects: HashMap<u64, Loaded>,
    bytes: usize,
    budget: usize,
}

impl ObjectBuffer {
    /// An empty buffer of `budget` bytes.
    pub fn new(budget: usize) -> ObjectBuffer {
        ObjectBuffer {
            objects: HashMap::new(),
            bytes: 0,
            budget,
        }
    }

    /// Objects in the buffer.
    pub fn len(&self) -> usize {
        self.objects.len()
    }

    /// Whether it holds no object.
    pub fn is_empty(&self) -> bool {
        self.objects.is_empty()
    }

    /// Bytes its objects take, summed from their [`Loaded::bytes`].
    pub fn bytes(&self) -> usize {
        self.bytes
    }

    /// Its budget, bytes.
    pub fn budget(&self) -> usize {
        self.budget
    }

    /// Whether object `id` is in the buffer.
    pub fn contains(&self, id: u64) -> bool {
        self.objects.contains_key(&id)
    }

    /// Whether its objects take more than its budget (an insertion never evicts: the
    /// walk evicts when it sees this).
    pub fn over_budget(&self) -> bool {
        self.bytes > self.budget
    }

    /// Puts `loaded` in place of the object of its id, if there was one (an object
    /// loaded again at another level).
    pub fn replace(&mut self, loaded: Loaded) {
        self.remove(loaded.entry.id);
        self.insert(loaded);
    }

    /// Adds an object (a second copy of the same id is ignored).
    pub fn insert(&mut self, loaded: Loaded) {
        if let std::collections::hash_map::Entry::Vacant(slot) = self.objects.entry(loaded.entry.id)
        {
            self.bytes += loaded.bytes;
            slot.insert(loaded);
        }
    }

    /// Puts `finer` in place of the same object held at a coarser level, if the budget
    /// has room for the difference; whether it did. An object no longer held is not
    /// brought back.
    pub fn refine(&mut self, finer: Loaded) -> bool {
        let Some(held) = self.objects.get_mut(&finer.entry.id) else {
            return false;
        };
        let grown = self.bytes - held.bytes + finer.bytes;
        if held.level <= finer.level || grown > self.budget {
            return false;
        }
        *held = finer;
        self.bytes = grown;
        true
    }

    /// Its objects, in no particular order.
    pub fn iter(&self) -> impl Iterator<Item = &Loaded> {
        self.objects.values()
    }

    /// The object `id`, if it is in the buffer.
    pub fn get(&self, id: u64) -> Option<&Loaded> {
        self.objects.get(&id)
    }

    /// Drops object `id`; whether it was there.
    pub fn remove(&mut self, id: u64) -> bool {
        match self.objects.remove(&id) {
            Some(o) => {
                self.bytes -= o.bytes;
                true
            }
            None => false,
        }
    }

    /// Fig. 4.8: keeps only the objects overlapping `cell`; if they still exceed the
    /// budget, drops the farthest from `eye` until they fit.
    pub fn evict_outside(&mut self, cell: &Aabb, eye: Vec3) -> Eviction {
        self.evict_outside_all(std::slice::from_ref(cell), eye)
    }

    /// [`ObjectBuffer::evict_outside`] for several latest cells (the disk cell the
    /// viewer is in and the one prefetched for it): keeps the objects overlapping any.
    pub fn evict_outside_all(&mut self, cells: &[Aabb], eye: Vec3) -> Eviction {
        let before = self.objects.len();
        self.objects
            .retain(|_, o| cells.iter().any(|c| o.entry.bounds.overlaps(c)));
        self.bytes = self.objects.values().map(|o| o.bytes).sum();
        let mut overflow = false;
        if self.bytes > self.budget {
            overflow = true;
            let mut by_distance: Vec<(f32, u64, usize)> = self
                .objects
                .values()
                .map(|o| {
                    (
                        o.entry.bounds.center().distance_squared(eye),
                        o.entry.id,
                        o.bytes,
                    )
                })
                .collect();
            by_distance.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            for (_, id, bytes) in by_distance {
                if self.bytes <= self.budget {
                    break;
                }
                self.objects.remove(&id);
                self.bytes -= bytes;
            }
        }
        Eviction {
            evicted: before - self.objects.len(),
            overflow,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::store::Extent;

    /// An object of `bytes` with an empty mesh in the unit box at `x` on the x axis.
    pub(crate) fn loaded(id: u64, x: f32, bytes: usize) -> Loaded {
        Loaded {
            entry: ObjectEntry {
                id,
                bounds: Aabb::new([x, 0.0, 0.0], [x + 1.0, 1.0, 1.0]).unwrap(),
                mesh: Extent {
                    first_page: 1,
                    page_count: 1,
                    byte_len: 10,
                    ..Extent::default()
                },
                triangles: 1,
                kind: 0,
            },
            mesh: Arc::new(Mesh::default()),
            bytes,
            level: 0,
            finest: 0,
            finer_of: false,
            dov: None,
            tau_scale: 1.0,
        }
    }

    #[test]
    fn keeps_the_latest_cell_then_the_nearest() {
        let mut b = ObjectBuffer::new(250);
        for i in 0..5 {
            b.insert(loaded(i, i as f32 * 10.0, 100));
        }
        assert!(b.over_budget());
        let cell = Aabb::new([0.0, 0.0, 0.0], [25.0, 1.0, 1.0]).unwrap();
        let e = b.evict_outside(&cell, Vec3::ZERO);
        assert_eq!((e.evicted, e.overflow, b.len()), (3, true, 2));
        assert!(b.contains(0) && b.contains(1) && b.bytes() <= 250);
        b.insert(loaded(1, 10.0, 100));
        assert_eq!(b.bytes(), 200, "a second copy is not counted");
    }
}
