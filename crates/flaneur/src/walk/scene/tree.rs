//! The memory HDoV scene tree (Shou 2002 §6.1, §6.2.1): a k-D tree over every object of
//! a database, each node with its internal LODs in memory, its h and s (eqs. 5.3–5.4)
//! and one VD, the DoV and count of visible objects of its subtree from the current
//! viewcell; a hash table from object id to leaf for the VDs' update on a change of
//! cell (§6.2.2).
//!
//! Choices, named: the tree splits the objects at the median of their centres along the
//! longer side of the node's box on the ground, down to one object a leaf (the thesis
//! gives no rule); it is built in memory when loaded, not stored (seconds); a leaf's
//! representations are its object's stored levels, full mesh first; an internal node's
//! are made as the HDoV-tree's are (`hdov::lods`), from its children's coarsest ones,
//! each with its error in metres against the node's full geometry: always the bound of
//! `hdov::lods` (the proxy's Hausdorff distance from its source plus its children's
//! largest error, an object's coarsest level measured against its full mesh), never a
//! measurement against the whole subtree, which at every depth of a binary tree would
//! cost the city's triangles again.

use std::collections::HashMap;
use std::sync::Arc;

use rayon::prelude::*;

use crate::database::Database;
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::hdov::{aggregate, error_above, internal_levels, Reference, Vd};
use crate::lod::stored;
use crate::progress::{Progress, Step};
use crate::rtree::ObjectEntry;
use crate::scene::Mesh;
use crate::walk::GROUP_ID;

/// One node of the scene tree.
#[derive(Clone, Debug)]
pub struct SceneNode {
    /// The box of the objects below it.
    pub bounds: Aabb,
    /// Its two children (internal), or none (a leaf).
    pub children: Option<[u32; 2]>,
    /// The object of a leaf (its id), `None` for an internal node.
    pub object: Option<u64>,
    /// Its parent, `None` for the root.
    pub parent: Option<u32>,
    /// Objects below it.
    pub leaves: u32,
    /// Eq. 5.3: log₂ of its leaf descendants (the tree's fan-out is 2).
    pub h: f32,
    /// Eq. 5.4: its finest representation's faces over its children's.
    pub s: f32,
    /// Its representations, finest first: a leaf's object at its stored levels (the full
    /// mesh first), an internal node's internal LODs (none when its children's geometry
    /// could not be simplified).
    pub levels: Vec<Arc<Mesh>>,
    /// Their triangles, in the same order.
    pub triangles: Vec<u32>,
    /// Their errors in metres, in the same order: a leaf's its object's stored levels'
    /// (0 for the full mesh), an internal node's its internal LODs' bounds on their
    /// Hausdorff distances from its objects' full meshes (`hdov::lods`).
    pub errors: Vec<f32>,
    /// Its VD from the current viewcell.
    pub vd: Vd,
}

/// The scene tree of a whole database, in memory.
#[derive(Debug)]
pub struct SceneTree {
    /// Its nodes; the root is node 0.
    pub nodes: Vec<SceneNode>,
    /// Each object's leaf (§6.2.2's hash table of nodes).
    leaf_of: HashMap<u64, u32>,
    /// The nodes whose VD is not zero, to clear on the next change of cell.
    touched: Vec<u32>,
    /// The viewcell whose VDs the tree holds.
    cell: Option<u32>,
    /// Objects' entries in the index, by id.
    pub entries: HashMap<u64, ObjectEntry>,
}

impl SceneTree {
    /// Loads every object of `db` with its stored levels, builds the k-D tree over them
    /// and makes the internal LODs (in parallel, a level of the tree at a time); tells
    /// `progress` how far it has got. An error names an object whose data cannot be
    /// read.
    pub fn load(db: &Database, progress: &dyn Progress) -> Result<SceneTree> {
        let objects = db.range(&db.bounds())?.objects;
        if objects.is_empty() {
            return Err(Error::Invalid(format!(
                "{} has no objects to build a scene tree of",
                db.store().path().display()
            )));
        }
        let total = objects.len() as u64;
        let mut leaves: HashMap<u64, Levels> = HashMap::new();
        for (i, o) in objects.iter().enumerate() {
            leaves.insert(o.id, object_levels(db, o)?);
            if i % 64 == 0 {
                progress.update(Step::SceneObjects, i as u64, Some(total));
            }
        }
        progress.finish(Step::SceneObjects);
        let mut nodes = Vec::with_capacity(2 * objects.len());
        split(&mut nodes, objects.clone(), None);
        let mut tree = SceneTree {
            leaf_of: HashMap::new(),
            touched: Vec::new(),
            cell: None,
            entries: objects.into_iter().map(|o| (o.id, o)).collect(),
            nodes,
        };
        for (k, n) in tree.nodes.iter_mut().enumerate() {
            if let Some(id) = n.object {
                tree.leaf_of.insert(id, k as u32);
                let (levels, triangles, errors) = leaves.remove(&id).expect("every object loaded");
                n.levels = levels;
                n.triangles = triangles;
                n.errors = errors;
            }
        }
        tree.make_internal_lods(progress)?;
        Ok(tree)
    }

