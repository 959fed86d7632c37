//! The scene tree's traversals (Shou 2002 §6.1, §6.3): what a frame draws, node by node
//! and at which representation, each culling nodes outside the view frustum.
//!
//! - **CONV**, the baseline: the same hierarchy with view frustum culling only, every
//!   object in view at full detail.
//! - **VSC(η)** (§6.1.1): the disk search's rule in memory. A node of DoV 0 is culled;
//!   a leaf is drawn at the detail of eq. 5.6; an internal node stops at its internal
//!   LOD (detail by eq. 5.5) when DoV ≤ η and h(1 + log₂ s) < log₂ NVO.
//! - **PB(n)** (§6.1.2, Fig. 6.2): a polygon budget of n triangles handed down the tree,
//!   children in descending DoV, child i getting B·(dᵢ/D)·k with k the share of the
//!   budget still left; a node's representation is the one of about
//!   min(λ·finest + (1 − λ)·coarsest, Bᵢ) triangles, λ = min(DoV/MAXDOV, 1). A leaf that
//!   does not fit what is left is dropped and its parent retreats to its own
//!   representation instead of its children's; after [`MAX_ATTEMPTS`] retreats that do
//!   not fit in a row the traversal ends and draws what is active.
//!
//! **Ours, beside the thesis's** ([`traverse_screened`] with a [`ScreenView`], the walks'
//! default; `hdov::Selection`): the thesis's internal LODs carry no error bound and
//! eq. 5.6 ignores the screen. Under ours a representation's stored error ε (metres,
//! [`SceneErrors`]) is held to the LOD threshold τ from the eye, ε < 2τ·tan(α)·d with d
//! the distance from the eye to the node's box (the criterion of `lod::level_for`; the
//! eye rather than its viewcell, since the traversal runs every frame):
//! - VSC: an internal node stops at its internal LOD only where the thesis's rule allows
//!   it **and** one of its internal LODs passes, drawn at the finer of eq. 5.5's level
//!   and the coarsest that passes; a leaf at the finer of eq. 5.6's level and the
//!   coarsest of its object's levels that passes (its full mesh when none does).
//! - PB: the budget spent by the screen, not by DoV shares ([`pb_by_screen`]): every
//!   visible object in the frustum at the coarsest of its levels that passes τ′, τ′ the
//!   smallest of τ, τ·2^¼, τ·2^½, … under which the frame fits the budget. Shares by DoV
//!   left a far façade of small DoV a share under its coarsest level and most of the
//!   budget unspent (PB(20,000) drew 11,692 triangles a frame at 23.1 dB on the
//!   3,000-object city). Where even every object's coarsest level overdraws, the thesis's
//!   traversal, each representation no coarser than the one that passes τ where the
//!   node's share holds it, so that the budget still bounds the frame.
//! A representation whose error is not known never passes.
//!
//! Choices the thesis leaves open, named: a representation "of about" t triangles is
//! the finest with at most t (the coarsest when none has so few); a retreat undoes what
//! the node's children had chosen (they are not drawn beside it); a node culled by the
//! frustum or by DoV 0 succeeds with nothing; MAX_ATTEMPTS is 8. When the attempts run
//! out, §6.1.2's text has "all the current active LODs are rendered", while Fig. 6.2 and
//! §6.3 also draw the node that did not fit, over the budget: we follow the text, so
//! that the budget bounds every frame (with Fig. 6.2's reading, 23 % of the demo city's
//! frames went over a budget of 20,000 by up to 1.5 %). A larger MAX_ATTEMPTS is worse:
//! each failed retreat undoes a larger subtree, and at 128 PB(20000) drew the root's
//! coarsest LOD, 177 triangles, on most frames.

use glam::Vec3;

use super::tree::{SceneNode, SceneTree};
use crate::database::Database;
use crate::error::{Error, Result};
use crate::geom::{Aabb, Frustum};
use crate::hdov::{level_for_detail, stops, ScreenTest, MAXDOV};

