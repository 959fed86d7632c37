//! The HDoV-tree of an open database: its head (one extent of `HdovNode` pages named
//! by the header's `hdov` segment: a = first page, b = byte length, c = pages), its
//! nodes read one page each, and its storage schemes.
//!
//! ```text
//! head
//!   0  magic          b"FLHD"
//!   4  version        u32, TREE_VERSION (2); version 1, whose internal LODs' errors
//!                     are not distances, is read as [`ProxyErrors::Quadric`]
//!   8  first node     u64, the page of node 0 (the root); node n is page first + n
//!  16  nodes          u32, N_node
//!  20  height         u32, levels of nodes
//!  24  fan-out        u32, M: the entries packing put in a node (the base of h's log)
//!  28  cells          u32, C: the walkable viewcells, each with a slot
//!  32  objects        u64
//!  40  V-page bytes   u32
//!  44  schemes        u32, k
//!  48  seconds        f64, the build's time for the tree
//!  56  LOD pages      u64, the internal LODs' pages
//!  64  visible nodes  u64, N_vnode summed over the cells
//!  72  schemes        k × (scheme u32, 0 u32, extent 16 bytes)
//!  72+24k  cells      C × u32: the viewcell id of each slot, ascending
//!  …       crc32      of the bytes before it
//! ```

use std::sync::OnceLock;

use super::node::HNode;
use super::scheme::{Scheme, Shape, StoredScheme};
use crate::cache::{BufferPool, Hint};
use crate::error::{Error, Result};
use crate::store::framing::{f64_at, push_crc, u32_at, u64_at, CRC_LEN};
use crate::store::{Extent, PageKind, Store};

/// The header segment that names the HDoV-tree's head.
pub const HDOV_SEGMENT: &str = "hdov";
const MAGIC: [u8; 4] = *b"FLHD";
/// The tree encoding this build writes (it reads version 1 too).
pub const TREE_VERSION: u32 = 2;

/// What the `error` of each stored internal LOD level means, by the tree's version.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum ProxyErrors {
    /// Version 1: the LOD core's quadric error of the collapses that made the level,
    /// not a bound on its distance from the objects; readers take it as unknown.
    Quadric,
    /// Version 2: a sampled Hausdorff distance in metres, in the objects' frame, from
    /// the node's full geometry (`hdov::lods`).
    Hausdorff,
}

impl ProxyErrors {
    fn version(self) -> u32 {
        match self {
            ProxyErrors::Quadric => 1,
            ProxyErrors::Hausdorff => TREE_VERSION,
        }
    }
}
const FIXED: usize = 72;
const SCHEME_RECORD: usize = 24;

/// What the tree's head says.
#[derive(Clone, Debug, PartialEq)]
pub struct TreeHead {
    /// The page of node 0, the root; node n is page `first_node + n`.
    pub first_node: u64,
    /// Nodes of the tree (N_node).
    pub nodes: u32,
    /// Levels of nodes.
    pub height: u32,
    /// The entries packing put in a node (M, the base of h's log).
    pub fanout: u32,
    /// Objects below the root.
    pub objects: u64,
    /// Bytes of a V-page.
    pub vpage_len: u32,
    /// The build's seconds for the tree.
    pub seconds: f64,
    /// Pages of the internal LODs.
    pub lod_pages: u64,
    /// Visible nodes summed over the cells (N_vnode).
    pub visible_nodes: u64,
    /// Each scheme stored, and its extent.
    pub schemes: Vec<(Scheme, Extent)>,
    /// The viewcell id of each slot, ascending.
    pub cells: Vec<u32>,
    /// What its internal LODs' errors mean (the head's version says).
    pub proxy_errors: ProxyErrors,
}

