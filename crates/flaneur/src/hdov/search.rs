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
//!
//! **Ours, beside the thesis's rule** ([`Selection::Screen`], the default of the walks;
//! [`Selection::Thesis`] keeps the rule above for the Table 5.3 reproduction): the thesis's
//! internal LODs carry no error bound and eq. 5.6 ignores the screen, which measured 14 dB
//! (η 0) to 23 dB (η 0.001) below the PVS walk's picture. Under ours a search also stops at
//! a node only where its finest internal LOD's stored error ε (metres) projects under the
//! LOD threshold τ from **anywhere in the viewcell**: ε < 2τ·tan(α)·d, the criterion of
//! [`lod::level_for`](crate::lod::level_for), with d the distance from the viewcell's box
//! (its eye heights widened by a kerb's step) to the node's box ([`ScreenTest`]). The
//! viewcell rather than the eye because a search answers for a cell and a walk keeps its
//! finds while the eye stays in it: a proxy fit for the cell's nearest point is fit for
//! every frame there. The error is read from the node's LOD directory (one page, once a
//! walk, [`NodeErrors`]): the node entry has no room for it, so these reads are counted
//! as model pages, not as the search's; a version-1 tree's errors are quadric errors, no
//! bound, and none of its internal LODs passes. The node is then drawn at the finer of eq. 5.5's
//! level and the coarsest whose error passes; an object at the finer of eq. 5.6's level
//! and its screen-space one (the walk's LOD selection, from the eye, frame by frame).

use std::collections::HashMap;
use std::sync::Mutex;

use super::node::HNodeKind;
use super::scheme::{Entered, StoredScheme};
use super::tree::{HdovTree, ProxyErrors};
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

/// Which rule picks what a VISUAL, VSC or PB walk draws, and at what detail.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Selection {
    /// Ours, the default: a node's internal LOD only where the thesis's rule allows it
    /// **and** its stored error projects under the LOD threshold τ ([`ScreenTest`]); an
    /// object at the finer of eq. 5.6's level and the screen-space one.
    #[default]
    Screen,
    /// The thesis's (§5.3, §6.1): a node's internal LOD wherever DoV ≤ η and eq. 5.4
    /// hold, an object at eq. 5.6's level whatever the screen says; for the Table 5.3
    /// and Table 6.1 reproductions.
    Thesis,
}

impl Selection {
    /// The names [`Selection::from_name`] takes.
    pub const NAMES: [&'static str; 2] = ["screen", "thesis"];

    /// Its name: `screen` or `thesis`.
    pub fn name(&self) -> &'static str {
        match self {
            Selection::Screen => "screen",
            Selection::Thesis => "thesis",
        }
    }

    /// The rule named `name` (`screen` or `thesis`); an error naming the choices.
    ///
    /// ```
    /// use flaneur::hdov::Selection;
    /// assert_eq!(Selection::from_name("thesis").unwrap(), Selection::Thesis);
    /// assert!(Selection::from_name("eyeball").is_err());
    /// ```
    pub fn from_name(name: &str) -> Result<Selection> {
        match name {
            "screen" => Ok(Selection::Screen),
            "thesis" => Ok(Selection::Thesis),
            _ => Err(Error::Invalid(format!(
                "a selection rule named {name:?}: give one of {}",
                Selection::NAMES.join(", ")
            ))),
        }
    }
}

impl std::str::FromStr for Selection {
    type Err = Error;

    fn from_str(s: &str) -> Result<Selection> {
        Selection::from_name(s)
    }
}

/// The distance between the nearest points of two boxes, 0 where they touch.
pub fn box_distance(a: &Aabb, b: &Aabb) -> f32 {
    (a.min - b.max)
        .max(b.min - a.max)
        .max(glam::Vec3::ZERO)
        .length()
}

/// The screen-space test of a representation's stored error, seen from anywhere in a
/// box (a viewcell; an eye is a box of no size): the criterion of
/// [`lod::level_for`](crate::lod::level_for), ε < 2τ·tan(α)·d, α half the vertical field
/// of view, d the distance between the boxes.
///
/// ```
/// use flaneur::geom::Aabb;
/// use flaneur::hdov::ScreenTest;
/// let cell = Aabb::new([0.0, 1.0, 0.0], [40.0, 2.0, 40.0]).unwrap();
/// let test = ScreenTest { from: cell, fov_y: 45f32.to_radians(), tau: 0.001 };
/// let far = Aabb::new([1040.0, 0.0, 0.0], [1100.0, 30.0, 40.0]).unwrap();
/// // 1,000 m away, 0.83 m projects under 0.1 % of the viewport; 2 m does not.
/// assert_eq!(test.coarsest_fit(&[0.5, 2.0], &far), Some(0));
/// assert_eq!(test.coarsest_fit(&[2.0, 8.0], &far), None);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenTest {
    /// Where the eye may be.
    pub from: Aabb,
    /// The vertical field of view, radians.
    pub fov_y: f32,
    /// τ, a fraction of the viewport.
    pub tau: f32,
}

impl ScreenTest {
    /// The largest error, metres, that projects under τ at `to` from anywhere in `from`.
    pub fn threshold(&self, to: &Aabb) -> f32 {
        2.0 * self.tau * (self.fov_y * 0.5).tan() * box_distance(&self.from, to)
    }