/// Retreats to a parent's representation that do not fit, in a row, before PB ends its
/// traversal (the thesis's MAX_ATTEMPTS, whose value it does not give).
pub const MAX_ATTEMPTS: u32 = 8;

/// How the scene tree is traversed.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum Traversal {
    /// CONV: view frustum culling only, every object at full detail.
    Conv,
    /// VSC(η): visibility simplification culling under the DoV threshold η.
    Vsc {
        /// The DoV threshold.
        eta: f32,
    },
    /// PB(n): a polygon budget of n triangles a frame.
    Pb {
        /// The budget, triangles.
        budget: u64,
    },
}

impl Traversal {
    /// The traversal's name as the thesis writes it: CONV, VSC(η), PB(n).
    pub fn label(&self) -> String {
        match self {
            Traversal::Conv => "CONV".into(),
            Traversal::Vsc { eta } => format!("VSC({eta})"),
            Traversal::Pb { budget } => format!("PB({budget})"),
        }
    }

    /// Checks its parameter, naming a bad one.
    pub fn validate(&self) -> Result<()> {
        match *self {
            Traversal::Vsc { eta } if !(eta.is_finite() && eta >= 0.0) => Err(Error::Invalid(
                format!("a DoV threshold η of {eta}: give a number ≥ 0"),
            )),
            Traversal::Pb { budget: 0 } => Err(Error::Invalid(
                "a polygon budget of 0 triangles draws nothing: give more".into(),
            )),
            _ => Ok(()),
        }
    }
}

/// A node drawn: at which of its representations, and its triangles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Active {
    /// The node, an index into [`SceneTree::nodes`].
    pub node: u32,
    /// Its representation: 0 its finest.
    pub level: usize,
    /// That representation's triangles.
    pub triangles: u32,
}

/// What a traversal chose, and what it cost.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Traversed {
    /// The nodes drawn, in the order visited.
    pub active: Vec<Active>,
    /// Nodes visited (Table 6.1's "Nodes").
    pub visited: usize,
    /// Triangles of the nodes drawn.
    pub triangles: u64,
    /// PB: nodes dropped for want of budget.
    pub dropped: usize,
    /// PB: the traversal ran out of attempts and ended, drawing what was active.
    pub ended: bool,
    /// PB: an object whose coarsest representation alone is over the whole budget (its
    /// id and triangles), when the frame met one.
    pub too_big: Option<(u64, u32)>,
}

/// The stored errors of each scene node's representations, metres, finest first: a
/// leaf's its object's stored levels' (0 for its full mesh), an internal node's its
/// internal LODs'. Empty where not known (an object without LOD data, or a tree whose
/// internal LODs keep no error): such a representation never passes the screen test.
#[derive(Clone, Debug, Default)]
pub struct SceneErrors {
    nodes: Vec<Vec<f32>>,
}

impl SceneErrors {
    /// The errors of `tree`'s nodes: its leaves' read from `db`'s LOD directories (a
    /// page or two an object, once), its internal nodes' those their internal LODs were
    /// made with ([`SceneNode::errors`](super::SceneNode::errors)). An error names an
    /// object whose LOD data cannot be read.
    pub fn load(db: &Database, tree: &SceneTree) -> Result<SceneErrors> {
        let mut nodes = Vec::with_capacity(tree.nodes.len());
        for n in &tree.nodes {
            let errors = match n.object {
                Some(id) => match db.lod_entry(id)? {
                    Some(e) if e.levels > 0 => {
                        let levels = crate::lod::stored::levels(db.store(), &e)?;
                        let errors: Vec<f32> = levels.iter().map(|l| l.error).collect();
                        // Only errors that describe the node's own representations.
                        match errors.len() == n.triangles.len() {
                            true => errors,
                            false => Vec::new(),
                        }
                    }
                    _ if n.triangles.len() == 1 => vec![0.0],
                    _ => Vec::new(),
                },
                None if n.errors.len() == n.triangles.len() => n.errors.clone(),
                None => Vec::new(),
            };
            nodes.push(errors);
        }
        Ok(SceneErrors { nodes })
    }

