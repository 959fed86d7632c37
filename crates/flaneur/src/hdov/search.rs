//! The HDoV-tree search (Shou 2002 §5.3, Fig. 5.4) for a viewcell and a DoV threshold
//! η, and the naive method it is measured against.
//!
//! From the root, each entry of a node read: DoV 0 prunes its branch; an object (an
//! entry of a leaf) is found with its detail by eq. 5.6; an internal entry stops at the
//! child's internal LOD when its DoV ≤ η **and** h(1 + log_M s) < log_M NVO (eq. 5.4,
//! h and s being the child's, kept in the entry), with its detail by eq. 5.5; otherwise
//! the search reads the child and goes on. With η = 0 it never stops above the leaves
//! and finds exactly the objects of the cell's PVS, as the naive method does.
//!
//! The details are weights in [0, 1] between the coarsest and the finest representation
//! (eq. 5.5: DoV/η for an internal LOD; eq. 5.6: min(DoV/MAXDOV, 1) for an object); the
//! level they pick is the loader's ([`level_for_detail`]), so that the search reads only
//! the tree and the V-pages, which is what the thesis's search I/O counts.

use super::node::HNodeKind;
use super::scheme::{Entered, StoredScheme};
use super::tree::HdovTree;
use super::vd::Vd;
use crate::cache::{BufferPool, Hint};
use crate::error::{Error, Result};
use crate::geom::Aabb;
use crate::rtree::ObjectEntry;
use crate::store::PageSource as _;
use crate::store::{Extent, Store};

/// The largest DoV an object seen from outside its box can have (half the sphere),
/// eq. 5.6's MAXDOV.
pub const MAXDOV: f32 = 0.5;

/// What the search found: an object, or a node drawn at one of its internal LODs.
#[derive(Clone, Debug, PartialEq)]
pub enum Found {
    /// An object, at the detail of eq. 5.6.
    Object {
        /// The object, as the index knows it.
        entry: ObjectEntry,
        /// Its DoV from the cell.
        dov: f32,
        /// Eq. 5.6's k: 1 draws it at full detail, 0 at its coarsest level.
        detail: f32,
    },
    /// A node, at one of its internal LODs (eq. 5.5).
    Node {
        /// The node's depth-first number, its box and its internal LODs (a chain).
        node: u32,
        /// The box of the objects below it.
        mbr: Aabb,
        /// Its internal LODs: an LOD chain.
        lods: Extent,
        /// Its DoV from the cell: the sum of its visible objects'.
        dov: f32,
        /// Visible objects below it.
        nvo: u32,
        /// Eq. 5.5's DoV/η: 1 draws its finest internal LOD, 0 its coarsest.
        detail: f32,
    },
}

impl Found {
    /// The DoV of what was found.
    pub fn dov(&self) -> f32 {
        match self {
            Found::Object { dov, .. } | Found::Node { dov, .. } => *dov,
        }
    }
}

/// A search's answer and what it read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SearchResult {
    /// What was found, in the order of the depth-first search.
    pub found: Vec<Found>,
    /// Nodes read (one page each) and V-pages read.
    pub nodes_read: u64,
    /// V-pages read.
    pub vpages_read: u64,
}

impl SearchResult {
    /// The objects found, at any detail.
    pub fn objects(&self) -> impl Iterator<Item = &ObjectEntry> {
        self.found.iter().filter_map(|f| match f {
            Found::Object { entry, .. } => Some(entry),
            Found::Node { .. } => None,
        })
    }

    /// Nodes found at an internal LOD.
    pub fn internal(&self) -> usize {
        self.found
            .iter()
            .filter(|f| matches!(f, Found::Node { .. }))
            .count()
    }
}

/// Whether the search stops at a child of `vd` (with h and s, in a tree of fan-out
/// `m`) rather than descending: eq. 5.4 under the threshold η.
pub fn stops(vd: Vd, eta: f32, h: f32, s: f32, m: f64) -> bool {
    if vd.dov > eta || vd.nvo == 0 {
        return false;
    }
    let log_m = |x: f64| x.ln() / m.ln();
    h as f64 * (1.0 + log_m(s as f64)) < log_m(vd.nvo as f64)
}

/// The level a representation of `detail` takes among levels of `triangles`, finest
/// (level 0) first: the coarsest level with at least the triangles interpolated
/// between the coarsest and the finest (eqs. 5.5–5.6 read in triangles).
pub fn level_for_detail(triangles: &[u32], detail: f32) -> usize {
    let (Some(&finest), Some(&coarsest)) = (triangles.first(), triangles.last()) else {
        return 0;
    };
    let k = detail.clamp(0.0, 1.0) as f64;
    let want = k * finest as f64 + (1.0 - k) * coarsest as f64;
    triangles
        .iter()
        .rposition(|&t| t as f64 >= want - 1e-6)
        .unwrap_or(0)
}

/// Searches the tree in the cell at `slot` under `eta`, reading V-pages through
/// `scheme` and nodes through `cache` when there is one (ending one of its searches
/// when done, so that DoV-Time's clock counts searches). An error names a damaged node
/// or V-page, or a tree whose V-pages disagree with themselves.
pub fn search(
    store: &Store,
    tree: &HdovTree,
    scheme: &StoredScheme,
    slot: usize,
    eta: f32,
    cache: Option<&BufferPool<'_>>,
) -> Result<SearchResult> {
    let found = search_in(store, tree, scheme, slot, eta, cache);
    if let Some(c) = cache {
        c.end_search();
    }
    found
}

