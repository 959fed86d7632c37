//! What a database file records about its objects outside the R-tree: how one object's
//! mesh is written and indexed, and the header segments that count the objects, their
//! triangles, their bounds and the pages of each kind.
//!
//! A build writes these and an open database reads them and, on insert, writes them
//! again; both point down here so that neither depends on the other.

use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::rtree::ObjectEntry;
use crate::scene::{decode_mesh, Mesh, MeshCodec};
use crate::store::{Extent, PageKind, Segment, Store};

const OBJECTS_SEGMENT: &str = "objects";
/// How the file's meshes are coded: `a` 1 raw (format version 1), 2 meshoptimizer's;
/// `b` the zstd level around each buffer, 0 for none. Absent in files of version 1.
const GEOMETRY_SEGMENT: &str = "geometry";
const CODEC_RAW: u64 = 1;
const CODEC_MESHOPT: u64 = 2;
const BOUNDS_SEGMENT: &str = "bounds";
const KINDS_SEGMENT: &str = "pagekinds";

/// Pages written per kind, kept in the header so `info` need not scan the file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct KindCounts {
    /// R-tree node pages ([`PageKind::RtreeNode`](crate::store::PageKind::RtreeNode)).
    pub rtree: u64,
    /// The objects' full meshes' pages ([`PageKind::Mesh`](crate::store::PageKind::Mesh)).
    pub mesh: u64,
    /// Metadata pages ([`PageKind::Meta`](crate::store::PageKind::Meta)).
    pub meta: u64,
    /// LOD pages (chains, progressive meshes, DAGs, the LOD table); 0 in a database
    /// without LODs. Kept in the LOD table's segment, not in `pagekinds`, so that files
    /// written before LODs read the same.
    pub lod: u64,
    /// Visibility pages (the viewcells' table); 0 in a database without visibility.
    /// Kept in the table's segment, as the LOD pages are.
    pub visibility: u64,
}

/// The counts the header's segments hold.
pub(crate) struct Meta {
    pub objects: u64,
    pub triangles: u64,
    pub bounds: Aabb,
    /// The `pagekinds` segment's counts; `lod` and `visibility` are 0 here, their
    /// tables keep them.
    pub kinds: KindCounts,
}

/// Writes one object's mesh in `codec` and returns its index entry.
pub(crate) fn write_object(
    store: &mut Store,
    id: u64,
    kind: u8,
    mesh: &Mesh,
    codec: MeshCodec,
) -> Result<ObjectEntry> {
    let mut entry = object_entry(id, kind, mesh)?;
    let dict = store.dictionaries()?;
    let bytes = codec
        .encode_with(mesh, dict.as_ref())
        .map_err(|w| Error::Invalid(format!("object {id}: {w}")))?;
    entry.mesh = store.append_packed_or_whole(PageKind::Mesh, &bytes, codec.packs())?;
    Ok(entry)
}

/// The index entry of object `id` before its mesh is written (its extent empty): the
/// mesh checked, its bounds and triangles counted.
pub(crate) fn object_entry(id: u64, kind: u8, mesh: &Mesh) -> Result<ObjectEntry> {
    mesh.validate()
        .map_err(|w| Error::Invalid(format!("object {id}: {w}")))?;
    let (min, max) = mesh.bounds();
    let bounds = Aabb::new(min, max).map_err(|e| Error::Invalid(format!("object {id}: {e}")))?;
    Ok(ObjectEntry {
        id,
        bounds,
        mesh: Extent::default(),
        triangles: mesh.triangle_count() as u32,
        kind,
    })
}

/// Records `codec` in the header, and the format version its files need.
pub(crate) fn save_codec(store: &mut Store, codec: MeshCodec) -> Result<()> {
    let (a, b) = match codec {
        MeshCodec::Raw => {
            store.write_as_version(crate::store::OLDEST_FORMAT_VERSION)?;
            return Ok(());
        }
        MeshCodec::Meshopt { zstd } => (CODEC_MESHOPT, zstd.unwrap_or(0) as u64),
    };
    store.set_segment(Segment {
        name: GEOMETRY_SEGMENT.into(),
        a,
        b,
        c: 0,
    })
}

