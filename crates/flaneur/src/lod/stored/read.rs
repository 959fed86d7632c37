//! Reading an object's stored LOD data through the store, every page counted: its list
//! of levels, one level's mesh, its progressive mesh and DAG.
//!
//! A level is read with as few pages as the layout allows (`chain`): the chain's first
//! page (its directory, and the coarsest levels with it), then only the pages of the
//! level asked for. Any damage is an error that names the page and the object; a
//! codec's complaint about bytes that passed their page checksums is reported against
//! the extent's first page.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::scene::Mesh;

use super::chain::{ChainDirectory, LevelInfo};
use super::table::LodEntry;
use crate::error::{Error, Result};
use crate::lod::dag::Dag;
use crate::lod::pm::ProgressiveMesh;
use crate::scene::decode_mesh;
use crate::store::{Extent, PageKind, Store};

/// Puts `what` (which data of which object) in front of an error about `ext`'s bytes;
/// a codec's `Invalid` becomes a `CorruptPage` naming the extent's first page.
fn about(store: &Store, ext: &Extent, what: &str, e: Error) -> Error {
    about_at(store.path(), ext, what, e)
}

/// [`about`] for bytes read from the database at `path`.
fn about_at(path: &Path, ext: &Extent, what: &str, e: Error) -> Error {
    match e {
        Error::CorruptPage {
            path,
            page,
            what: w,
        } => Error::CorruptPage {
            path,
            page,
            what: format!("{what}: {w}"),
        },
        Error::Truncated { path, what: w } => Error::Truncated {
            path,
            what: format!("{what}: {w}"),
        },
        Error::Invalid(w) => Error::CorruptPage {
            path: path.to_path_buf(),
            page: ext.first_page,
            what: format!("{what}: {w}"),
        },
        other => other,
    }
}

/// The head of a chain read so far: its first bytes, whole pages (or the whole chain).
struct ChainHead {
    dir: ChainDirectory,
    prefix: Vec<u8>,
}

/// The chain at `ext`'s directory and first pages, `what` naming it in errors.
fn read_chain(store: &Store, ext: &Extent, what: &str) -> Result<ChainHead> {
    let total = ext.byte_len as usize;
    let payload = store.payload_size();
    let read = |start: usize, len: usize| {
        store
            .read_extent_range(ext, PageKind::Lod, start, len)
            .map_err(|err| about(store, ext, what, err))
    };
    // The first page holds the header, usually the directory, often the coarsest level.
    let mut prefix = read(0, total.min(payload))?;
    let dir_len =
        ChainDirectory::len_from_prefix(&prefix).map_err(|err| about(store, ext, what, err))?;
    if dir_len > prefix.len() && dir_len <= total {
        // A long directory: read up to the end of its last page.
        let end = dir_len.div_ceil(payload).saturating_mul(payload).min(total);
        prefix.extend(read(prefix.len(), end - prefix.len())?);
    }
    let dir = ChainDirectory::decode(&prefix, total).map_err(|err| about(store, ext, what, err))?;
    Ok(ChainHead { dir, prefix })
}

/// The chain of the object of `e`, checked to be that object's.
fn read_chain_head(store: &Store, e: &LodEntry) -> Result<ChainHead> {
    let what = format!("LOD chain of object {}", e.id);
    let ext = &e.chain;
    let ChainHead { dir, prefix } = read_chain(store, ext, &what)?;
    if dir.object != e.id
        || dir.full_triangles != e.triangles
        || dir.stored_levels() != e.levels as usize
    {
        return Err(about(
            store,
            ext,
            &what,
            Error::Invalid(format!(
                "the chain is object {}'s with {} levels under a {}-triangle mesh; the table \
                 says object {}, {} levels, {} triangles",
                dir.object,
                dir.stored_levels(),
                dir.full_triangles,
                e.id,
                e.levels,
                e.triangles
            )),
        ));
    }
    Ok(ChainHead { dir, prefix })
}

/// Every level of the object of `e`, level 0 (its full mesh) first. Reads the chain's
/// directory.
pub(crate) fn levels(store: &Store, e: &LodEntry) -> Result<Vec<LevelInfo>> {
    if e.chain.is_empty() {
        return Ok(vec![LevelInfo {
            level: 0,
            triangles: e.triangles,
            error: 0.0,
        }]);
    }
    Ok(read_chain_head(store, e)?.dir.levels())
}

