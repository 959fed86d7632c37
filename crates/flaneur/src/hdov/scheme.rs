//! The three storage schemes of the HDoV-tree's view-variant part (Shou 2002 §5.4),
//! each one extent of `VPage` pages, written at build and read by the search.
//!
//! - **Horizontal** (§5.4.1, Fig. 5.6): every node has a V-page for every cell, found
//!   by position (node n, cell slot i at V-page n·C + i), a blank one where the node is
//!   not visible. A node's V-page costs one access; the storage is eq. 5.7.
//! - **Vertical** (§5.4.2, Fig. 5.7): a V-page-index of C segments, each of N_node
//!   V-page pointers (0 = nil: the subtree is not visible and is pruned), and only the
//!   visible nodes' V-pages, each cell's together in depth-first order so that a search
//!   reads them front to back. Entering a cell reads its segment (4·N_node bytes);
//!   storage eq. 5.8.
//! - **Indexed-vertical** (§5.4.3, Fig. 5.8): the segments keep only the visible
//!   nodes' (node, pointer) pairs, so they vary in length; a directory of C (offset,
//!   count) records finds them. Entering a cell reads its pairs; storage eq. 5.9.
//!
//! ```text
//! head (every scheme)
//!   0  magic       b"FLVP"
//!   4  version     u32, SCHEME_VERSION
//!   8  scheme      u32: 0 horizontal, 1 vertical, 2 indexed-vertical
//!  12  cells       u32, C
//!  16  nodes       u32, N_node
//!  20  V-page len  u32, bytes
//!  24  V-pages at  u64, offset of the first V-page in the extent
//!  32  V-pages     u64, how many are stored
//!  40  crc32       of the bytes before it
//! then
//!   horizontal:  V-pages, N_node · C of them, node-major
//!   vertical:    C segments of N_node u32 (V-page number + 1; 0 = nil), V-pages
//!   indexed:     C directory records (offset u64 of the cell's pairs from the
//!                extent's start, count u32), the pairs (node u32, V-page number u32,
//!                nodes ascending), V-pages
//! ```
//!
//! Pointers are V-page numbers (u32), not byte addresses: the size of a pointer in
//! eqs. 5.8–5.9 is 4 bytes here, as is the integer.

use crate::error::{Error, Result};
use crate::store::framing::{push_crc, u32_at, u64_at, CRC_LEN};
use crate::store::{Extent, PageKind, Store};

use super::vd::{decode_vpage, encode_vpage, CellVd, Vd};

const MAGIC: [u8; 4] = *b"FLVP";
/// The scheme encoding this build writes and reads.
pub const SCHEME_VERSION: u32 = 1;
const HEAD_LEN: usize = 44;
const DIR_RECORD: usize = 12;
const PAIR: usize = 8;
/// Bytes of a V-page pointer and of an integer (the node number), as eqs. 5.8–5.9 use.
pub const POINTER_LEN: usize = 4;
pub const INTEGER_LEN: usize = 4;

/// How the V-pages are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub enum Scheme {
    /// Every node a V-page in every cell, found by position (§5.4.1).
    Horizontal,
    /// A V-page-index segment of every node per cell, nil for hidden nodes (§5.4.2).
    Vertical,
    /// Only the visible nodes' (node, pointer) pairs per cell (§5.4.3).
    Indexed,
}

impl Scheme {
    /// The three schemes, in the order of §5.4.
    pub const ALL: [Scheme; 3] = [Scheme::Horizontal, Scheme::Vertical, Scheme::Indexed];

    /// The name `flaneur build --hdov` takes.
    pub fn name(self) -> &'static str {
        match self {
            Scheme::Horizontal => "horizontal",
            Scheme::Vertical => "vertical",
            Scheme::Indexed => "indexed",
        }
    }

    fn code(self) -> u32 {
        self as u32
    }
}

impl std::str::FromStr for Scheme {
    type Err = Error;

    fn from_str(s: &str) -> Result<Scheme> {
        Scheme::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                Error::Invalid(format!(
                    "'{s}' is not an HDoV storage scheme: horizontal, vertical or indexed"
                ))
            })
    }
}

/// The shape every scheme is written for.
#[derive(Clone, Copy, Debug)]
pub struct Shape {
    pub cells: usize,
    pub nodes: usize,
    pub vpage_len: usize,
}