    /// Node `k`'s representations' errors (empty where not known).
    pub fn of(&self, k: u32) -> &[f32] {
        self.nodes.get(k as usize).map_or(&[], |e| e.as_slice())
    }

    /// Sets node `k`'s errors (a tree whose internal LODs carry them, or a test).
    pub fn set(&mut self, k: u32, errors: Vec<f32>) {
        if self.nodes.len() <= k as usize {
            self.nodes.resize(k as usize + 1, Vec::new());
        }
        self.nodes[k as usize] = errors;
    }
}

/// What the screen rule holds a traversal to (ours): the eye, the view's vertical field
/// of view (radians), τ (a fraction of the viewport) and the nodes' errors.
#[derive(Clone, Copy, Debug)]
pub struct ScreenView<'e> {
    /// Where the eye is.
    pub eye: Vec3,
    /// The vertical field of view, radians.
    pub fov_y: f32,
    /// The LOD threshold τ, a fraction of the viewport.
    pub tau: f32,
    /// The nodes' representations' errors.
    pub errors: &'e SceneErrors,
}

impl ScreenView<'_> {
    /// The coarsest of node `k`'s representations whose error passes from the eye;
    /// `None` when none does.
    fn fit(&self, k: u32, bounds: &Aabb) -> Option<usize> {
        let test = ScreenTest {
            from: Aabb {
                min: self.eye,
                max: self.eye,
            },
            fov_y: self.fov_y,
            tau: self.tau,
        };
        test.coarsest_fit(self.errors.of(k), bounds)
    }
}

/// Traverses `tree` as `how` says for a view of `frustum`, by the thesis's rules. VSC and
/// PB use the VDs of the tree's current cell.
pub fn traverse(tree: &SceneTree, how: Traversal, frustum: &Frustum) -> Result<Traversed> {
    traverse_screened(tree, how, frustum, None)
}

/// [`traverse`], VSC and PB holding representations to the screen rule of `screen`
/// (ours) when given; `None` is the thesis's traversal.
pub fn traverse_screened(
    tree: &SceneTree,
    how: Traversal,
    frustum: &Frustum,
    screen: Option<&ScreenView<'_>>,
) -> Result<Traversed> {
    how.validate()?;
    if let Some(v) = screen.filter(|v| !(0.0..1.0).contains(&v.tau)) {
        return Err(Error::Invalid(format!(
            "LOD threshold τ = {}: give a fraction of the viewport within [0, 1)",
            v.tau
        )));
    }
    let mut out = Traversed::default();
    match how {
        Traversal::Conv => conv(tree, 0, frustum, &mut out),
        Traversal::Vsc { eta } => vsc(tree, 0, eta, frustum, screen, &mut out),
        Traversal::Pb { budget }
            if screen.is_some_and(|v| pb_by_screen(tree, budget, frustum, v, &mut out)) => {}
        Traversal::Pb { budget } => {
            out = Traversed::default();
            let mut pb = Budget {
                tree,
                frustum,
                screen,
                initial: budget as f64,
                remaining: budget as f64,
                attempts: 0,
                ended: false,
                out: &mut out,
            };
            pb.refine(0, budget as f64);
        }
    }
    out.triangles = out.active.iter().map(|a| a.triangles as u64).sum();
    Ok(out)
}

fn conv(tree: &SceneTree, k: u32, frustum: &Frustum, out: &mut Traversed) {
    out.visited += 1;
    let n = &tree.nodes[k as usize];
    if !frustum.overlaps_aabb(&n.bounds) {
        return;
    }
    match n.children {
        None => out.active.push(Active {
            node: k,
            level: 0,
            triangles: n.triangles.first().copied().unwrap_or(0),
        }),
        Some([a, b]) => {
            conv(tree, a, frustum, out);
            conv(tree, b, frustum, out);
        }
    }
}