/// Level `level` of the object of `e` as a mesh: level 0 from its mesh extent, a coarse
/// level from the pages of its chain that hold the directory and that level.
pub(crate) fn level_mesh(store: &Store, e: &LodEntry, level: usize) -> Result<Mesh> {
    if level == 0 {
        let what = format!("mesh of object {}", e.id);
        let bytes = store
            .read_extent(&e.mesh, PageKind::Mesh)
            .map_err(|err| about(store, &e.mesh, &what, err))?;
        return decode_mesh(&bytes).map_err(|w| about(store, &e.mesh, &what, Error::Invalid(w)));
    }
    if level > e.levels as usize {
        return Err(Error::Invalid(format!(
            "object {} has LOD levels 0..={} (0 is its full mesh), not {level}",
            e.id, e.levels
        )));
    }
    let head = read_chain_head(store, e)?;
    let what = format!("LOD level {level} of object {}", e.id);
    chain_level_of(store, &e.chain, &head, level, &what)
}

/// The coarsest stored level of each object of `entries`, with its number: the chains'
/// first pages asked for together, then the pages their coarsest levels need beyond
/// them, so that a remote store fetches each step's pages in parallel. Objects with no
/// coarse level come at full detail (level 0), their meshes asked for together too.
pub(crate) fn coarsest_levels(store: &Store, entries: &[LodEntry]) -> Result<Vec<(usize, Mesh)>> {
    let (chained, whole): (Vec<&LodEntry>, Vec<&LodEntry>) =
        entries.iter().partition(|e| !e.chain.is_empty());
    store.announce(
        &chained
            .iter()
            .map(|e| e.chain.first_page)
            .collect::<Vec<_>>(),
    );
    // A failed fetch is the read's to report, naming its page.
    let _ = store.prefetch(&whole.iter().map(|e| e.mesh).collect::<Vec<_>>());
    let heads = chained
        .iter()
        .map(|e| read_chain_head(store, e))
        .collect::<Result<Vec<_>>>()?;
    let payload = store.payload_size();
    let mut rest = Vec::new();
    for (e, head) in chained.iter().zip(&heads) {
        let (offset, length) = head.dir.level_range(e.levels as usize)?;
        let have = head.prefix.len();
        if offset + length > have {
            let first = offset.max(have) / payload;
            let last = (offset + length - 1) / payload;
            rest.extend((first..=last).map(|p| e.chain.first_page + p as u64));
        }
    }
    store.announce(&rest);
    let mut heads = chained
        .iter()
        .map(|e| e.id)
        .zip(heads)
        .collect::<HashMap<_, _>>();
    entries
        .iter()
        .map(|e| match heads.remove(&e.id) {
            Some(head) => {
                let level = e.levels as usize;
                let what = format!("LOD level {level} of object {}", e.id);
                Ok((level, chain_level_of(store, &e.chain, &head, level, &what)?))
            }
            None => Ok((0, level_mesh(store, e, 0)?)),
        })
        .collect()
}

/// One level of a group's chain (an HDoV node's internal LODs, numbered 1..=n finest
/// first, not checked against an object), chosen by `pick` from its levels: the level's
/// description and mesh. `what` names the chain in errors.
pub(crate) fn chain_level(
    store: &Store,
    ext: &Extent,
    what: &str,
    pick: impl FnOnce(&[LevelInfo]) -> usize,
) -> Result<(LevelInfo, Mesh)> {
    let head = read_chain(store, ext, what)?;
    let levels = head.dir.levels();
    let level = pick(&levels[1..]) + 1;
    let info = *levels.get(level).ok_or_else(|| {
        Error::Invalid(format!("{what}: no level {level} of {}", levels.len() - 1))
    })?;
    let what = format!("{what}, level {level}");
    Ok((info, chain_level_of(store, ext, &head, level, &what)?))
}

/// The levels of a group's chain (an HDoV node's internal LODs, 1..=n finest first),
/// from its directory. `what` names the chain in errors.
pub(crate) fn chain_levels(store: &Store, ext: &Extent, what: &str) -> Result<Vec<LevelInfo>> {
    let mut levels = read_chain(store, ext, what)?.dir.levels();
    levels.remove(0);
    Ok(levels)
}

