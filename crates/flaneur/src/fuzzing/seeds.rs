//! The corpora's seeds, cut from a real database: the pieces each target takes, as the
//! file holds them. `write_decoder_seeds` (tests/fuzz_decoders_corpus.rs, ignored)
//! builds a small city and writes them, with the scene file and OBJ seeds it makes
//! itself.

use std::path::Path;

use crate::error::{Error, Result};
use crate::hdov::{TreeHead, HDOV_SEGMENT};
use crate::lod::stored::chain::{decode_chain, ChainDirectory};
use crate::lod::stored::table::LodTable;
use crate::rtree::ObjectEntry;
use crate::scene::{encode_levels_v2, DictionaryUse, Framing, Mesh, MeshCodec};
use crate::store::{page, Extent, PageKind, Store};
use crate::visibility::VISIBILITY_SEGMENT;
use crate::Database;

/// Seeds larger than this are left out (a corpus is stored in the repository), but
/// for the whole file.
const MAX_SEED: usize = 48 * 1024;

/// One seed: the target whose corpus it joins, a name saying what it is, its bytes.
#[derive(Clone, Debug)]
pub struct Seed {
    /// The target (`TARGETS`' name).
    pub target: &'static str,
    /// What the bytes are, for the file name.
    pub name: String,
    /// The bytes.
    pub bytes: Vec<u8>,
}

/// The seeds of every target but `scene_file` and `obj`, cut from the database at
/// `path`: its header page; a page of each kind; its R-tree nodes' payloads; objects'
/// mesh extents (in format version 2 also without zstd, and each chain's blob of
/// levels); their LOD chains, progressive meshes with DAGs, the LOD table; the
/// visibility table; the HDoV-tree's head, nodes and V-pages; and the whole file.
pub fn cut_seeds(path: &Path) -> Result<Vec<Seed>> {
    let file = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let db = Database::open(path)?;
    let store = db.store();
    let page_size = store.page_size();
    let mut seeds = Vec::new();
    let mut add = |target: &'static str, name: String, bytes: Vec<u8>| {
        if bytes.len() <= MAX_SEED || target == "database" {
            seeds.push(Seed {
                target,
                name,
                bytes,
            });
        }
    };
    add(
        "db_header",
        "header-page".into(),
        file[..page_size].to_vec(),
    );
    add("database", "whole-file".into(), file.clone());

    page_seeds(path, &file, page_size, &mut add)?;
    add("db_page", "packed-extents".into(), packed_extents_seed());

    let objects = db.range(&db.bounds())?.objects;
    mesh_seeds(store, &objects, &mut add)?;
    lod_seeds(store, &objects, &mut add)?;
    if let Some((extent, _)) = store.segment_extent(VISIBILITY_SEGMENT, |_, _| Ok(()))? {
        let bytes = store.read_extent(&extent, PageKind::Visibility)?;
        add("visibility_table", "table".into(), bytes);
    }
    if let Some((extent, _)) = store.segment_extent(HDOV_SEGMENT, |_, _| Ok(()))? {
        let bytes = store.read_extent(&extent, PageKind::HdovNode)?;
        if let Ok(head) = TreeHead::decode(&bytes) {
            // Node seeds with the tree's real node count.
            for s in seeds
                .iter_mut()
                .filter(|s| s.target == "hdov" && s.bytes[0] == 1)
            {
                s.bytes[1..5].copy_from_slice(&head.nodes.to_le_bytes());
            }
        }
        seeds.push(Seed {
            target: "hdov",
            name: "tree-head".into(),
            bytes: [&[0u8][..], &bytes].concat(),
        });
    }
    Ok(seeds)
}

/// Where a seed goes: its target, its name and its bytes.
type Add<'a> = dyn FnMut(&'static str, String, Vec<u8>) + 'a;

/// Seeds from the file's pages: a page or two of each kind, every R-tree node's payload,
/// and the HDoV-tree's first nodes and V-pages.
fn page_seeds(path: &Path, file: &[u8], page_size: usize, add: &mut Add<'_>) -> Result<()> {
    let mut kinds_seen = [0usize; 16];
    for (p, raw) in file.chunks_exact(page_size).enumerate().skip(1) {
        let Some(kind) = PageKind::from_u8(raw[0]) else {
            continue;
        };
        let seen = &mut kinds_seen[kind as usize];
        *seen += 1;
        if *seen <= 2 {
            add("db_page", format!("{}-page-{p}", kind.name()), raw.to_vec());
        }
        let payload = page::decode(raw, kind).map_err(|what| Error::CorruptPage {
            path: path.to_path_buf(),
            page: p as u64,
            what,
        })?;
        match kind {
            PageKind::RtreeNode => add("rtree_node", format!("node-page-{p}"), payload.to_vec()),
            PageKind::HdovNode if *seen <= 8 => {
                let mut b = vec![1];
                b.extend_from_slice(&u32::MAX.to_le_bytes());
                b.extend_from_slice(payload);
                add("hdov", format!("node-page-{p}"), b);
            }
            PageKind::VPage if *seen <= 4 => {
                let mut b = vec![2];
                b.extend_from_slice(&((payload.len() / 8).min(64) as u16).to_le_bytes());
                b.extend_from_slice(&u64::MAX.to_le_bytes());
                b.extend_from_slice(payload);
                add("hdov", format!("v-page-{p}"), b);
            }
            _ => {}
        }
    }
    Ok(())
}