impl TreeHead {
    /// The head's bytes, as the layout above.
    pub fn encode(&self) -> Vec<u8> {
        let mut b = Vec::new();
        b.extend_from_slice(&MAGIC);
        b.extend_from_slice(&self.proxy_errors.version().to_le_bytes());
        b.extend_from_slice(&self.first_node.to_le_bytes());
        for v in [
            self.nodes,
            self.height,
            self.fanout,
            self.cells.len() as u32,
        ] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&self.objects.to_le_bytes());
        b.extend_from_slice(&self.vpage_len.to_le_bytes());
        b.extend_from_slice(&(self.schemes.len() as u32).to_le_bytes());
        b.extend_from_slice(&self.seconds.to_le_bytes());
        b.extend_from_slice(&self.lod_pages.to_le_bytes());
        b.extend_from_slice(&self.visible_nodes.to_le_bytes());
        for (s, e) in &self.schemes {
            b.extend_from_slice(&(*s as u32).to_le_bytes());
            b.extend_from_slice(&0u32.to_le_bytes());
            b.extend_from_slice(&e.to_le_bytes());
        }
        for c in &self.cells {
            b.extend_from_slice(&c.to_le_bytes());
        }
        push_crc(&mut b);
        b
    }

    /// Reads a head's bytes; the complaint names what is wrong.
    pub fn decode(b: &[u8]) -> std::result::Result<TreeHead, String> {
        if b.len() < FIXED + CRC_LEN || b[..4] != MAGIC {
            return Err("not an HDoV-tree head".into());
        }
        let proxy_errors = match u32_at(b, 4) {
            1 => ProxyErrors::Quadric,
            TREE_VERSION => ProxyErrors::Hausdorff,
            v => {
                return Err(format!(
                    "HDoV-tree version {v}, this build reads 1 and {TREE_VERSION}"
                ))
            }
        };
        let (cells, k) = (u32_at(b, 28) as usize, u32_at(b, 44) as usize);
        let len = (FIXED + CRC_LEN) as u64 + SCHEME_RECORD as u64 * k as u64 + 4 * cells as u64;
        if len != b.len() as u64 {
            return Err(format!(
                "a head of {k} schemes and {cells} cells takes {len} bytes, it has {}",
                b.len()
            ));
        }
        let crc_at = b.len() - CRC_LEN;
        if crc32fast::hash(&b[..crc_at]) != u32_at(b, crc_at) {
            return Err("the head's checksum does not match".into());
        }
        let mut schemes = Vec::with_capacity(k);
        for i in 0..k {
            let r = &b[FIXED + i * SCHEME_RECORD..][..SCHEME_RECORD];
            let scheme = *Scheme::ALL
                .get(u32_at(r, 0) as usize)
                .ok_or_else(|| format!("scheme {} is not known", u32_at(r, 0)))?;
            schemes.push((
                scheme,
                Extent::from_le_bytes(r[8..24].try_into().expect("16")),
            ));
        }
        let at = FIXED + k * SCHEME_RECORD;
        let ids: Vec<u32> = (0..cells).map(|i| u32_at(b, at + 4 * i)).collect();
        if !ids.windows(2).all(|w| w[0] < w[1]) {
            return Err("the cells are not in ascending order".into());
        }
        let head = TreeHead {
            first_node: u64_at(b, 8),
            nodes: u32_at(b, 16),
            height: u32_at(b, 20),
            fanout: u32_at(b, 24),
            objects: u64_at(b, 32),
            vpage_len: u32_at(b, 40),
            seconds: f64_at(b, 48),
            lod_pages: u64_at(b, 56),
            visible_nodes: u64_at(b, 64),
            schemes,
            cells: ids,
            proxy_errors,
        };
        if head.nodes == 0 || head.height == 0 || head.fanout < 2 || head.vpage_len == 0 {
            return Err(format!(
                "a tree of {} nodes, height {}, fan-out {} and {}-byte V-pages",
                head.nodes, head.height, head.fanout, head.vpage_len
            ));
        }
        Ok(head)
    }

    /// The shape its schemes were written for.
    pub(crate) fn shape(&self) -> Shape {
        Shape {
            cells: self.cells.len(),
            nodes: self.nodes as usize,
            vpage_len: self.vpage_len as usize,
        }
    }

    /// What eqs. 5.7–5.9 estimate `scheme` takes for this tree, bytes (its head and,
    /// for the indexed scheme, its directory aside).
    pub fn estimate(&self, scheme: Scheme) -> u64 {
        super::scheme::estimate(scheme, self.shape(), self.visible_nodes)
    }

    /// The smallest scheme stored, by eqs. 5.7–5.9 for a city whose cells see little
    /// of the tree: indexed-vertical, then vertical, then horizontal. An error for a
    /// head that lists none.
    pub fn smallest_scheme(&self) -> Result<Scheme> {
        [Scheme::Indexed, Scheme::Vertical, Scheme::Horizontal]
            .into_iter()
            .find(|s| self.schemes.iter().any(|t| t.0 == *s))
            .ok_or_else(|| Error::Invalid("the HDoV-tree stores no scheme".into()))
    }

    /// The slot of viewcell `cell`, `None` when it has none (not walkable).
    pub fn slot(&self, cell: u32) -> Option<usize> {
        self.cells.binary_search(&cell).ok()
    }
}

/// The HDoV-tree of an open database.
#[derive(Debug)]
pub struct HdovTree {
    extent: Extent,
    head: OnceLock<TreeHead>,
    schemes: OnceLock<Vec<StoredScheme>>,
}

impl HdovTree {
    /// The tree the header's segment names, `None` for a database built without
    /// `--hdov`. Reads nothing.
    pub fn open(store: &Store) -> Result<Option<HdovTree>> {
        let found = store.segment_extent(HDOV_SEGMENT, |extent, c| {
            if c != extent.page_count as u64 {
                return Err(format!(
                    "a head of {} bytes takes {} pages, the segment says {c}",
                    extent.byte_len, extent.page_count
                ));
            }
            Ok(())
        })?;
        Ok(found.map(|(extent, _)| HdovTree {
            extent,
            head: OnceLock::new(),
            schemes: OnceLock::new(),
        }))
    }