    /// The coarsest of the representations whose stored `errors` (metres, finest
    /// first) project under τ at `to`; `None` when none does. An error that is not a
    /// number ≥ 0 never passes.
    pub fn coarsest_fit(&self, errors: &[f32], to: &Aabb) -> Option<usize> {
        let t = self.threshold(to);
        errors.iter().rposition(|&e| e >= 0.0 && e < t)
    }
}

/// The stored errors of HDoV nodes' internal LODs (metres, finest first), each read
/// from its LOD directory the first time it is asked and kept: a walk's, shared by its
/// threads.
#[derive(Debug, Default)]
pub struct NodeErrors {
    known: Mutex<HashMap<u32, Vec<f32>>>,
    /// Nodes whose errors could not be read, with why, not yet taken.
    damaged: Mutex<Vec<(u32, Error)>>,
}

impl NodeErrors {
    /// Node `node`'s internal LODs' errors, read from the chain at `lods` the first
    /// time (one page, counted as an LOD page). An error names a damaged chain.
    pub(crate) fn of(&self, store: &Store, node: u32, lods: &Extent) -> Result<Vec<f32>> {
        let lock = || self.known.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(e) = lock().get(&node) {
            return Ok(e.clone());
        }
        let what = format!("internal LODs of HDoV node {node}");
        let levels = crate::lod::stored::chain_levels(store, lods, &what)?;
        let errors: Vec<f32> = levels.iter().map(|l| l.error).collect();
        lock().insert(node, errors.clone());
        Ok(errors)
    }

    /// Node `node`'s errors, when they have been read.
    pub fn known(&self, node: u32) -> Option<Vec<f32>> {
        let known = self.known.lock().unwrap_or_else(|p| p.into_inner());
        known.get(&node).cloned()
    }

    /// Node `node`'s errors could not be read: from now on it has none (its internal
    /// LODs never pass), and the damage waits to be taken.
    fn damage(&self, node: u32, e: Error) {
        let mut known = self.known.lock().unwrap_or_else(|p| p.into_inner());
        known.insert(node, Vec::new());
        let mut damaged = self.damaged.lock().unwrap_or_else(|p| p.into_inner());
        damaged.push((node, e));
    }

    /// The nodes whose errors a tolerant search could not read since the last call,
    /// with why (their objects were found instead).
    pub fn take_damaged(&self) -> Vec<(u32, Error)> {
        let mut damaged = self.damaged.lock().unwrap_or_else(|p| p.into_inner());
        std::mem::take(&mut *damaged)
    }
}

/// What a search under [`Selection::Screen`] holds nodes' internal LODs to: the test from
/// the viewcell, and the errors read so far.
#[derive(Clone, Copy, Debug)]
pub struct ScreenRule<'e> {
    /// The test, from the viewcell searched
    /// ([`visual::screen_test`](crate::walk::visual::screen_test)).
    pub test: ScreenTest,
    /// Where the nodes' errors are read and kept.
    pub errors: &'e NodeErrors,
    /// A node whose errors cannot be read (a damaged page) is searched past, its damage
    /// kept for [`NodeErrors::take_damaged`], rather than failing the search: for a
    /// viewer that walks on.
    pub tolerant: bool,
}

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
/// when done, so that DoV-Time's clock counts searches). Under `screen` (ours) a node's
/// internal LOD is used only where its stored error also passes the rule's test; `None`
/// is the thesis's search. An error names a damaged node or V-page, or a tree whose
/// V-pages disagree with themselves.
pub fn search(
    store: &Store,
    (tree, scheme): (&HdovTree, &StoredScheme),
    slot: usize,
    eta: f32,
    cache: Option<&BufferPool<'_>>,
    screen: Option<&ScreenRule<'_>>,
) -> Result<SearchResult> {
    let found = search_in(store, tree, scheme, slot, eta, cache, screen);
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
    screen: Option<&ScreenRule<'_>>,
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
        screen,
        bounded: head.proxy_errors == ProxyErrors::Hausdorff,
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
    screen: Option<&'a ScreenRule<'a>>,
    /// Whether the tree's stored errors are distances (a version-1 tree's are quadric
    /// errors, no bound: none of its internal LODs passes the screen rule).
    bounded: bool,
}

impl Walk<'_> {
    /// Whether node `node`'s internal LODs pass the screen rule, when there is one.
    fn fits(&self, node: u32, mbr: &Aabb, lods: &Extent) -> Result<bool> {
        let Some(rule) = self.screen else {
            return Ok(true);
        };
        if !self.bounded {
            return Ok(false);
        }
        let errors = match rule.errors.of(self.store, node, lods) {
            Ok(e) => e,
            Err(e) if rule.tolerant => {
                rule.errors.damage(node, e);
                return Ok(false);
            }
            Err(e) => return Err(e),
        };
        Ok(rule.test.coarsest_fit(&errors, mbr).is_some())
    }

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
                    if !c.lods.is_empty()
                        && stops(vd, self.eta, c.h, c.s, self.fanout)
                        && self.fits(c.node, &c.mbr, &c.lods)?
                    {
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