/// One scheme's bytes for `cells` (by slot, each cell's visible nodes).
pub fn encode(scheme: Scheme, shape: Shape, cells: &[CellVd]) -> Vec<u8> {
    let Shape {
        nodes, vpage_len, ..
    } = shape;
    let c = cells.len();
    let mut body = Vec::new();
    let mut vpages = Vec::new();
    let mut stored = 0u64;
    let mut push_vpage = |vds: &[Vd], vpages: &mut Vec<u8>| {
        vpages.extend_from_slice(&encode_vpage(vds, vpage_len));
        stored += 1;
        stored as u32
    };
    match scheme {
        Scheme::Horizontal => {
            let blank: Vec<Vd> = Vec::new();
            for n in 0..nodes as u32 {
                for cell in cells {
                    push_vpage(cell.get(&n).unwrap_or(&blank), &mut vpages);
                }
            }
        }
        Scheme::Vertical => {
            let mut index = vec![0u32; c * nodes];
            for (i, cell) in cells.iter().enumerate() {
                for (&n, vds) in cell {
                    index[i * nodes + n as usize] = push_vpage(vds, &mut vpages);
                }
            }
            index
                .iter()
                .for_each(|p| body.extend_from_slice(&p.to_le_bytes()));
        }
        Scheme::Indexed => {
            let pairs_at = HEAD_LEN + c * DIR_RECORD;
            let mut pairs = Vec::new();
            for cell in cells {
                body.extend_from_slice(&((pairs_at + pairs.len()) as u64).to_le_bytes());
                body.extend_from_slice(&(cell.len() as u32).to_le_bytes());
                for (&n, vds) in cell {
                    let p = push_vpage(vds, &mut vpages);
                    pairs.extend_from_slice(&n.to_le_bytes());
                    pairs.extend_from_slice(&p.to_le_bytes());
                }
            }
            body.extend_from_slice(&pairs);
        }
    }
    let mut out = Vec::with_capacity(HEAD_LEN + body.len() + vpages.len());
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&SCHEME_VERSION.to_le_bytes());
    out.extend_from_slice(&scheme.code().to_le_bytes());
    out.extend_from_slice(&(c as u32).to_le_bytes());
    out.extend_from_slice(&(nodes as u32).to_le_bytes());
    out.extend_from_slice(&(vpage_len as u32).to_le_bytes());
    out.extend_from_slice(&((HEAD_LEN + body.len()) as u64).to_le_bytes());
    out.extend_from_slice(&stored.to_le_bytes());
    push_crc(&mut out);
    debug_assert_eq!(out.len(), HEAD_LEN);
    out.extend_from_slice(&body);
    out.extend_from_slice(&vpages);
    out
}

/// A scheme in an open database: its extent and head.
#[derive(Clone, Debug)]
pub struct StoredScheme {
    pub scheme: Scheme,
    pub extent: Extent,
    shape: Shape,
    vpages_at: u64,
    /// V-pages stored.
    pub vpages: u64,
    objects: u64,
}

/// Where the search stands in one cell: the segment of the V-page-index read on
/// entering it.
#[derive(Clone, Debug)]
pub enum Entered {
    Horizontal { slot: usize },
    Vertical { pointers: Vec<u32> },
    Indexed { pairs: Vec<(u32, u32)> },
}

impl StoredScheme {
    /// Reads and checks the head of the scheme at `extent` (counted). `shape` is what
    /// the tree's head says; a head that disagrees is named.
    pub fn open(
        store: &Store,
        scheme: Scheme,
        extent: Extent,
        shape: Shape,
        objects: u64,
    ) -> Result<StoredScheme> {
        let corrupt = |what: String| Error::CorruptPage {
            path: store.path().to_path_buf(),
            page: extent.first_page,
            what: format!("HDoV {} scheme: {what}", scheme.name()),
        };
        if (extent.byte_len as usize) < HEAD_LEN {
            return Err(corrupt(format!("{} bytes hold no head", extent.byte_len)));
        }
        let b = store.read_extent_range(&extent, PageKind::VPage, 0, HEAD_LEN)?;
        if b[..4] != MAGIC || u32_at(&b, 4) != SCHEME_VERSION {
            return Err(corrupt("not a V-page extent of this version".into()));
        }
        let crc = u32_at(&b, HEAD_LEN - CRC_LEN);
        if crc32fast::hash(&b[..HEAD_LEN - CRC_LEN]) != crc {
            return Err(corrupt("the head's checksum does not match".into()));
        }
        let found = (
            u32_at(&b, 8),
            u32_at(&b, 12) as usize,
            u32_at(&b, 16) as usize,
            u32_at(&b, 20) as usize,
        );
        let want = (scheme.code(), shape.cells, shape.nodes, shape.vpage_len);
        if found != want {
            return Err(corrupt(format!(
                "the head says (scheme, cells, nodes, V-page bytes) {found:?}, the tree {want:?}"
            )));
        }
        let (vpages_at, vpages) = (u64_at(&b, 24), u64_at(&b, 32));
        let end = vpages
            .checked_mul(shape.vpage_len as u64)
            .and_then(|v| v.checked_add(vpages_at));
        if end != Some(extent.byte_len as u64) {
            return Err(corrupt(format!(
                "{vpages} V-pages from byte {vpages_at} do not end the extent of {} bytes",
                extent.byte_len
            )));
        }
        Ok(StoredScheme {
            scheme,
            extent,
            shape,
            vpages_at,
            vpages,
            objects,
        })
    }

