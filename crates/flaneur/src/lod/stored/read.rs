//! Reading an object's stored LOD data through the store, every page counted: its list
//! of levels, one level's mesh, its progressive mesh and DAG.
//!
//! A level is read with as few pages as the layout allows (`chain`): the chain's first
//! page (its directory, and the coarsest levels with it), then only the pages of the
//! level asked for. Any damage is an error that names the page and the object; a
//! codec's complaint about bytes that passed their page checksums is reported against
//! the extent's first page.

use std::path::{Path, PathBuf};

use crate::scene::Mesh;

use super::chain::{ChainDirectory, LevelInfo};
use super::table::LodEntry;
use crate::error::{Error, Result};
use crate::lod::dag::Dag;
use crate::lod::pm::ProgressiveMesh;
use crate::scene::{decode_mesh, expand_frame, is_frame};
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

/// Where a chain's bytes lie: an object's in two extents, its head (the directory and
/// the coarsest level, in whole pages) and the rest (`table`); an HDoV node's in one.
/// Read as one run of bytes; a codec's complaint is reported against the head.
#[derive(Clone, Copy, Debug)]
struct ChainPlace {
    head: Extent,
    rest: Extent,
}

impl ChainPlace {
    fn of(e: &LodEntry) -> ChainPlace {
        ChainPlace {
            head: e.chain,
            rest: e.chain_rest,
        }
    }

    fn single(ext: &Extent) -> ChainPlace {
        ChainPlace {
            head: *ext,
            rest: Extent::default(),
        }
    }

    /// The chain's length in bytes.
    fn len(&self) -> usize {
        self.head.byte_len as usize + self.rest.byte_len as usize
    }

    /// The chain's bytes `start..start + len`, from whichever extents hold them.
    fn read(&self, store: &Store, start: usize, len: usize) -> Result<Vec<u8>> {
        let split = self.head.byte_len as usize;
        let end = start.saturating_add(len);
        let range = |ext: &Extent, from: usize, to: usize| {
            store.read_extent_range(ext, PageKind::Lod, from, to - from)
        };
        if end <= split {
            return range(&self.head, start, end);
        }
        if start >= split {
            return range(&self.rest, start - split, end - split);
        }
        let mut b = range(&self.head, start, split)?;
        b.extend(range(&self.rest, 0, end - split)?);
        Ok(b)
    }

    /// The file's pages that hold the chain's bytes `start..end` (`start < end`).
    fn pages(&self, start: usize, end: usize, payload: usize) -> Vec<u64> {
        let split = self.head.byte_len as usize;
        let span = |ext: &Extent, from: usize, to: usize| {
            ext.page_of(from as u64, payload)..=ext.page_of(to as u64 - 1, payload)
        };
        let mut pages = Vec::new();
        if start < split {
            pages.extend(span(&self.head, start, end.min(split)));
        }
        if end > split {
            pages.extend(span(&self.rest, start.max(split) - split, end - split));
        }
        pages
    }

    /// Where the page that holds the chain's byte `at` ends, as a chain offset: a packed
    /// chain (format version 2) starts inside its first page.
    fn page_end(&self, at: usize, payload: usize) -> usize {
        let split = self.head.byte_len as usize;
        let (ext, base) = if at < split || self.rest.is_empty() {
            (&self.head, 0)
        } else {
            (&self.rest, split)
        };
        let abs = ext.offset as usize + (at - base);
        (abs / payload + 1) * payload - ext.offset as usize + base
    }
}

/// The head of a chain read so far: its first bytes, whole pages (or the whole chain).
struct ChainHead {
    dir: ChainDirectory,
    prefix: Vec<u8>,
}

/// The chain at `place`'s directory and first pages, `what` naming it in errors.
fn read_chain(store: &Store, place: &ChainPlace, what: &str) -> Result<ChainHead> {
    let total = place.len();
    let payload = store.payload_size();
    let ext = &place.head;
    let read = |start: usize, len: usize| {
        place
            .read(store, start, len)
            .map_err(|err| about(store, ext, what, err))
    };
    // The first page holds the header, usually the directory, often the coarsest level.
    // (A packed chain starts inside its page; a header cut by the page's end reads on
    // into the next.)
    let first = place.page_end(0, payload).max(ChainDirectory::HEADER_LEN);
    let mut prefix = read(0, total.min(first))?;
    let dir_len =
        ChainDirectory::len_from_prefix(&prefix).map_err(|err| about(store, ext, what, err))?;
    if dir_len > prefix.len() && dir_len <= total {
        // A long directory: read up to the end of its last page.
        let end = place.page_end(dir_len - 1, payload).min(total);
        prefix.extend(read(prefix.len(), end - prefix.len())?);
    }
    let dir = ChainDirectory::decode(&prefix, total).map_err(|err| about(store, ext, what, err))?;
    Ok(ChainHead { dir, prefix })
}