fn vsc(
    tree: &SceneTree,
    k: u32,
    eta: f32,
    frustum: &Frustum,
    screen: Option<&ScreenView<'_>>,
    out: &mut Traversed,
) {
    out.visited += 1;
    let n = &tree.nodes[k as usize];
    if n.vd.dov <= 0.0 || !frustum.overlaps_aabb(&n.bounds) {
        return;
    }
    // Under the screen rule, the coarsest representation that passes (a leaf's full
    // mesh when none does; an internal node's internal LODs only where one does).
    let fit = screen.map(|v| v.fit(k, &n.bounds));
    match n.children {
        None => {
            let finest = fit.map(|f| f.unwrap_or(0));
            out.active
                .push(at_detail(k, n, (n.vd.dov / MAXDOV).min(1.0), finest))
        }
        Some(_)
            if !n.levels.is_empty()
                && stops(n.vd, eta, n.h, n.s, 2.0)
                && fit.is_none_or(|f| f.is_some()) =>
        {
            out.active
                .push(at_detail(k, n, (n.vd.dov / eta).min(1.0), fit.flatten()))
        }
        Some([a, b]) => {
            vsc(tree, a, eta, frustum, screen, out);
            vsc(tree, b, eta, frustum, screen, out);
        }
    }
}

/// Each step of τ′ in [`pb_by_screen`]: 2^¼.
pub const PB_TAU_STEP: f32 = 1.189_207_1;

/// PB's budget spent by the screen (ours): the visible leaves in `frustum` (DoV above 0
/// from the current cell), each at the coarsest of its levels whose error passes τ′ from
/// the eye (full detail where none does), τ′ the smallest of τ·[`PB_TAU_STEP`]^k under
/// which their triangles fit `budget`; what is drawn goes to `out`. False, with `out`
/// holding what was visited, when even every leaf's coarsest level overdraws.
fn pb_by_screen(
    tree: &SceneTree,
    budget: u64,
    frustum: &Frustum,
    view: &ScreenView<'_>,
    out: &mut Traversed,
) -> bool {
    let mut leaves = Vec::new();
    visible_leaves(tree, 0, frustum, out, &mut leaves);
    let coarsest: u64 = leaves
        .iter()
        .map(|&k| *tree.nodes[k as usize].triangles.last().unwrap_or(&0) as u64)
        .sum();
    if coarsest > budget {
        return false;
    }
    let mut tau = view.tau;
    loop {
        let v = ScreenView { tau, ..*view };
        let levels: Vec<usize> = leaves
            .iter()
            .map(|&k| v.fit(k, &tree.nodes[k as usize].bounds).unwrap_or(0))
            .collect();
        let total: u64 = leaves
            .iter()
            .zip(&levels)
            .map(|(&k, &l)| tree.nodes[k as usize].triangles[l] as u64)
            .sum();
        // Past τ′ = 1 every error that passes anything passes; the coarsest levels fit.
        let last = tau >= 1.0;
        if total <= budget || last {
            for (&k, level) in leaves.iter().zip(levels) {
                let n = &tree.nodes[k as usize];
                let level = if last { n.triangles.len() - 1 } else { level };
                out.active.push(Active {
                    node: k,
                    level,
                    triangles: n.triangles[level],
                });
            }
            return true;
        }
        // From τ = 0 (full detail), the ladder starts at 10⁻⁵ of the viewport.
        tau = (tau * PB_TAU_STEP).max(1e-5);
    }
}

/// The leaves below node `k` that are in `frustum` and visible from the current cell.
fn visible_leaves(
    tree: &SceneTree,
    k: u32,
    frustum: &Frustum,
    out: &mut Traversed,
    leaves: &mut Vec<u32>,
) {
    out.visited += 1;
    let n = &tree.nodes[k as usize];
    if n.vd.dov <= 0.0 || !frustum.overlaps_aabb(&n.bounds) {
        return;
    }
    match n.children {
        None if !n.triangles.is_empty() => leaves.push(k),
        None => {}
        Some([a, b]) => {
            visible_leaves(tree, a, frustum, out, leaves);
            visible_leaves(tree, b, frustum, out, leaves);
        }
    }
}

/// Node `k` at the level of `detail` (eqs. 5.5–5.6), or at `finest` where that is finer.
fn at_detail(k: u32, n: &SceneNode, detail: f32, finest: Option<usize>) -> Active {
    let by_detail = level_for_detail(&n.triangles, detail);
    let level = finest.map_or(by_detail, |f| by_detail.min(f));
    Active {
        node: k,
        level,
        triangles: n.triangles[level],
    }
}

