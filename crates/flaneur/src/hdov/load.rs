//! Reading what a search found at the detail it deserves: an object at the stored level
//! its eq. 5.6 weight picks (its full mesh when it has no coarser level), a node at the
//! internal LOD its eq. 5.5 weight picks ([`level_for_detail`]). Every page counted.
//!
//! A node's levels come with their errors ([`Loader::node_levels`]): in metres, a sampled
//! Hausdorff distance from the node's full geometry, as a version-2 tree stores them
//! (`hdov::lods`); a version-1 tree's are quadric errors, no distance, and are read as
//! infinite, so that no screen-space test takes such a proxy for fine enough.
//!
//! A walk keeps one [`Loader`] from search to search: it remembers each object's and
//! node's levels once their directory is read, so that the level a later search's find
//! deserves is known without a read, and only what is not already held at that level is
//! loaded (the delta search of §5.8.5).
//!
//! A loader that reads many finds at once ([`Loader::learn`], [`Loader::meshes`]) asks
//! for their pages together first, so that a remote store fetches them in a few
//! parallel runs rather than a round trip each; it reads the same pages as one find at
//! a time.

use std::collections::HashMap;

use super::search::{level_for_detail, Found};
use super::tree::{HdovTree, ProxyErrors};
use crate::catalog::read_mesh;
use crate::error::{Error, Result};
use crate::lod::stored::{
    chain_level, chain_levels, chain_levels_at, level_mesh, levels, levels_at, LodEntry, LodTable,
};
use crate::lod::LevelInfo;
use crate::scene::Mesh;
use crate::store::{Extent, Store};

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

/// Reads `found` from `store`, finding objects' LODs through `lods` (a node's through
/// `tree`'s head, which says what their errors mean).
pub(crate) fn load(
    store: &Store,
    lods: Option<&LodTable>,
    tree: Option<&HdovTree>,
    found: &Found,
) -> Result<Representation> {
    let mut loader = Loader::new(store, lods, tree);
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
    /// The tree whose nodes it reads: its head says what their errors mean.
    tree: Option<&'a HdovTree>,
    objects: HashMap<u64, ObjectLevels>,
    /// Each node's internal LODs, finest (level 1) first, their errors in metres.
    nodes: HashMap<u32, Vec<LevelInfo>>,
}