/// The chain of the object of `e`, checked to be that object's.
fn read_chain_head(store: &Store, e: &LodEntry) -> Result<ChainHead> {
    let what = format!("LOD chain of object {}", e.id);
    let ext = &e.chain;
    let ChainHead { dir, prefix } = read_chain(store, &ChainPlace::of(e), &what)?;
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
        let dict = store.dictionaries()?;
        return decode_mesh(&bytes, dict.as_ref())
            .map_err(|w| about(store, &e.mesh, &what, Error::Invalid(w)));
    }
    check_level(e, level)?;
    let head = read_chain_head(store, e)?;
    let what = format!("LOD level {level} of object {}", e.id);
    chain_level_of(store, &ChainPlace::of(e), &head, level, &what)
}

/// Every coarse level of the object of `e` (all but its full mesh), finest first, each
/// with its error in metres, its chain's head read once; none for an object with no
/// chain.
pub(crate) fn coarse_levels(store: &Store, e: &LodEntry) -> Result<Vec<(Mesh, f32)>> {
    if e.chain.is_empty() {
        return Ok(Vec::new());
    }
    let head = read_chain_head(store, e)?;
    let place = ChainPlace::of(e);
    head.dir
        .levels()
        .iter()
        .skip(1)
        .map(|l| {
            let what = format!("LOD level {} of object {}", l.level, e.id);
            Ok((
                chain_level_of(store, &place, &head, l.level, &what)?,
                l.error,
            ))
        })
        .collect()
}

/// The coarsest stored level of each object of `entries`, with its number: the chains'
/// heads asked for together (then any page a coarsest level needs beyond its head,
/// which a build of this version never leaves), so that a remote store fetches them in
/// a few parallel runs. Objects with no coarse level come at full detail (level 0),
/// their meshes asked for together with the heads.
pub(crate) fn coarsest_levels(store: &Store, entries: &[LodEntry]) -> Result<Vec<(usize, Mesh)>> {
    let wanted: Vec<(LodEntry, usize)> = entries
        .iter()
        .map(|e| {
            (
                *e,
                if e.chain.is_empty() {
                    0
                } else {
                    e.levels as usize
                },
            )
        })
        .collect();
    levels_at(store, &wanted)
        .into_iter()
        .zip(&wanted)
        .map(|(mesh, (_, level))| Ok((*level, mesh?)))
        .collect()
}

/// Level `level` of the object of each `(entry, level)` of `wanted`, in order: the
/// chains' heads of the coarse levels and the full meshes asked for together, then the
/// pages each coarse level needs beyond its head, so that a remote store fetches a
/// batch in a few parallel runs. Each object's result apart: damage costs that object.
pub(crate) fn levels_at(store: &Store, wanted: &[(LodEntry, usize)]) -> Vec<Result<Mesh>> {
    let coarse = |e: &LodEntry, level: usize| level > 0 && !e.chain.is_empty();
    // A chain's head is its directory and its coarsest level, and a batch's heads lie
    // side by side (`bake`): asked for whole, they come in a few runs, with the full
    // meshes. A failed fetch is the read's to report, naming its page.
    let first: Vec<Extent> = wanted
        .iter()
        .map(|(e, level)| if coarse(e, *level) { e.chain } else { e.mesh })
        .collect();
    let _ = store.prefetch(&first);
    let heads: Vec<Result<Option<ChainHead>>> = Error::until_offline(wanted, |(e, level)| {
        coarse(e, *level)
            .then(|| read_chain_head(store, e))
            .transpose()
    });
    let rest: Vec<u64> = wanted
        .iter()
        .zip(&heads)
        .filter_map(|((e, level), head)| match head {
            Ok(Some(head)) => pages_beyond_head(store, &ChainPlace::of(e), head, *level).ok(),
            _ => None,
        })
        .flatten()
        .collect();
    store.announce(&rest);
    Error::until_offline(wanted.iter().zip(heads), |((e, level), head)| match head? {
        None => level_mesh(store, e, *level),
        Some(head) => {
            check_level(e, *level)?;
            let what = format!("LOD level {level} of object {}", e.id);
            chain_level_of(store, &ChainPlace::of(e), &head, *level, &what)
        }
    })
}

/// The pages of the chain at `place` (its head read) that level `level` lies on beyond
/// the head: none when the head holds it.
fn pages_beyond_head(
    store: &Store,
    place: &ChainPlace,
    head: &ChainHead,
    level: usize,
) -> Result<Vec<u64>> {
    let (start, end) = head.dir.read_range(level)?;
    let have = head.prefix.len();
    if end <= have {
        return Ok(Vec::new());
    }
    Ok(place.pages(start.max(have), end, store.payload_size()))
}