    /// Internal LODs from the leaves up, the nodes of one height at once; then each
    /// node's h and s.
    fn make_internal_lods(&mut self, progress: &dyn Progress) -> Result<()> {
        let height = self.heights();
        let top = height.iter().copied().max().unwrap_or(0);
        let internal = self.nodes.iter().filter(|n| n.object.is_none()).count() as u64;
        let mut done = 0;
        // Each internal node's coarsest geometry's error against its full geometry.
        let mut coarsest_error: Vec<Option<f32>> = vec![None; self.nodes.len()];
        for level in 1..=top {
            let at: Vec<usize> = (0..self.nodes.len())
                .filter(|&k| height[k] == level)
                .collect();
            let made: Vec<Result<(Levels, f32)>> = at
                .par_iter()
                .map(|&k| self.make_node(k as u32, &coarsest_error))
                .collect();
            for (&k, m) in at.iter().zip(made) {
                let ((levels, triangles, errors), error) = m?;
                self.nodes[k].levels = levels;
                self.nodes[k].triangles = triangles;
                self.nodes[k].errors = errors;
                coarsest_error[k] = Some(error);
            }
            done += at.len() as u64;
            progress.update(Step::SceneLods, done, Some(internal));
        }
        progress.finish(Step::SceneLods);
        for k in 0..self.nodes.len() {
            let n = &self.nodes[k];
            let below: u32 = match n.children {
                Some([a, b]) => self.faces(a) + self.faces(b),
                None => n.triangles.first().copied().unwrap_or(0),
            };
            let s = (self.faces(k as u32) as f64 / below.max(1) as f64).max(f64::MIN_POSITIVE);
            let h = (n.leaves as f32).log2();
            let n = &mut self.nodes[k];
            n.h = h;
            n.s = s as f32;
        }
        Ok(())
    }

    /// Internal node `k`'s internal LODs (its children's made), and its coarsest
    /// geometry's error against its full geometry; `errors` holds the internal nodes'
    /// made so far.
    fn make_node(&self, k: u32, errors: &[Option<f32>]) -> Result<(Levels, f32)> {
        let [a, b] = self.nodes[k as usize].children.expect("internal");
        let parts = [self.coarsest(a), self.coarsest(b)];
        let source = aggregate(parts.iter().map(|m| m.as_ref()));
        // The largest distance of a child's coarsest geometry from its full geometry
        // (an object's measured only as far as it could be the larger).
        let mut parts_error = 0.0f32;
        for c in [a, b] {
            let n = &self.nodes[c as usize];
            parts_error = match (errors[c as usize], n.object, &n.levels[..]) {
                (Some(e), _, _) => parts_error.max(e),
                (None, Some(_), [full, .., coarsest]) if !coarsest.indices.is_empty() => {
                    error_above(coarsest, full, parts_error)?
                }
                _ => parts_error,
            };
        }
        // Always the bound: a binary tree has a dozen depths, each the whole city, and
        // measuring each against its full geometry made the 3,000-object city's tree
        // load in 205 s against 6 s; the bound measures against the small source.
        let levels = if source.indices.is_empty() {
            Vec::new()
        } else {
            internal_levels(&source, Reference::Source { parts_error })?
        };
        let error = levels.last().map_or(parts_error, |l| l.error);
        let mut made: Levels = Default::default();
        for l in levels {
            made.1.push(l.mesh.triangle_count() as u32);
            made.2.push(l.error);
            made.0.push(Arc::new(l.mesh));
        }
        Ok((made, error))
    }

    /// Each node's height: 0 for a leaf.
    fn heights(&self) -> Vec<u32> {
        let mut h = vec![0u32; self.nodes.len()];
        // Children come after their parent: a reverse sweep sees them first.
        for k in (0..self.nodes.len()).rev() {
            if let Some([a, b]) = self.nodes[k].children {
                h[k] = 1 + h[a as usize].max(h[b as usize]);
            }
        }
        h
    }

