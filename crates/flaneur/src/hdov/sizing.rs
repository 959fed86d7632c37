//! The V-page storage an HDoV-tree over a database's objects and visibility would take at
//! a given fan-out, without building it: the packing and each cell's VDs only, no internal
//! LODs and no nodes written. The schemes differ only in how many V-pages they store and
//! how they find them (§5.4, eqs. 5.7–5.9), and those follow from the nodes, the cells and
//! the visible nodes of each cell (N_vnode), which is what is computed here.
//!
//! The sizes are eqs. 5.7–5.9 for that shape, which are the bytes each scheme's encoding
//! writes for its V-pages and pointers, its head and directory of cells aside
//! ([`SchemeReport::estimate_bytes`](super::SchemeReport) beside what a build stored).

use super::build::{pack, preorder, topology};
use super::scheme::{estimate, Scheme, Shape};
use super::vd::VENTRY_LEN;
use crate::error::{Error, Result};
use crate::rtree::ObjectEntry;

/// The storage of an HDoV-tree at one fan-out.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FanoutSizes {
    /// Entries a node holds (M).
    pub fanout: u32,
    /// Nodes of the tree.
    pub nodes: u32,
    /// Levels of nodes.
    pub height: u32,
    /// Walkable viewcells.
    pub cells: u32,
    /// N_vnode summed over the cells.
    pub visible_nodes: u64,
    /// The V-page bytes of each scheme (eqs. 5.7–5.9), horizontal, vertical, indexed.
    pub schemes: Vec<(Scheme, u64)>,
}

impl FanoutSizes {
    /// The share of the tree's nodes a cell sees, over all cells.
    pub fn visible_share(&self) -> f64 {
        self.visible_nodes as f64 / (self.nodes as f64 * self.cells as f64).max(1.0)
    }

    /// `scheme`'s V-page bytes.
    pub fn bytes(&self, scheme: Scheme) -> u64 {
        self.schemes
            .iter()
            .find(|(k, _)| *k == scheme)
            .map_or(0, |(_, b)| *b)
    }

    /// `scheme`'s bytes over the horizontal scheme's.
    pub fn share_of_horizontal(&self, scheme: Scheme) -> f64 {
        self.bytes(scheme) as f64 / self.bytes(Scheme::Horizontal).max(1) as f64
    }
}

/// The storage at fan-out `fanout` of a tree over `objects`, whose cells (by id) have
/// the PVSs `pvs` returns (ids and DoVs).
pub(crate) fn sizes_at(
    objects: Vec<ObjectEntry>,
    cells: &[u32],
    fanout: u32,
    mut pvs: impl FnMut(u32) -> Result<(Vec<u64>, Vec<f32>)>,
) -> Result<FanoutSizes> {
    if fanout < 2 {
        return Err(Error::Invalid(format!(
            "HDoV fan-out {fanout} must be at least 2"
        )));
    }
    if objects.is_empty() {
        return Err(Error::Invalid("an HDoV-tree over no objects".into()));
    }
    let packed = pack(objects, fanout as usize);
    let order = preorder(&packed);
    let mut number = vec![0u32; packed.len()];
    for (k, &n) in order.iter().enumerate() {
        number[n] = k as u32;
    }
    let topology = topology(&packed, &number);
    let mut visible_nodes = 0u64;
    for &id in cells {
        let (ids, dov) = pvs(id)?;
        let vd = topology
            .aggregate(&ids, &dov)
            .map_err(|e| Error::Invalid(format!("viewcell {id}: {e}")))?;
        visible_nodes += vd.len() as u64;
    }
    let shape = Shape {
        cells: cells.len(),
        nodes: packed.len(),
        vpage_len: fanout as usize * VENTRY_LEN,
    };
    Ok(FanoutSizes {
        fanout,
        nodes: packed.len() as u32,
        height: packed.last().map_or(0, |root| root.level as u32 + 1),
        cells: cells.len() as u32,
        visible_nodes,
        schemes: Scheme::ALL
            .iter()
            .map(|&s| (s, estimate(s, shape, visible_nodes)))
            .collect(),
    })
}