impl<'a> Loader<'a> {
    pub(crate) fn new(
        store: &'a Store,
        lods: Option<&'a LodTable>,
        tree: Option<&'a HdovTree>,
    ) -> Loader<'a> {
        Loader {
            store,
            lods,
            tree,
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
            Found::Node { detail, .. } => {
                let t = triangles(self.node_levels(found)?);
                Ok(level_for_detail(&t, *detail) + 1)
            }
        }
    }

    /// Node `found`'s internal LODs, finest (level 1) first, each with its triangles
    /// and its error in metres (a version-1 tree's read as infinite). Reads its chain's directory the first time
    /// only; an object's find has none.
    pub(crate) fn node_levels(&mut self, found: &Found) -> Result<&[LevelInfo]> {
        let Found::Node { node, lods, .. } = found else {
            return Err(Error::Invalid("an object has no internal LODs".into()));
        };
        if !self.nodes.contains_key(node) {
            let mut levels = chain_levels(self.store, lods, &node_chain(*node))?;
            let errors = match self.tree {
                Some(t) => t.head(self.store)?.proxy_errors,
                None => ProxyErrors::Hausdorff,
            };
            if errors == ProxyErrors::Quadric {
                for l in levels.iter_mut() {
                    l.error = f32::INFINITY;
                }
            }
            self.nodes.insert(*node, levels);
        }
        Ok(&self.nodes[node])
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

    /// The coarsest level `found` has: an object's coarsest stored level (0 when it has
    /// none), a node's coarsest internal LOD. Reads its directory the first time only.
    pub(crate) fn coarsest(&mut self, found: &Found) -> Result<usize> {
        self.level(found)?;
        Ok(match found {
            Found::Object { entry, .. } => match self.object(entry.id)? {
                Some((e, _)) if !e.chain.is_empty() => e.levels as usize,
                _ => 0,
            },
            Found::Node { node, .. } => self.nodes[node].len(),
        })
    }

    /// Makes the levels of `finds` known, asking for what that reads together first (the
    /// objects' LOD table entries, then their chains' heads; the nodes' chains' first
    /// pages). The same pages as [`Loader::level`] one find at a time; a find whose data
    /// cannot be read stays unknown, for its level's read to name the damage.
    pub(crate) fn learn(&mut self, finds: &[Found]) {
        let store = self.store;
        let ids: Vec<u64> = finds
            .iter()
            .filter_map(|f| match f {
                Found::Object { entry, .. } if !self.objects.contains_key(&entry.id) => {
                    Some(entry.id)
                }
                _ => None,
            })
            .collect();
        let entries: Vec<(u64, Option<LodEntry>)> = match self.lods {
            Some(t) => {
                let mut pages: Vec<u64> = Error::until_offline(&ids, |&id| t.entry_page(store, id))
                    .into_iter()
                    .map_while(Result::ok)
                    .flatten()
                    .collect();
                pages.dedup();
                store.announce(&pages);
                Error::until_offline(&ids, |&id| t.find(store, id).map(|e| (id, e)))
                    .into_iter()
                    .map_while(Result::ok)
                    .collect()
            }
            None => ids.iter().map(|&id| (id, None)).collect(),
        };
        let heads: Vec<_> = entries
            .iter()
            .filter_map(|(_, e)| e.filter(|e| e.levels > 0).map(|e| e.chain))
            .collect();
        let _ = store.prefetch(&heads);
        let known = Error::until_offline(entries, |(id, found)| {
            Ok((
                id,
                match found {
                    Some(e) if e.levels > 0 => Some((e, triangles(&levels(store, &e)?))),
                    Some(e) => Some((e, vec![e.triangles])),
                    None => None,
                },
            ))
        });
        self.objects.extend(known.into_iter().flatten());
        let nodes: Vec<u64> = finds
            .iter()
            .filter_map(|f| match f {
                Found::Node { node, lods, .. } if !self.nodes.contains_key(node) => {
                    Some(lods.first_page)
                }
                _ => None,
            })
            .collect();
        store.announce(&nodes);
        let nodes = finds.iter().filter(|f| matches!(f, Found::Node { .. }));
        let _ = Error::until_offline(nodes, |f| self.level(f));
    }

    /// The meshes of `wanted`, each find at its level (one [`Loader::level`] or
    /// [`Loader::coarsest`] gave), in order, their pages asked for together first. Each
    /// find's result apart: damage costs that find.
    pub(crate) fn meshes(&mut self, wanted: &[(&Found, usize)]) -> Vec<Result<Mesh>> {
        let store = self.store;
        let mut out: Vec<Option<Result<Mesh>>> = (0..wanted.len()).map(|_| None).collect();
        // Objects with LOD data, read as a batch of levels.
        let mut chained: Vec<(usize, (LodEntry, usize))> = Vec::new();
        let mut nodes: Vec<(usize, (Extent, usize, String))> = Vec::new();
        let mut bare = Vec::new();
        for (k, (found, level)) in wanted.iter().enumerate() {
            match found {
                Found::Object { entry, .. } => match self.object(entry.id) {
                    Ok(Some((e, _))) => chained.push((k, (*e, *level))),
                    Ok(None) => bare.push(entry.mesh),
                    Err(e) => out[k] = Some(Err(e)),
                },
                Found::Node { node, lods, .. } => {
                    nodes.push((k, (*lods, *level, node_chain(*node))));
                }
            }
        }
        let _ = store.prefetch(&bare);
        let batch: Vec<(LodEntry, usize)> = chained.iter().map(|(_, w)| *w).collect();
        for ((k, _), mesh) in chained.iter().zip(levels_at(store, &batch)) {
            out[*k] = Some(mesh);
        }
        let batch: Vec<(Extent, usize, String)> = nodes.iter().map(|(_, w)| w.clone()).collect();
        for ((k, _), mesh) in nodes.iter().zip(chain_levels_at(store, &batch)) {
            out[*k] = Some(mesh);
        }
        Error::until_offline(wanted.iter().zip(out), |((found, level), got)| {
            got.unwrap_or_else(|| self.mesh(found, *level))
        })
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
