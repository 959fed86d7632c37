//! Reading what a search found at the detail it deserves: an object at the stored level
//! its eq. 5.6 weight picks (its full mesh when it has no coarser level), a node at the
//! internal LOD its eq. 5.5 weight picks ([`level_for_detail`]). Every page counted.

use super::search::{level_for_detail, Found};
use crate::error::{Error, Result};
use crate::lod::stored::{chain_level, level_mesh, levels, LodTable};
use crate::lod::LevelInfo;
use crate::scene::{decode_mesh, Mesh};
use crate::store::{PageKind, Store};

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
    match found {
        Found::Object { entry, detail, .. } => {
            let e = match lods {
                Some(t) => t.find(store, entry.id)?,
                None => None,
            };
            let Some(e) = e else {
                let bytes = store.read_extent(&entry.mesh, PageKind::Mesh)?;
                let mesh = decode_mesh(&bytes).map_err(|what| Error::CorruptPage {
                    path: store.path().to_path_buf(),
                    page: entry.mesh.first_page,
                    what: format!("mesh of object {}: {what}", entry.id),
                })?;
                return Ok(Representation { mesh, level: 0 });
            };
            let level = if e.levels == 0 {
                0
            } else {
                level_for_detail(&triangles(&levels(store, &e)?), *detail)
            };
            Ok(Representation {
                mesh: level_mesh(store, &e, level)?,
                level,
            })
        }
        Found::Node {
            node, lods, detail, ..
        } => {
            let what = format!("internal LODs of HDoV node {node}");
            let (info, mesh) = chain_level(store, lods, &what, |levels| {
                level_for_detail(&triangles(levels), *detail)
            })?;
            Ok(Representation {
                mesh,
                level: info.level,
            })
        }
    }
}