/// Stored level `level` of the chain at `ext` whose head is read.
fn chain_level_of(
    store: &Store,
    ext: &Extent,
    head: &ChainHead,
    level: usize,
    what: &str,
) -> Result<Mesh> {
    let (offset, length) = head.dir.level_range(level)?;
    let end = offset + length;
    let have = head.prefix.len();
    let bytes = if end <= have {
        head.prefix[offset..end].to_vec()
    } else {
        // Only the pages the prefix lacks: the finer levels before this one are skipped.
        let from = offset.max(have);
        let rest = store
            .read_extent_range(ext, PageKind::Lod, from, end - from)
            .map_err(|err| about(store, ext, what, err))?;
        let mut b = head.prefix.get(offset..).unwrap_or(&[]).to_vec();
        b.extend(rest);
        b
    };
    head.dir
        .decode_level(level, &bytes)
        .map_err(|err| about(store, ext, what, err))
}

/// The progressive mesh and DAG of the object of `e`, when it has them; checked against
/// each other so that refinement can start from them.
pub(crate) fn progressive(store: &Store, e: &LodEntry) -> Result<Option<(ProgressiveMesh, Dag)>> {
    read_progressive(store, e)?.map(|b| b.decode()).transpose()
}

/// An object's progressive mesh and DAG as read from their pages (counted, checksums
/// checked), not yet decoded. Decoding takes a few times longer than reading and needs
/// nothing of the store, so a walk can do it on another thread.
pub(crate) struct ProgressiveBytes {
    path: PathBuf,
    id: u64,
    triangles: u32,
    pm: (Extent, Vec<u8>),
    dag: (Extent, Vec<u8>),
}

/// The bytes of the progressive mesh and DAG of the object of `e`, when it has them.
pub(crate) fn read_progressive(store: &Store, e: &LodEntry) -> Result<Option<ProgressiveBytes>> {
    if e.pm.is_empty() {
        return Ok(None);
    }
    let read = |ext: &Extent, what: &str| {
        store
            .read_extent(ext, PageKind::Lod)
            .map_err(|err| about(store, ext, &format!("{what} of object {}", e.id), err))
    };
    Ok(Some(ProgressiveBytes {
        path: store.path().to_path_buf(),
        id: e.id,
        triangles: e.triangles,
        pm: (e.pm, read(&e.pm, "progressive mesh")?),
        dag: (e.dag, read(&e.dag, "LOD DAG")?),
    }))
}

impl ProgressiveBytes {
    /// The object these bytes belong to.
    pub(crate) fn id(&self) -> u64 {
        self.id
    }

    /// The progressive mesh and DAG, checked against each other and the object.
    pub(crate) fn decode(self) -> Result<(ProgressiveMesh, Dag)> {
        let (path, (pm_ext, pm_bytes), (dag_ext, dag_bytes)) = (&self.path, &self.pm, &self.dag);
        let what = format!("progressive mesh of object {}", self.id);
        let pm = ProgressiveMesh::from_bytes(pm_bytes)
            .map_err(|err| about_at(path, pm_ext, &what, err))?;
        if pm.triangle_map.len() != self.triangles as usize {
            return Err(about_at(
                path,
                pm_ext,
                &what,
                Error::Invalid(format!(
                    "it refines to {} triangles, the object has {}",
                    pm.triangle_map.len(),
                    self.triangles
                )),
            ));
        }
        let what = format!("LOD DAG of object {}", self.id);
        let dag = Dag::from_bytes(dag_bytes).map_err(|err| about_at(path, dag_ext, &what, err))?;
        // The DAG's nodes are the PM's position splits, in order.
        let runs_match = dag.split_count() == pm.splits.len()
            && (0..dag.node_count() as u32).all(|k| {
                let run = dag.splits(k);
                !pm.splits[run.start].joins_previous
                    && pm.splits[run.start + 1..run.end]
                        .iter()
                        .all(|s| s.joins_previous)
            });
        if !runs_match {
            return Err(about_at(
                path,
                dag_ext,
                &what,
                Error::Invalid(format!(
                    "its {} nodes over {} splits are not the runs of the progressive mesh's {} splits",
                    dag.node_count(),
                    dag.split_count(),
                    pm.splits.len()
                )),
            ));
        }
        Ok((pm, dag))
    }
}
