//! Reading what a search found at the detail it deserves: an object at the stored level
//! its eq. 5.6 weight picks (its full mesh when it has no coarser level), a node at the
//! internal LOD its eq. 5.5 weight picks ([`level_for_detail`]). Every page counted.
//!
//! A walk keeps one [`Loader`] from search to search: it remembers each object's and
//! node's levels once their directory is read, so that the level a later search's find
//! deserves is known without a read, and only what is not already held at that level is
//! loaded (the delta search of §5.8.5).

use std::collections::HashMap;

use super::search::{level_for_detail, Found};
use crate::catalog::read_mesh;
use crate::error::Result;
use crate::lod::stored::{chain_level, chain_levels, level_mesh, levels, LodEntry, LodTable};
use crate::lod::LevelInfo;
use crate::scene::Mesh;
use crate::store::Store;

/// A found object's or node's mesh, and the level it is at (0: an object's full mesh;
/// an internal LOD's levels count from 1, finest first).
#[derive(Clone, Debug, PartialEq)]
pub struct Representation {
    /// The mesh read.
    pub mesh: Mesh,
    /// Its level: 0 an object's full mesh, an internal LOD's from 1 (finest).
    pub level: usize,
}

fn triangles(levels: &[LevelInfo]) -> Vec<u32> {
    levels.iter().map(|l| l.triangles).collect()
}

/// Reads `found` from `store`, finding objects' LODs through `lods`.
pub(crate) fn load(
    store: &Store,
    lods: Option<&LodTable>,
    found: &Found,
) -> Result<Representation> {
    let mut loader = Loader::new(store, lods);
    let level = loader.level(found)?;
    Ok(Representation {
        mesh: loader.mesh(found, level)?,
        level,
    })
}

/// An object's LOD data as far as a loader needs it: where it lies and its levels'
/// triangles (`None`: no LOD data, full detail only).
type ObjectLevels = Option<(LodEntry, Vec<u32>)>;

/// Reads what searches find, remembering the levels of what it has seen.
pub(crate) struct Loader<'a> {
    store: &'a Store,
    lods: Option<&'a LodTable>,
    objects: HashMap<u64, ObjectLevels>,
    /// Each node's internal LODs' triangles, finest (level 1) first.
    nodes: HashMap<u32, Vec<u32>>,
}

impl<'a> Loader<'a> {
    pub(crate) fn new(store: &'a Store, lods: Option<&'a LodTable>) -> Loader<'a> {
        Loader {
            store,
            lods,
            objects: HashMap::new(),
            nodes: HashMap::new(),
        }
    }

    /// The level `found` deserves: reads its directory the first time only.
    pub(crate) fn level(&mut self, found: &Found) -> Result<usize> {
        match found {
            Found::Object { entry, detail, .. } => Ok(match self.object(entry.id)? {
                Some((e, t)) if e.levels > 0 => level_for_detail(t, *detail),
                _ => 0,
            }),
            Found::Node {
                node, lods, detail, ..
            } => {
                if !self.nodes.contains_key(node) {
                    let levels = chain_levels(self.store, lods, &node_chain(*node))?;
                    self.nodes.insert(*node, triangles(&levels));
                }
                Ok(level_for_detail(&self.nodes[node], *detail) + 1)
            }
        }
    }

    /// `found`'s mesh at `level` (one [`Loader::level`] gave).
    pub(crate) fn mesh(&mut self, found: &Found, level: usize) -> Result<Mesh> {
        match found {
            Found::Object { entry, .. } => match self.object(entry.id)?.as_ref().map(|(e, _)| *e) {
                Some(e) => level_mesh(self.store, &e, level),
                None => read_mesh(self.store, entry),
            },
            Found::Node { node, lods, .. } => {
                let what = node_chain(*node);
                let (_, mesh) = chain_level(self.store, lods, &what, |_| level - 1)?;
                Ok(mesh)
            }
        }
    }

    /// Object `id`'s LOD data, looked up and its levels read the first time.
    fn object(&mut self, id: u64) -> Result<&ObjectLevels> {
        if !self.objects.contains_key(&id) {
            let found = match self.lods {
                Some(t) => t.find(self.store, id)?,
                None => None,
            };
            let levels = match found {
                Some(e) if e.levels > 0 => Some((e, triangles(&levels(self.store, &e)?))),
                Some(e) => Some((e, vec![e.triangles])),
                None => None,
            };
            self.objects.insert(id, levels);
        }
        Ok(&self.objects[&id])
    }
}

/// How errors name a node's chain of internal LODs.
fn node_chain(node: u32) -> String {
    format!("internal LODs of HDoV node {node}")
}
