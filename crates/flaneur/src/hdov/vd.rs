//! The view-variant part of the HDoV-tree for one viewcell: each entry's VD = (DoV,
//! NVO) (Shou 2002 §5.2.2, §5.3), aggregated bottom-up from the visibility table's
//! per-object DoVs (§5.5.3: a node's DoV is the sum of its children's, NVO the count of
//! visible objects below), and the V-page that holds one node's V-entries.
//!
//! ```text
//! V-page (fixed size: the tree's largest node × 8 bytes; V-entry k for entry k)
//!   8k+0  DoV  f32, ≥ 0, 0 for an entry nothing of which is visible
//!   8k+4  NVO  u32, visible objects below the entry (1 for a visible object)
//! ```
//!
//! A node is visible in a cell when one of its entries has a DoV above zero; only
//! visible nodes have V-entries worth storing, and every visible node has a visible
//! parent (attribute 3 of §5.2.2).

use std::collections::{BTreeMap, HashMap};

use crate::store::framing::{f32_at, u32_at};

/// Bytes of one V-entry.
pub const VENTRY_LEN: usize = 8;

/// One entry's view-variant data for a cell.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vd {
    /// Its DoV: the sum of the visible objects' below it (one object's for a leaf entry).
    pub dov: f32,
    /// Visible objects below (NVO).
    pub nvo: u32,
}

/// Where each node and object sits in the tree: what aggregation needs.
#[derive(Clone, Debug, Default)]
pub struct Topology {
    /// Per node (by number): its entries, and its parent node and entry, `None` for
    /// the root.
    pub entries: Vec<u16>,
    pub parent: Vec<Option<(u32, u16)>>,
    /// Per node, its level (0 for a leaf).
    pub level: Vec<u16>,
    /// Each object's leaf and entry.
    pub object: HashMap<u64, (u32, u16)>,
}

/// The visible nodes of one cell, by number, each with its V-entries.
pub type CellVd = BTreeMap<u32, Vec<Vd>>;

impl Topology {
    /// The VDs of a cell whose visible objects are `ids` with DoVs `dov` (the
    /// visibility table's record): sums up the tree, leaves first. An object the tree
    /// does not hold is named.
    pub fn aggregate(&self, ids: &[u64], dov: &[f32]) -> Result<CellVd, String> {
        let mut out = CellVd::new();
        for (id, &d) in ids.iter().zip(dov) {
            let &(leaf, slot) = self
                .object
                .get(id)
                .ok_or_else(|| format!("object {id} of the PVS is not in the HDoV-tree"))?;
            let vds = out
                .entry(leaf)
                .or_insert_with(|| vec![Vd::default(); self.entries[leaf as usize] as usize]);
            vds[slot as usize] = Vd {
                dov: vds[slot as usize].dov + d,
                nvo: vds[slot as usize].nvo + 1,
            };
        }
        // Each level's nodes hand their sums to their parents, from the leaves up.
        let top = self.level.iter().copied().max().unwrap_or(0);
        for level in 0..top {
            let at: Vec<u32> = out
                .keys()
                .copied()
                .filter(|&n| self.level[n as usize] == level)
                .collect();
            for n in at {
                let Some((parent, slot)) = self.parent[n as usize] else {
                    continue;
                };
                let (dov, nvo) = out[&n]
                    .iter()
                    .fold((0f64, 0u32), |(d, c), v| (d + v.dov as f64, c + v.nvo));
                let vds = out
                    .entry(parent)
                    .or_insert_with(|| vec![Vd::default(); self.entries[parent as usize] as usize]);
                vds[slot as usize] = Vd {
                    dov: dov as f32,
                    nvo,
                };
            }
        }
        Ok(out)
    }
}

/// One node's V-entries as a V-page of `len` bytes.
pub fn encode_vpage(vds: &[Vd], len: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity(len);
    for v in vds {
        out.extend_from_slice(&v.dov.to_le_bytes());
        out.extend_from_slice(&v.nvo.to_le_bytes());
    }
    out.resize(len, 0);
    out
}

/// The first `entries` V-entries of a V-page; the complaint names a bad one.
pub fn decode_vpage(b: &[u8], entries: usize, objects: u64) -> Result<Vec<Vd>, String> {
    if b.len() < entries * VENTRY_LEN {
        return Err(format!(
            "a V-page of {} bytes cannot hold {entries} V-entries",
            b.len()
        ));
    }
    (0..entries)
        .map(|k| {
            let v = Vd {
                dov: f32_at(b, k * VENTRY_LEN),
                nvo: u32_at(b, k * VENTRY_LEN + 4),
            };
            let sane = v.dov.is_finite()
                && v.dov >= 0.0
                && (v.nvo as u64) <= objects
                && (v.dov > 0.0) == (v.nvo > 0);
            if sane {
                Ok(v)
            } else {
                Err(format!(
                    "V-entry {k} holds DoV {} and NVO {}, not a visible part of a tree of {objects} objects",
                    v.dov, v.nvo
                ))
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A root (node 0) over two leaves (1 and 2) of two objects each.
    fn small() -> Topology {
        Topology {
            entries: vec![2, 2, 2],
            parent: vec![None, Some((0, 0)), Some((0, 1))],
            level: vec![1, 0, 0],
            object: HashMap::from([(10, (1, 0)), (11, (1, 1)), (12, (2, 0)), (13, (2, 1))]),
        }
    }

    #[test]
    fn dovs_and_counts_sum_up_the_tree() {
        let vd = small()
            .aggregate(&[10, 11, 13], &[0.25, 0.125, 0.5])
            .unwrap();
        assert_eq!(vd.len(), 3);
        assert_eq!(vd[&0], [Vd { dov: 0.375, nvo: 2 }, Vd { dov: 0.5, nvo: 1 }]);
        assert_eq!(vd[&2], [Vd::default(), Vd { dov: 0.5, nvo: 1 }]);
        // A leaf nothing of which is seen has no V-entries, nor does a PVS of nothing.
        let vd = small().aggregate(&[12], &[0.01]).unwrap();
        assert_eq!(vd.keys().copied().collect::<Vec<_>>(), [0, 2]);
        assert!(small().aggregate(&[], &[]).unwrap().is_empty());
        let e = small().aggregate(&[99], &[0.1]).unwrap_err();
        assert!(e.contains("object 99"), "{e}");
    }

    #[test]
    fn vpages_round_trip_and_nonsense_is_named() {
        let vds = [Vd { dov: 0.5, nvo: 3 }, Vd::default()];
        let b = encode_vpage(&vds, 64);
        assert_eq!(b.len(), 64);
        assert_eq!(decode_vpage(&b, 2, 10).unwrap(), vds);
        let mut bad = b.clone();
        bad[4..8].copy_from_slice(&0u32.to_le_bytes());
        let e = decode_vpage(&bad, 2, 10).unwrap_err();
        assert!(e.contains("V-entry 0"), "{e}");
        let e = decode_vpage(&b, 2, 2).unwrap_err();
        assert!(e.contains("NVO 3"), "{e}");
    }
}