fn search_in(
    store: &Store,
    tree: &HdovTree,
    scheme: &StoredScheme,
    slot: usize,
    eta: f32,
    cache: Option<&BufferPool<'_>>,
) -> Result<SearchResult> {
    if !(eta.is_finite() && eta >= 0.0) {
        return Err(Error::Invalid(format!(
            "a DoV threshold η of {eta}: give a number ≥ 0"
        )));
    }
    let head = tree.head(store)?;
    let (fanout, height) = (head.fanout as f64, head.height);
    let entered = scheme.enter(store, slot)?;
    let mut out = SearchResult::default();
    // The root's V-page first: a cache is told the root's DoV, the sum of its entries'.
    let Some(vds) = scheme.vpage(store, &entered, 0)? else {
        return Ok(out);
    };
    out.vpages_read += 1;
    let hint = Hint {
        level: height as u16 - 1,
        height,
        mbr: Aabb::EMPTY,
        dov: vds.iter().map(|v| v.dov).sum(),
    };
    let root = tree.node_through(store, cache, 0, &hint)?;
    out.nodes_read += 1;
    let walk = Walk {
        store,
        tree,
        scheme,
        entered: &entered,
        eta,
        fanout,
        height,
        cache,
    };
    walk.visit(root, &vds, &mut out)?;
    Ok(out)
}

/// One search's fixed parts, for its recursion.
struct Walk<'a> {
    store: &'a Store,
    tree: &'a HdovTree,
    scheme: &'a StoredScheme,
    entered: &'a Entered,
    eta: f32,
    fanout: f64,
    height: u32,
    cache: Option<&'a BufferPool<'a>>,
}

impl Walk<'_> {
    fn visit(&self, node: super::node::HNode, vds: &[Vd], out: &mut SearchResult) -> Result<()> {
        match node.kind {
            HNodeKind::Leaf(objects) => {
                for (o, vd) in objects.into_iter().zip(vds) {
                    if vd.dov > 0.0 {
                        out.found.push(Found::Object {
                            entry: o,
                            dov: vd.dov,
                            detail: (vd.dov / MAXDOV).min(1.0),
                        });
                    }
                }
            }
            HNodeKind::Internal { level, children } => {
                for (c, &vd) in children.iter().zip(vds) {
                    if vd.dov <= 0.0 {
                        continue;
                    }
                    if !c.lods.is_empty() && stops(vd, self.eta, c.h, c.s, self.fanout) {
                        out.found.push(Found::Node {
                            node: c.node,
                            mbr: c.mbr,
                            lods: c.lods,
                            dov: vd.dov,
                            nvo: vd.nvo,
                            detail: (vd.dov / self.eta).min(1.0),
                        });
                        continue;
                    }
                    let hint = Hint {
                        level: level - 1,
                        height: self.height,
                        mbr: c.mbr,
                        dov: vd.dov,
                    };
                    let child = self
                        .tree
                        .node_through(self.store, self.cache, c.node, &hint)?;
                    out.nodes_read += 1;
                    let Some(cvds) = self.scheme.vpage(self.store, self.entered, c.node)? else {
                        return Err(Error::Invalid(format!(
                            "{}: HDoV node {} has DoV {} in its parent's V-page but no visible entry of its own ({} scheme)",
                            self.store.path().display(),
                            c.node,
                            vd.dov,
                            self.scheme.scheme.name()
                        )));
                    };
                    out.vpages_read += 1;
                    self.visit(child, &cvds, out)?;
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stop_rule_is_eq_5_4_under_eta() {
        let m = 73.0;
        // Ten visible objects of DoV 1e-4 under a node of one level that keeps 1/20
        // of its children's faces: h(1 + log_M s) = 0.30, log_M 10 = 0.54.
        let vd = Vd {
            dov: 0.001,
            nvo: 10,
        };
        assert!(stops(vd, 0.002, 1.0, 0.05, m));
        // Above η, or with one visible object (log_M 1 = 0), it descends.
        assert!(!stops(vd, 0.0005, 1.0, 0.05, m));
        assert!(!stops(Vd { dov: 0.001, nvo: 1 }, 0.002, 1.0, 0.05, m));
        // η = 0 never stops at a visible node.
        assert!(!stops(vd, 0.0, 1.0, 0.05, m));
    }

    #[test]
    fn details_pick_levels_between_coarsest_and_finest() {
        let t = [1000, 400, 100, 20];
        assert_eq!(level_for_detail(&t, 1.0), 0);
        assert_eq!(level_for_detail(&t, 0.0), 3);
        // Half way is 510 triangles: level 0 is the coarsest with that many.
        assert_eq!(level_for_detail(&t, 0.5), 0);
        assert_eq!(level_for_detail(&t, 0.3), 1);
        assert_eq!(level_for_detail(&[50], 0.2), 0);
        assert_eq!(level_for_detail(&[], 0.2), 0);
    }
}