/// How the file's meshes are coded: raw when the header says nothing (every file of
/// format version 1). A `NotADatabase` for a codec this build does not know.
pub(crate) fn load_codec(store: &Store) -> Result<MeshCodec> {
    let Some(seg) = store.header().segment(GEOMETRY_SEGMENT) else {
        return Ok(MeshCodec::Raw);
    };
    match (seg.a, i32::try_from(seg.b)) {
        (CODEC_RAW, _) => Ok(MeshCodec::Raw),
        (CODEC_MESHOPT, Ok(0)) => Ok(MeshCodec::Meshopt { zstd: None }),
        (CODEC_MESHOPT, Ok(level)) => Ok(MeshCodec::Meshopt { zstd: Some(level) }),
        _ => Err(Error::NotADatabase {
            path: store.path().to_path_buf(),
            what: format!(
                "its meshes are coded as {}/{}, which this build does not know",
                seg.a, seg.b
            ),
        }),
    }
}

/// Reads the counts from the header; a `NotADatabase` naming the first segment missing.
pub(crate) fn load_meta(store: &Store) -> Result<Meta> {
    let missing = |name: &str| Error::NotADatabase {
        path: store.path().to_path_buf(),
        what: format!("it has no '{name}' segment"),
    };
    let h = store.header();
    let objects = h
        .segment(OBJECTS_SEGMENT)
        .ok_or_else(|| missing(OBJECTS_SEGMENT))?;
    let bounds = h
        .segment(BOUNDS_SEGMENT)
        .ok_or_else(|| missing(BOUNDS_SEGMENT))?;
    let kinds = h
        .segment(KINDS_SEGMENT)
        .ok_or_else(|| missing(KINDS_SEGMENT))?;
    Ok(Meta {
        objects: objects.a,
        triangles: objects.b,
        bounds: unpack_bounds(bounds),
        kinds: KindCounts {
            rtree: kinds.a,
            mesh: kinds.b,
            meta: kinds.c,
            lod: 0,
            visibility: 0,
        },
    })
}

/// Records the counts in the header (persisted at the store's flush/finish).
pub(crate) fn save_meta(
    store: &mut Store,
    objects: u64,
    triangles: u64,
    bounds: &Aabb,
    kinds: &KindCounts,
) -> Result<()> {
    store.set_segment(Segment {
        name: OBJECTS_SEGMENT.into(),
        a: objects,
        b: triangles,
        c: 0,
    })?;
    let [a, b, c] = pack_bounds(bounds);
    store.set_segment(Segment {
        name: BOUNDS_SEGMENT.into(),
        a,
        b,
        c,
    })?;
    store.set_segment(Segment {
        name: KINDS_SEGMENT.into(),
        a: kinds.rtree,
        b: kinds.mesh,
        c: kinds.meta,
    })
}

/// Reads `object`'s full mesh from `store` (counted like every read); a mesh that does
/// not decode is a [`Error::CorruptPage`] naming its first page and the object.
pub(crate) fn read_mesh(store: &Store, object: &ObjectEntry) -> Result<Mesh> {
    let bytes = store.read_extent(&object.mesh, PageKind::Mesh)?;
    decode_mesh(&bytes, store.dictionaries()?.as_ref()).map_err(|what| Error::CorruptPage {
        path: store.path().to_path_buf(),
        page: object.mesh.first_page,
        what: format!("mesh of object {}: {what}", object.id),
    })
}

fn pack_bounds(b: &Aabb) -> [u64; 3] {
    let bytes = b.to_le_bytes();
    [0, 1, 2].map(|i| u64::from_le_bytes(bytes[i * 8..i * 8 + 8].try_into().unwrap()))
}

fn unpack_bounds(seg: &Segment) -> Aabb {
    let mut bytes = [0u8; 24];
    for (i, v) in [seg.a, seg.b, seg.c].into_iter().enumerate() {
        bytes[i * 8..i * 8 + 8].copy_from_slice(&v.to_le_bytes());
    }
    Aabb::from_le_bytes(&bytes)
}