    fn corrupt(&self, store: &Store, at: usize, what: String) -> Error {
        Error::CorruptPage {
            path: store.path().to_path_buf(),
            page: self.extent.first_page + (at / store.payload_size()) as u64,
            what: format!("HDoV {} scheme: {what}", self.scheme.name()),
        }
    }

    /// Enters the cell at `slot`: reads what the scheme keeps per cell (nothing for
    /// horizontal, the cell's segment of the V-page-index otherwise). Counted.
    pub fn enter(&self, store: &Store, slot: usize) -> Result<Entered> {
        let Shape { cells, nodes, .. } = self.shape;
        if slot >= cells {
            return Err(Error::Invalid(format!(
                "cell slot {slot} of a tree of {cells} cells"
            )));
        }
        let read =
            |at: usize, len: usize| store.read_extent_range(&self.extent, PageKind::VPage, at, len);
        match self.scheme {
            Scheme::Horizontal => Ok(Entered::Horizontal { slot }),
            Scheme::Vertical => {
                let at = HEAD_LEN + slot * nodes * POINTER_LEN;
                let b = read(at, nodes * POINTER_LEN)?;
                let pointers: Vec<u32> = (0..nodes).map(|n| u32_at(&b, n * 4)).collect();
                if let Some(n) = pointers.iter().position(|&p| p as u64 > self.vpages) {
                    return Err(self.corrupt(
                        store,
                        at + n * 4,
                        format!("cell slot {slot}: node {n} points past the V-pages"),
                    ));
                }
                Ok(Entered::Vertical { pointers })
            }
            Scheme::Indexed => {
                let at = HEAD_LEN + slot * DIR_RECORD;
                let d = read(at, DIR_RECORD)?;
                let (offset, count) = (u64_at(&d, 0) as usize, u32_at(&d, 8) as usize);
                let fits = count <= nodes
                    && offset >= HEAD_LEN + cells * DIR_RECORD
                    && offset
                        .checked_add(count * PAIR)
                        .is_some_and(|end| end <= self.vpages_at as usize);
                if !fits {
                    return Err(self.corrupt(
                        store,
                        at,
                        format!("cell slot {slot}: {count} pairs at byte {offset} do not fit"),
                    ));
                }
                let b = read(offset, count * PAIR)?;
                let pairs: Vec<(u32, u32)> = (0..count)
                    .map(|k| (u32_at(&b, k * PAIR), u32_at(&b, k * PAIR + 4)))
                    .collect();
                let ordered = pairs.windows(2).all(|w| w[0].0 < w[1].0);
                let inside = pairs
                    .iter()
                    .all(|&(n, p)| (n as usize) < nodes && p >= 1 && p as u64 <= self.vpages);
                if !(ordered && inside) {
                    return Err(self.corrupt(
                        store,
                        offset,
                        format!(
                            "cell slot {slot}: its (node, V-page) pairs are out of order or range"
                        ),
                    ));
                }
                Ok(Entered::Indexed { pairs })
            }
        }
    }

    /// Node `node`'s V-entries in the cell entered (as many as a V-page holds, those
    /// past the node's entries blank), `None` when the node is not visible there. Reads
    /// its V-page (counted) unless the scheme's index says nil.
    pub fn vpage(&self, store: &Store, entered: &Entered, node: u32) -> Result<Option<Vec<Vd>>> {
        let entries = self.shape.vpage_len / super::vd::VENTRY_LEN;
        let number = match entered {
            Entered::Horizontal { slot } => {
                Some(node as u64 * self.shape.cells as u64 + *slot as u64 + 1)
            }
            Entered::Vertical { pointers } => pointers
                .get(node as usize)
                .copied()
                .filter(|&p| p != 0)
                .map(u64::from),
            Entered::Indexed { pairs } => pairs
                .binary_search_by_key(&node, |p| p.0)
                .ok()
                .map(|k| pairs[k].1 as u64),
        };
        let Some(number) = number else {
            return Ok(None);
        };
        let len = self.shape.vpage_len;
        let at = self.vpages_at as usize + (number as usize - 1) * len;
        let b = store.read_extent_range(&self.extent, PageKind::VPage, at, len)?;
        let vds = decode_vpage(&b, entries, self.objects)
            .map_err(|e| self.corrupt(store, at, format!("node {node}: {e}")))?;
        Ok(vds.iter().any(|v| v.dov > 0.0).then_some(vds))
    }
}

/// The storage eqs. 5.7–5.9 estimate for `shape` with `visible_nodes` (N_vnode summed
/// over the cells), bytes.
pub fn estimate(scheme: Scheme, shape: Shape, visible_nodes: u64) -> u64 {
    let (c, n, vp) = (
        shape.cells as u64,
        shape.nodes as u64,
        shape.vpage_len as u64,
    );
    match scheme {
        Scheme::Horizontal => vp * c * n,
        Scheme::Vertical => POINTER_LEN as u64 * n * c + vp * visible_nodes,
        Scheme::Indexed => (POINTER_LEN + INTEGER_LEN) as u64 * visible_nodes + vp * visible_nodes,
    }
}