/// Seeds from the first objects' mesh extents: as stored, and in format version 2 also
/// without zstd and with the target's own dictionary.
fn mesh_seeds(store: &Store, objects: &[ObjectEntry], add: &mut Add<'_>) -> Result<()> {
    for o in objects.iter().take(6) {
        let mesh = store.read_extent(&o.mesh, PageKind::Mesh)?;
        if mesh.starts_with(b"FLG2") {
            // The same mesh in version 2 without zstd: the codec's own buffers, which
            // the fuzzer mutates more usefully than a frame.
            let dict = store.dictionaries()?;
            let decoded =
                crate::scene::decode_mesh(&mesh, dict.as_ref()).map_err(Error::Invalid)?;
            let plain = MeshCodec::Meshopt { zstd: None }.to_bytes(&decoded)?;
            add("mesh_codec", format!("object-{}-no-zstd", o.id), plain);
            // And compressed with the target's dictionary, which it decodes with: the
            // city's is not in the input.
            let framed = MeshCodec::meshopt()
                .encode_with(&decoded, Some(super::dictionaries()))
                .map_err(Error::Invalid)?;
            add("mesh_codec", format!("object-{}-dictionary", o.id), framed);
        }
        add("mesh_codec", format!("object-{}", o.id), mesh);
    }
    Ok(())
}

/// Seeds from the LOD table: the table itself, each object's chain (and its blob of
/// levels in format version 2), and its progressive mesh with its DAG.
fn lod_seeds(store: &Store, objects: &[ObjectEntry], add: &mut Add<'_>) -> Result<()> {
    if let Some(table) = LodTable::open(store)? {
        let bytes = store.read_extent(&table.extent(), PageKind::Lod)?;
        let which = [1012, 4084, 65524]
            .iter()
            .position(|&p| p == store.payload_size());
        if let Some(which) = which {
            add(
                "lod_table",
                "table".into(),
                [&[which as u8][..], &bytes].concat(),
            );
        }
        let dict = store.dictionaries()?;
        for o in objects {
            let Some(e) = table.find(store, o.id)? else {
                continue;
            };
            if !e.chain.is_empty() {
                let mut chain = store.read_extent(&e.chain, PageKind::Lod)?;
                chain.extend(store.read_extent(&e.chain_rest, PageKind::Lod)?);
                // A version-2 chain's levels are one blob after its directory: a mesh
                // blob of several levels, for the mesh codec's target too.
                let blob = ChainDirectory::len_from_prefix(&chain)
                    .ok()
                    .and_then(|head| chain.get(head..))
                    .filter(|b| b.starts_with(b"FLG2"));
                if let Some(blob) = blob {
                    add(
                        "mesh_codec",
                        format!("levels-object-{}", o.id),
                        blob.to_vec(),
                    );
                    if blob.get(4).is_some_and(|f| f & 1 != 0) {
                        // Its levels compressed with the target's dictionary, as the
                        // meshes above (a small city may train no levels' dictionary).
                        let (_, finest_first) = decode_chain(&chain, dict.as_ref())?;
                        let coarse_first: Vec<&Mesh> = finest_first.iter().rev().collect();
                        let framing =
                            Framing::Dictionary(super::dictionaries(), DictionaryUse::Levels);
                        let (bytes, _) =
                            encode_levels_v2(&coarse_first, framing).map_err(Error::Invalid)?;
                        add(
                            "mesh_codec",
                            format!("levels-object-{}-dictionary", o.id),
                            bytes,
                        );
                    }
                }
                add("lod_chain", format!("object-{}", o.id), chain);
            }
            if !e.pm.is_empty() {
                let pm = store.read_extent(&e.pm, PageKind::Lod)?;
                let dag = store.read_extent(&e.dag, PageKind::Lod)?;
                let split = (pm.len() as u32).to_le_bytes();
                add(
                    "lod_pm_dag",
                    format!("object-{}", o.id),
                    [&split[..], &pm, &dag].concat(),
                );
            }
        }
    }
    Ok(())
}

/// A `db_page` input for its extents: a packed reference (2 pages from page 1, 1,200
/// bytes at byte 100), then blobs of both kinds, small ones and one over a page, as the
/// target cuts them (a length byte, times 8, then the bytes).
fn packed_extents_seed() -> Vec<u8> {
    let reference = Extent {
        first_page: 1,
        page_count: 2,
        byte_len: 1200,
        offset: 100,
        packed: true,
    };
    let mut b = reference.to_le_bytes().to_vec();
    for n in [12u8, 13, 200, 3, 126] {
        b.push(n);
        b.extend((0..n as usize * 8).map(|i| (i % 251) as u8));
    }
    b
}