/// The polygon budget traversal's state (Fig. 6.2).
struct Budget<'a> {
    tree: &'a SceneTree,
    frustum: &'a Frustum,
    screen: Option<&'a ScreenView<'a>>,
    initial: f64,
    remaining: f64,
    attempts: u32,
    ended: bool,
    out: &'a mut Traversed,
}

impl Budget<'_> {
    /// Fig. 6.2's Refine(node) with the node's share `budget`: whether it (or what it
    /// retreated to) fitted.
    fn refine(&mut self, k: u32, budget: f64) -> bool {
        if self.ended {
            return true;
        }
        self.out.visited += 1;
        let n = &self.tree.nodes[k as usize];
        if n.vd.dov <= 0.0 || !self.frustum.overlaps_aabb(&n.bounds) {
            return true;
        }
        // Under the screen rule, no coarser than what passes τ (the finest when none
        // does), where the share holds it.
        let floor = self.screen.map(|v| v.fit(k, &n.bounds).unwrap_or(0));
        let lod = lod_for_budget(n, budget, floor);
        let Some([a, b]) = n.children else {
            let (level, t) = lod.expect("a leaf has its object's mesh");
            if (t as f64) < self.remaining {
                self.take(k, level, t);
                return true;
            }
            self.out.dropped += 1;
            let coarsest = *n.triangles.last().expect("a leaf has levels");
            if coarsest as f64 > self.initial {
                self.out.too_big = Some((n.object.expect("a leaf"), coarsest));
            }
            return false;
        };
        let (mark, before) = (self.out.active.len(), self.remaining);
        let mut children = [a, b];
        let dov = |c: &u32| self.tree.nodes[*c as usize].vd.dov;
        if dov(&b) > dov(&a) {
            children.swap(0, 1);
        }
        let total = n.vd.dov as f64;
        let mut success = true;
        for c in children {
            let share = budget * dov(&c) as f64 / total * (self.remaining / self.initial);
            if !self.refine(c, share) {
                success = false;
            }
        }
        if success || self.ended {
            return true;
        }
        // A child overdrew: this node's own representation instead of its children's.
        self.out.active.truncate(mark);
        self.remaining = before;
        match lod {
            Some((level, t)) if (t as f64) < self.remaining => {
                self.take(k, level, t);
                self.attempts = 0;
                true
            }
            _ if self.attempts > MAX_ATTEMPTS => {
                self.out.ended = true;
                self.ended = true;
                true
            }
            _ => {
                self.out.dropped += 1;
                self.attempts += 1;
                false
            }
        }
    }

    fn take(&mut self, node: u32, level: usize, triangles: u32) {
        self.remaining -= triangles as f64;
        self.out.active.push(Active {
            node,
            level,
            triangles,
        });
    }
}

/// The representation of node `n` for a share `budget`: the finest with at most
/// min(λ·finest + (1 − λ)·coarsest, budget) triangles (the coarsest when none has so
/// few), λ = min(DoV/MAXDOV, 1); with a `floor` (the screen rule's level), at most
/// min(max(that, the floor's triangles), budget). `None` for a node without
/// representations.
fn lod_for_budget(n: &SceneNode, budget: f64, floor: Option<usize>) -> Option<(usize, u32)> {
    let (&finest, &coarsest) = (n.triangles.first()?, n.triangles.last()?);
    let lambda = (n.vd.dov / MAXDOV).min(1.0) as f64;
    let mut want = lambda * finest as f64 + (1.0 - lambda) * coarsest as f64;
    if let Some(&t) = floor.and_then(|f| n.triangles.get(f)) {
        want = want.max(t as f64);
    }
    let want = want.min(budget);
    let level = n
        .triangles
        .iter()
        .position(|&t| t as f64 <= want)
        .unwrap_or(n.triangles.len() - 1);
    Some((level, n.triangles[level]))
}