/// Level `level` of each group's chain of `wanted` (an HDoV node's internal LODs,
/// 1..=n finest first; `what` naming it in errors), in order: the chains' heads read,
/// then the pages each level needs beyond its head asked for together, so that a remote
/// store fetches a batch in a few parallel runs. Each chain's result apart.
pub(crate) fn chain_levels_at(
    store: &Store,
    wanted: &[(Extent, usize, String)],
) -> Vec<Result<Mesh>> {
    let heads: Vec<Result<ChainHead>> = Error::until_offline(wanted, |(ext, _, what)| {
        read_chain(store, &ChainPlace::single(ext), what)
    });
    let rest: Vec<u64> = wanted
        .iter()
        .zip(&heads)
        .filter_map(|((ext, level, _), head)| {
            let head = head.as_ref().ok()?;
            pages_beyond_head(store, &ChainPlace::single(ext), head, *level).ok()
        })
        .flatten()
        .collect();
    store.announce(&rest);
    Error::until_offline(wanted.iter().zip(heads), |((ext, level, what), head)| {
        let head = head?;
        let stored = head.dir.stored_levels();
        if *level == 0 || *level > stored {
            return Err(Error::Invalid(format!(
                "{what}: no level {level} of {stored}"
            )));
        }
        let what = format!("{what}, level {level}");
        chain_level_of(store, &ChainPlace::single(ext), &head, *level, &what)
    })
}

/// An error unless the object of `e` has a stored level `level`.
fn check_level(e: &LodEntry, level: usize) -> Result<()> {
    if level > e.levels as usize {
        return Err(Error::Invalid(format!(
            "object {} has LOD levels 0..={} (0 is its full mesh), not {level}",
            e.id, e.levels
        )));
    }
    Ok(())
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
    let place = ChainPlace::single(ext);
    let head = read_chain(store, &place, what)?;
    let levels = head.dir.levels();
    let level = pick(&levels[1..]) + 1;
    let info = *levels.get(level).ok_or_else(|| {
        Error::Invalid(format!("{what}: no level {level} of {}", levels.len() - 1))
    })?;
    let what = format!("{what}, level {level}");
    Ok((info, chain_level_of(store, &place, &head, level, &what)?))
}

/// The levels of a group's chain (an HDoV node's internal LODs, 1..=n finest first),
/// from its directory. `what` names the chain in errors.
pub(crate) fn chain_levels(store: &Store, ext: &Extent, what: &str) -> Result<Vec<LevelInfo>> {
    let mut levels = read_chain(store, &ChainPlace::single(ext), what)?
        .dir
        .levels();
    levels.remove(0);
    Ok(levels)
}

/// Stored level `level` of the chain at `place` whose head is read.
fn chain_level_of(
    store: &Store,
    place: &ChainPlace,
    head: &ChainHead,
    level: usize,
    what: &str,
) -> Result<Mesh> {
    let ext = &place.head;
    let (start, end) = head.dir.read_range(level)?;
    let have = head.prefix.len();
    let bytes = if end <= have {
        head.prefix[start..end].to_vec()
    } else {
        // Only the pages the prefix lacks: the finer levels before this one are skipped.
        let from = start.max(have);
        let rest = place
            .read(store, from, end - from)
            .map_err(|err| about(store, ext, what, err))?;
        let mut b = head.prefix.get(start..).unwrap_or(&[]).to_vec();
        b.extend(rest);
        b
    };
    head.dir
        .decode_level(level, &bytes, store.dictionaries()?.as_ref())
        .map_err(|err| about(store, ext, what, err))
}

/// The bytes of a progressive mesh or DAG as its codec reads them: a zstd frame (format
/// version 2) expanded, to at most 64 times its length (far above what zstd makes of
/// these codecs), else the bytes themselves (version 1).
fn unframed(bytes: &[u8]) -> Result<std::borrow::Cow<'_, [u8]>> {
    if !is_frame(bytes) {
        return Ok(std::borrow::Cow::Borrowed(bytes));
    }
    let max = bytes.len().saturating_mul(64).saturating_add(1 << 16);
    Ok(std::borrow::Cow::Owned(
        expand_frame(bytes, max).map_err(Error::Invalid)?,
    ))
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
    /// The bytes `pm` and `dag` of the progressive mesh and DAG of object `id`, of
    /// `triangles` triangles, as if read from nowhere (errors name no file and page 0):
    /// for decoding bytes that came from elsewhere.
    pub(crate) fn from_parts(id: u64, triangles: u32, pm: Vec<u8>, dag: Vec<u8>) -> Self {
        ProgressiveBytes {
            path: PathBuf::new(),
            id,
            triangles,
            pm: (Extent::default(), pm),
            dag: (Extent::default(), dag),
        }
    }

    /// The object these bytes belong to.
    pub(crate) fn id(&self) -> u64 {
        self.id
    }

    /// The progressive mesh and DAG, checked against each other and the object.
    pub(crate) fn decode(self) -> Result<(ProgressiveMesh, Dag)> {
        let (path, (pm_ext, pm_bytes), (dag_ext, dag_bytes)) = (&self.path, &self.pm, &self.dag);
        let what = format!("progressive mesh of object {}", self.id);
        let pm_bytes = unframed(pm_bytes).map_err(|err| about_at(path, pm_ext, &what, err))?;
        let pm = ProgressiveMesh::from_bytes(&pm_bytes)
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
        let dag = unframed(dag_bytes)
            .and_then(|b| Dag::from_bytes(&b))
            .map_err(|err| about_at(path, dag_ext, &what, err))?;
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