    fn corrupt(&self, store: &Store, page: u64, what: String) -> Error {
        Error::CorruptPage {
            path: store.path().to_path_buf(),
            page,
            what,
        }
    }

    /// Where the head lies.
    pub(crate) fn extent(&self) -> Extent {
        self.extent
    }

    /// The head, read (and counted) the first time.
    pub fn head(&self, store: &Store) -> Result<&TreeHead> {
        if let Some(h) = self.head.get() {
            return Ok(h);
        }
        let b = store.read_extent(&self.extent, PageKind::HdovNode)?;
        let head =
            TreeHead::decode(&b).map_err(|e| self.corrupt(store, self.extent.first_page, e))?;
        Ok(self.head.get_or_init(|| head))
    }

    /// The schemes stored, their heads read (and counted) the first time.
    pub fn schemes(&self, store: &Store) -> Result<&[StoredScheme]> {
        if let Some(s) = self.schemes.get() {
            return Ok(s);
        }
        let head = self.head(store)?;
        let opened = head
            .schemes
            .iter()
            .map(|&(s, e)| StoredScheme::open(store, s, e, head.shape(), head.objects))
            .collect::<Result<Vec<_>>>()?;
        Ok(self.schemes.get_or_init(|| opened))
    }

    /// The stored scheme `scheme`; an error naming the schemes built when it is not.
    pub fn scheme(&self, store: &Store, scheme: Scheme) -> Result<&StoredScheme> {
        let all = self.schemes(store)?;
        all.iter().find(|s| s.scheme == scheme).ok_or_else(|| {
            let built: Vec<&str> = all.iter().map(|s| s.scheme.name()).collect();
            Error::Invalid(format!(
                "{}: the HDoV-tree was built with the {} scheme(s), not {}",
                store.path().display(),
                built.join(", "),
                scheme.name()
            ))
        })
    }

    /// Node `number`, read from its page (counted).
    #[cfg(test)]
    pub fn node(&self, store: &Store, number: u32) -> Result<HNode> {
        self.node_through(store, None, number, &Hint::UNKNOWN)
    }

    /// Node `number`, read through `cache` when there is one (the node caches of
    /// §5.7 hold the view-invariant nodes: `hint` carries the node's level and its DoV
    /// in the current cell), else from its page. A page read is counted by the store.
    pub fn node_through(
        &self,
        store: &Store,
        cache: Option<&BufferPool<'_>>,
        number: u32,
        hint: &Hint,
    ) -> Result<HNode> {
        let head = self.head(store)?;
        if number >= head.nodes {
            return Err(Error::Invalid(format!(
                "HDoV node {number} of a tree of {} nodes",
                head.nodes
            )));
        }
        let page = head.first_node + number as u64;
        let mut b = Vec::new();
        match cache {
            Some(c) => c.get(page, PageKind::HdovNode, hint, &mut b)?,
            None => store.read_page_into(page, PageKind::HdovNode, &mut b)?,
        }
        let node = HNode::decode(&b, head.nodes).map_err(|e| self.corrupt(store, page, e))?;
        if node.number != number {
            return Err(self.corrupt(
                store,
                page,
                format!("the page of node {number} holds node {}", node.number),
            ));
        }
        Ok(node)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heads_round_trip_and_damage_is_named() {
        let head = TreeHead {
            first_node: 40,
            nodes: 9,
            height: 2,
            fanout: 73,
            objects: 600,
            vpage_len: 584,
            seconds: 1.5,
            lod_pages: 12,
            visible_nodes: 200,
            schemes: vec![(Scheme::Vertical, Extent::default())],
            cells: vec![3, 7, 8],
            proxy_errors: ProxyErrors::Hausdorff,
        };
        let b = head.encode();
        assert_eq!(TreeHead::decode(&b).unwrap(), head);
        // A version-1 head, whose proxies' errors are quadric, says so.
        let old = TreeHead {
            proxy_errors: ProxyErrors::Quadric,
            ..head.clone()
        };
        assert_eq!(u32_at(&old.encode(), 4), 1);
        assert_eq!(TreeHead::decode(&old.encode()).unwrap(), old);
        let mut future = b.clone();
        future[4..8].copy_from_slice(&3u32.to_le_bytes());
        crate::store::framing::reseal(&mut future);
        assert!(TreeHead::decode(&future).unwrap_err().contains("version 3"));
        assert_eq!(head.slot(7), Some(1));
        assert_eq!(head.slot(4), None);
        let mut bad = b.clone();
        bad[20] ^= 1;
        assert!(TreeHead::decode(&bad).unwrap_err().contains("checksum"));
        assert!(TreeHead::decode(&b[..b.len() - 4])
            .unwrap_err()
            .contains("takes"));
    }
}