    /// Node `k`'s coarsest geometry: its coarsest representation, or (an internal node
    /// without internal LODs) its children's.
    fn coarsest(&self, k: u32) -> Arc<Mesh> {
        let n = &self.nodes[k as usize];
        match (n.levels.last(), n.children) {
            (Some(m), _) => m.clone(),
            (None, Some([a, b])) => Arc::new(aggregate([
                self.coarsest(a).as_ref(),
                self.coarsest(b).as_ref(),
            ])),
            (None, None) => Arc::new(Mesh::default()),
        }
    }

    /// Node `k`'s faces for s: its finest representation's, or its children's.
    fn faces(&self, k: u32) -> u32 {
        let n = &self.nodes[k as usize];
        match (n.triangles.first(), n.children) {
            (Some(&t), _) => t,
            (None, Some([a, b])) => self.faces(a) + self.faces(b),
            (None, None) => 0,
        }
    }

    /// Brings the VDs to viewcell `cell`'s, from its PVS: the last cell's cleared, each
    /// visible object's DoV added up its path to the root through the hash table. An
    /// error for a cell without a PVS.
    pub fn enter(&mut self, db: &Database, cell: u32) -> Result<()> {
        if self.cell == Some(cell) {
            return Ok(());
        }
        let pvs = db
            .pvs(cell)?
            .ok_or_else(|| Error::Invalid(format!("viewcell {cell} has no PVS")))?;
        for k in self.touched.drain(..) {
            self.nodes[k as usize].vd = Vd::default();
        }
        for (id, &dov) in pvs.ids.iter().zip(&pvs.dov) {
            if dov <= 0.0 {
                continue;
            }
            let mut at = Some(*self.leaf_of.get(id).ok_or_else(|| {
                Error::Invalid(format!(
                    "object {id} of viewcell {cell}'s PVS is not in the scene tree"
                ))
            })?);
            while let Some(k) = at {
                let n = &mut self.nodes[k as usize];
                if n.vd.nvo == 0 {
                    self.touched.push(k);
                }
                n.vd.dov += dov;
                n.vd.nvo += 1;
                at = n.parent;
            }
        }
        self.cell = Some(cell);
        Ok(())
    }

    /// The viewcell whose VDs it holds.
    pub fn cell(&self) -> Option<u32> {
        self.cell
    }

    /// Node `k`'s id in an object buffer: its object's, or the node's with
    /// [`GROUP_ID`](crate::walk::GROUP_ID).
    pub fn key(&self, k: u32) -> u64 {
        self.nodes[k as usize].object.unwrap_or(GROUP_ID | k as u64)
    }
}

/// A node's representations, finest first, their triangles and their errors (metres).
type Levels = (Vec<Arc<Mesh>>, Vec<u32>, Vec<f32>);

/// Object `o`'s stored levels, full mesh first, and their triangles.
fn object_levels(db: &Database, o: &ObjectEntry) -> Result<Levels> {
    let full = db.mesh(o)?;
    let mut triangles = vec![full.triangle_count() as u32];
    let mut errors = vec![0.0];
    let mut levels = vec![Arc::new(full)];
    if let Some(e) = db.lod_entry(o.id)? {
        let infos = stored::levels(db.store(), &e)?;
        for k in 1..=e.levels as usize {
            let m = stored::level_mesh(db.store(), &e, k)?;
            triangles.push(m.triangle_count() as u32);
            errors.push(infos.get(k).map_or(0.0, |l| l.error));
            levels.push(Arc::new(m));
        }
    }
    Ok((levels, triangles, errors))
}

/// Appends the subtree over `objects` to `nodes` under `parent`: a leaf for one object,
/// else two halves at the median of the centres along the box's longer side on the
/// ground. Its index.
fn split(nodes: &mut Vec<SceneNode>, mut objects: Vec<ObjectEntry>, parent: Option<u32>) -> u32 {
    let bounds = objects.iter().fold(Aabb::EMPTY, |b, o| b.union(&o.bounds));
    let k = nodes.len() as u32;
    nodes.push(SceneNode {
        bounds,
        children: None,
        object: None,
        parent,
        leaves: objects.len() as u32,
        h: 0.0,
        s: 1.0,
        levels: Vec::new(),
        triangles: Vec::new(),
        errors: Vec::new(),
        vd: Vd::default(),
    });
    if objects.len() == 1 {
        nodes[k as usize].object = Some(objects[0].id);
        return k;
    }
    let e = bounds.extent();
    let axis = if e.x >= e.z { 0 } else { 2 };
    objects.sort_by(|a, b| {
        a.bounds.center()[axis]
            .total_cmp(&b.bounds.center()[axis])
            .then(a.id.cmp(&b.id))
    });
    let upper = objects.split_off(objects.len() / 2);
    let a = split(nodes, objects, Some(k));
    let b = split(nodes, upper, Some(k));
    nodes[k as usize].children = Some([a, b]);
    k
}
