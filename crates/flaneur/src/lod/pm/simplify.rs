//! The half-edge collapses that simplify a mesh into a progressive mesh (Zheng 2007
//! §2.1.1), ordered by the quadric error metric (Garland & Heckbert, §2.1.2), each
//! checked legal before it applies; `progressive` records them as vertex splits.
//!
//! The collapse of position c onto its neighbour p is taken cheapest first from a binary
//! heap that holds one entry per position: its best collapse. A collapse changes the
//! fans and quadrics of p and its neighbours only, so exactly those are re-evaluated; a
//! position whose best changed gets a new entry and a new version stamp, and entries
//! with an old stamp are dropped when popped (lazy invalidation). Every collapse is
//! checked when popped, so a stale or optimistic entry never applies an illegal one.
//! Ties break on position number: the same mesh gives the same progressive mesh on every
//! run. n collapses, each touching a bounded neighbourhood: O(n log n).
//!
//! A collapse c → p is legal when (choices the papers leave open are marked *):
//! - c's triangles form one manifold disk or half-disk, no triangle names a position
//!   twice, and the edge has one triangle (boundary) or two wound oppositely;
//! - the link condition holds: c and p share no neighbour but the pivots;
//! - *a boundary position moves only along the boundary (a boundary edge) — boundary
//!   edges also carry constraint planes in the quadrics, so a straight outline keeps its
//!   corners, and a step off a curved one costs its distance;
//! - *no wedge of c lies in both edge triangles with a different wedge of p in each
//!   (one split has one v_p, and could not restore both);
//! - no remaining triangle degenerates, duplicates another, or turns by more than 90°
//!   (fold-over, §2.1.1) — *neither from its normal before the collapse nor from its
//!   normal in the original mesh, so that no level folds over against the original;
//! - *the collapse does not remove a piece's last triangles: a mesh of disjoint pieces (a
//!   group of merged objects) keeps every piece, and pieces never merge, since a
//!   collapse follows an edge.
//!
//! Creases and seams (*): positions are welded (`topology`), and a collapse moves every
//! wedge (vertex) of c at once, so a crease can never open into a crack. A wedge on the
//! collapsing edge goes to the wedge of p in the same triangle, as in any half-edge
//! collapse; a wedge off the edge goes to the wedge of p nearest in normal. When that
//! wedge's normal differs (beyond `SEAM_COS`), or two wedges of c with different normals
//! merge, triangles take a normal from across a crease, and the collapse costs at least
//! its edge's length: a crease moves only along its own line until the feature it bounds
//! is smaller than the error, and then the feature goes. Locking every seam vertex would
//! have frozen citygen's buildings, where every corner is one; refusing such collapses
//! outright would have kept every box, window sill and ledge at every level.
//!
//! Normals (*): a half-edge collapse creates no vertex, so each surviving triangle takes
//! the normal of p's wedge it now uses; the quadric holds no normal term.
//!
//! Error (*): the quadric is weighted (`quadric`) and normalised by its total weight, so the
//! error of a collapse is the root of a weighted mean squared distance, in metres.
//! Ordering by that mean rather than the sum keeps large flat regions from being
//! preferred over small curved ones merely for their area, and on the bunny halves the
//! Hausdorff distance at 1 % of the triangles.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::DVec3;
use rayon::prelude::*;

use crate::scene::Mesh;

use super::quadric::Quadric;
use super::topology::{Adjacency, Fan};
use crate::error::Result;

/// The weight of a boundary edge's constraint plane per metre of edge, against a
/// triangle plane's weight of the root of its area: large, so that a boundary position's error is
/// mostly its distance off the outline.
const BOUNDARY_WEIGHT: f64 = 10.0;

/// Two wedges of one position count as one surface when their normals are within 1°.
/// A collapse that moves triangles onto a wedge of another surface — across a crease —
/// costs at least the length of its edge: the crease survives every level finer than
/// the feature it bounds.
const SEAM_COS: f64 = 0.999_85;

/// A new triangle is degenerate when the sine of its angle at the moved corner is below
/// this.
const MIN_SINE: f64 = 1e-6;

/// A position's best collapse as queued: ordered by error, then position, so that the
/// order never depends on the heap's internals.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Candidate {
    /// The error's f64 bits: for non-negative floats the bits order as the numbers do.
    error_bits: u64,
    c: u32,
    p: u32,
    stamp: u32,
}

/// A triangle on the collapsing edge.
#[derive(Clone, Copy, Debug)]
struct EdgeFace {
    face: u32,
    /// Wound p → c: the triangle the split recreates as f_l = (v_p, v_c, v_l).
    left: bool,
    pivot: u32,
}

/// Why a collapse is illegal: one reason per rule of the module comment.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Reject {
    /// c's triangles are not one manifold disk or half-disk.
    Fan,
    /// The edge has no triangle, more than two, or two wound alike.
    Edge,
    /// A boundary position would leave the boundary (or an interior one has a
    /// boundary edge, which a manifold fan rules out).
    Boundary,
    /// c and p share a neighbour other than the pivots.
    Link,
    /// A wedge of c lies in both edge triangles, with a different wedge of p in each.
    SplitWedge,
    /// The collapse would remove a piece's last triangles.
    LastTriangles,
    /// A triangle would lose its area.
    Degenerate,
    /// A triangle would turn by 90° or more.
    FoldOver,
    /// A triangle would turn by 90° or more from its original facing.
    FoldOverOriginal,
    /// A triangle would land on an existing one.
    Duplicate,
    /// A moved triangle would have an edge as long as the domain's limit.
    LongEdge,
}

/// A checked collapse, ready to apply.
#[derive(Clone, Debug)]
struct Plan {
    c: u32,
    p: u32,
    error: f64,
    edge: Vec<EdgeFace>,
    /// (wedge of c, wedge of p it goes to), by wedge of c.
    moves: Vec<(u32, u32)>,
}

/// f_l or f_r of a recorded collapse, in original numbers.
#[derive(Clone, Copy, Debug)]
pub(super) struct RemovedFace {
    pub face: u32,
    pub pivot: u32,
    pub corner: u8,
}

/// One wedge's collapse, in original numbers, in collapse order.
#[derive(Clone, Debug)]
pub(super) struct Collapse {
    pub v_c: u32,
    pub v_p: u32,
    pub left: Option<RemovedFace>,
    pub right: Option<RemovedFace>,
    pub adjusted: Vec<u32>,
    pub error: f32,
    pub group: u32,
}

/// What a simplifier starts from besides the mesh: its welded connectivity, each
/// position's quadric, the positions that never collapse, and the triangles' original
/// normals. The whole mesh's is computed once (`of`); a part of a mesh simplified on
/// its own (`parallel`) takes its share of the whole's.
pub(super) struct Setup {
    pub adj: Adjacency,
    pub quadrics: Vec<Quadric>,
    /// Positions that never collapse: a corner of a triangle that names a position twice.
    pub locked: Vec<bool>,
    /// Unit normals of the original triangles (zero for degenerate ones).
    pub face_normals: Vec<DVec3>,
}

impl Setup {
    pub(super) fn of(mesh: &Mesh) -> Setup {
        let adj = Adjacency::new(mesh);
        // The boundary's sort and the triangles' quadrics are apart until the end.
        let (boundary, faces) = rayon::join(
            || adj.boundary_edges(),
            || {
                (0..adj.faces.len() as u32)
                    .into_par_iter()
                    .map(|f| {
                        let [a, b, c] = adj.corner_coords(f);
                        let normal = (b - a).cross(c - a).normalize_or_zero();
                        (Quadric::triangle(a, b, c), normal)
                    })
                    .collect::<Vec<_>>()
            },
        );
        let np = adj.position_count();
        let mut quadrics = vec![Quadric::default(); np];
        let mut locked = vec![false; np];
        for (f, (q, _)) in faces.iter().enumerate() {
            let pinched = adj.is_pinched(f as u32);
            for p in adj.corner_positions(f as u32) {
                quadrics[p as usize] += *q;
                locked[p as usize] |= pinched;
            }
        }
        let face_normals: Vec<DVec3> = faces.into_iter().map(|(_, n)| n).collect();
        for (a, b, f) in boundary {
            let q = Quadric::boundary_edge(
                adj.coords[a as usize],
                adj.coords[b as usize],
                face_normals[f as usize],
                BOUNDARY_WEIGHT,
            );
            quadrics[a as usize] += q;
            quadrics[b as usize] += q;
        }
        Setup {
            adj,
            quadrics,
            locked,
            face_normals,
        }
    }
}

/// Which collapses a simplifier may make: c → p only where c is `free`, and only when
/// the edge and every edge the collapse makes are shorter than `max_edge`
/// (El-Sana & Varshney's rule for an octree cell, §3, extended to the edges made, so
/// that a cell's reach stays within `max_edge` of it).
pub(super) struct Domain {
    /// Per position; `None`: every position.
    pub free: Option<Vec<bool>>,
    pub max_edge: f64,
}

impl Domain {
    pub(super) fn everything() -> Domain {
        Domain {
            free: None,
            max_edge: f64::INFINITY,
        }
    }
}

pub(super) struct Simplifier {
    pub adj: Adjacency,
    pub quadrics: Vec<Quadric>,
    locked: Vec<bool>,
    free: Option<Vec<bool>>,
    max_edge_sq: f64,
    /// Each position's entry in the heap, and its version: an entry whose stamp is
    /// not its position's is stale.
    queued: Vec<Option<(u64, u32)>>,
    stamps: Vec<u32>,
    /// Unit normals of the original triangles (zero for degenerate ones).
    face_normals: Vec<DVec3>,
    /// Unit vertex normals (zero where the input's is zero).
    vertex_normals: Vec<DVec3>,
    heap: BinaryHeap<Reverse<Candidate>>,
    pub collapses: Vec<Collapse>,
    pub groups: u32,
    /// Buffers reused by every `queue`.
    fan: Fan,
    options: Vec<(u64, u32)>,
    /// Scratch marks for the link condition, valid where equal to `generation`.
    marks: Vec<u32>,
    generation: u32,
}

impl Simplifier {
    /// `mesh` gives the vertex normals; `setup` must be of the same mesh.
    pub(super) fn new(mesh: &Mesh, setup: Setup, domain: Domain) -> Simplifier {
        let Setup {
            adj,
            quadrics,
            locked,
            face_normals,
        } = setup;
        let np = adj.position_count();
        let vertex_normals = mesh
            .normals
            .iter()
            .map(|n| DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64).normalize_or_zero())
            .collect();
        Simplifier {
            adj,
            quadrics,
            locked,
            free: domain.free,
            max_edge_sq: domain.max_edge * domain.max_edge,
            queued: vec![None; np],
            stamps: vec![0; np],
            fan: Fan::default(),
            options: Vec::new(),
            face_normals,
            vertex_normals,
            heap: BinaryHeap::new(),
            collapses: Vec::new(),
            groups: 0,
            marks: vec![0; np],
            generation: 0,
        }
    }

    pub(super) fn run(&mut self) {
        for c in 0..self.adj.position_count() as u32 {
            self.queue(c, false);
        }
        while let Some(Reverse(cand)) = self.heap.pop() {
            let c = cand.c as usize;
            if cand.stamp != self.stamps[c] {
                continue;
            }
            // c's entry has left the heap.
            self.queued[c] = None;
            let mut fan = std::mem::take(&mut self.fan);
            let plan = match self.adj.fan_into(cand.c, &mut fan) {
                true => self.check(cand.c, cand.p, &fan),
                false => Err(Reject::Fan),
            };
            self.fan = fan;
            match plan {
                Ok(plan) if plan.error.to_bits() <= cand.error_bits => self.apply(plan),
                // Queued on its quadric alone, and dearer than that: back in line.
                Ok(plan) => self.push(cand.c, Some((plan.error.to_bits(), cand.p))),
                Err(_) => self.queue(cand.c, true),
            }
        }
    }

    /// Makes `best` position `c`'s entry in the heap, unless it already is.
    fn push(&mut self, c: u32, best: Option<(u64, u32)>) {
        let c_ = c as usize;
        if best == self.queued[c_] {
            return;
        }
        self.queued[c_] = best;
        self.stamps[c_] = self.stamps[c_].wrapping_add(1);
        if let Some((error_bits, p)) = best {
            self.heap.push(Reverse(Candidate {
                error_bits,
                c,
                p,
                stamp: self.stamps[c_],
            }));
        }
    }

    /// Queues position `c`'s cheapest collapse, if it has one.
    ///
    /// Checking legality is most of the work, and most cheapest collapses are legal, so
    /// between two single-wedge positions (where the quadric is the whole error) the
    /// cheapest is queued unchecked, and checked when it comes out of the heap; if it
    /// fails there, `c` is queued again with `checked`, every option checked.
    fn queue(&mut self, c: u32, checked: bool) {
        let mut fan = std::mem::take(&mut self.fan);
        let mut options = std::mem::take(&mut self.options);
        options.clear();
        let free = self.free.as_ref().is_none_or(|f| f[c as usize]);
        if free && !self.locked[c as usize] && self.adj.fan_into(c, &mut fan) {
            let coords = &self.adj.coords;
            let near =
                |p: u32| coords[c as usize].distance_squared(coords[p as usize]) < self.max_edge_sq;
            options.extend(
                fan.neighbours
                    .iter()
                    .filter(|&&p| !self.locked[p as usize] && near(p))
                    // A boundary position moves along the boundary only.
                    .filter(|&&p| fan.closed || p == fan.first || p == fan.last)
                    .map(|&p| (self.cost(c, p).to_bits(), p)),
            );
        }
        options.sort_unstable();
        let smooth_c = self.adj.wedges(c).len() == 1;
        // A plan's error is at least its quadric's, so once the quadric alone costs more
        // than the best plan found, nothing later can beat it.
        let mut best: Option<(u64, u32)> = None;
        for &option in &options {
            if best.is_some_and(|b| option >= b) {
                break;
            }
            let p = option.1;
            if !checked && smooth_c && self.adj.wedges(p).len() == 1 {
                best = Some(option);
            } else if let Ok(plan) = self.check(c, p, &fan) {
                let option = (plan.error.to_bits(), p);
                if best.is_none_or(|b| option < b) {
                    best = Some(option);
                }
            }
        }
        self.fan = fan;
        self.options = options;
        self.push(c, best);
    }

    /// The error of collapsing c onto p: both quadrics at p's position (m², ≥ 0).
    fn cost(&self, c: u32, p: u32) -> f64 {
        let e = (self.quadrics[c as usize] + self.quadrics[p as usize])
            .error(self.adj.coords[p as usize]);
        if e.is_finite() {
            e
        } else {
            f64::MAX
        }
    }

    /// The collapse c → p if it is legal (see the module comment), else why not.
    fn check(&mut self, c: u32, p: u32, fan: &Fan) -> Result<Plan, Reject> {
        let adj = &self.adj;
        let faces_c = &adj.face_lists[c as usize];
        let faces_p = &adj.face_lists[p as usize];

        let mut edge: Vec<EdgeFace> = Vec::with_capacity(2);
        for &f in faces_c {
            let ps = adj.corner_positions(f);
            if let Some(kp) = ps.iter().position(|&q| q == p) {
                let kc = ps.iter().position(|&q| q == c).ok_or(Reject::Fan)?;
                let pivot = ps[3 - kc - kp];
                edge.push(EdgeFace {
                    face: f,
                    left: (kp + 1) % 3 == kc,
                    pivot,
                });
            }
        }
        let boundary_edge = match edge.as_slice() {
            [_] => true,
            [a, b] if a.left != b.left => false,
            _ => return Err(Reject::Edge),
        };
        if boundary_edge == fan.closed {
            return Err(Reject::Boundary);
        }

        // The link condition: common neighbours are the pivots, and only they.
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            // Wrapped: old marks could pass for new ones.
            self.marks.fill(0);
            self.generation = 1;
        }
        let generation = self.generation;
        for &f in faces_p {
            for q in adj.corner_positions(f) {
                self.marks[q as usize] = generation;
            }
        }
        let is_pivot = |q: u32| edge.iter().any(|e| e.pivot == q);
        if fan
            .neighbours
            .iter()
            .any(|&q| q != p && self.marks[q as usize] == generation && !is_pivot(q))
        {
            return Err(Reject::Link);
        }

        // Never collapse a piece away.
        if faces_c.len() == edge.len() && faces_p.len() == edge.len() {
            return Err(Reject::LastTriangles);
        }

        let (moves, crosses) = self.wedge_moves(c, p, &edge)?;
        self.geometry(c, p, &edge)?;
        let mut error = self.cost(c, p);
        if crosses {
            error = error
                .max(self.adj.coords[c as usize].distance_squared(self.adj.coords[p as usize]));
        }
        Ok(Plan {
            c,
            p,
            error,
            edge,
            moves,
        })
    }

    /// Where each wedge of c goes, and whether some triangle must take a normal from
    /// across a crease (see `SEAM_COS`).
    fn wedge_moves(
        &self,
        c: u32,
        p: u32,
        edge: &[EdgeFace],
    ) -> Result<(Vec<(u32, u32)>, bool), Reject> {
        let adj = &self.adj;
        let wedge_at = |f: u32, q: u32| adj.faces[f as usize][adj.corner_at(f, q).unwrap_or(0)];
        let agree = |a: u32, b: u32| {
            self.vertex_normals[a as usize].dot(self.vertex_normals[b as usize]) >= SEAM_COS
        };
        let mut crosses = false;
        let mut moves: Vec<(u32, u32)> = Vec::with_capacity(2);
        for e in edge {
            let (cw, pw) = (wedge_at(e.face, c), wedge_at(e.face, p));
            match moves.iter_mut().find(|m| m.0 == cw) {
                // The edge's two triangles give one wedge of c two wedges of p: a crease
                // that ends at c. One split has one v_p, so it could not restore both.
                Some(m) if m.1 != pw => return Err(Reject::SplitWedge),
                Some(_) => {}
                None => moves.push((cw, pw)),
            }
        }
        if adj.wedges(c).len() == 1 && adj.wedges(p).len() == 1 {
            // A smooth position: the wedge was placed by the edge; nothing else moves.
            return Ok((moves, crosses));
        }
        let mut p_wedges: Vec<u32> = adj.face_lists[p as usize]
            .iter()
            .map(|&f| wedge_at(f, p))
            .collect();
        p_wedges.sort_unstable();
        p_wedges.dedup();
        for &f in &adj.face_lists[c as usize] {
            let cw = wedge_at(f, c);
            if moves.iter().any(|m| m.0 == cw) {
                continue;
            }
            let n = self.vertex_normals[cw as usize];
            // The wedge of p nearest in normal; the lowest index among equals.
            let best = p_wedges
                .iter()
                .map(|&pw| (n.dot(self.vertex_normals[pw as usize]), Reverse(pw)))
                .max_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
                .ok_or(Reject::Edge)?;
            crosses |= best.0 < SEAM_COS;
            moves.push((cw, best.1 .0));
        }
        for (i, a) in moves.iter().enumerate() {
            crosses |= moves[i + 1..]
                .iter()
                .any(|b| a.1 == b.1 && !agree(a.0, b.0));
        }
        moves.sort_unstable();
        Ok((moves, crosses))
    }

    /// Whether the triangles that move keep a shape and a facing, and stay distinct.
    fn geometry(&self, c: u32, p: u32, edge: &[EdgeFace]) -> Result<(), Reject> {
        let adj = &self.adj;
        let to = adj.coords[p as usize];
        for &f in &adj.face_lists[c as usize] {
            if edge.iter().any(|e| e.face == f) {
                continue;
            }
            let ps = adj.corner_positions(f);
            let k = ps.iter().position(|&q| q == c).ok_or(Reject::Fan)?;
            let mut pts = adj.corner_coords(f);
            let before = (pts[1] - pts[0]).cross(pts[2] - pts[0]);
            pts[k] = to;
            let (e1, e2) = (pts[(k + 1) % 3] - to, pts[(k + 2) % 3] - to);
            if e1.length_squared().max(e2.length_squared()) >= self.max_edge_sq {
                return Err(Reject::LongEdge);
            }
            let after = e1.cross(e2);
            if after.length() <= MIN_SINE * e1.length() * e2.length() {
                return Err(Reject::Degenerate);
            }
            if before.dot(after) <= 0.0 && before != DVec3::ZERO {
                return Err(Reject::FoldOver);
            }
            let original = self.face_normals[f as usize];
            if original.dot(after) <= 0.0 && original != DVec3::ZERO {
                return Err(Reject::FoldOverOriginal);
            }
            // Only a triangle across both pivots can land on an existing one.
            let (a, b) = (ps[(k + 1) % 3], ps[(k + 2) % 3]);
            let is_pivot = |q: u32| edge.iter().any(|e| e.pivot == q);
            if is_pivot(a) && is_pivot(b) {
                let duplicate = adj.face_lists[p as usize].iter().any(|&g| {
                    let qs = adj.corner_positions(g);
                    qs.contains(&a) && qs.contains(&b)
                });
                if duplicate {
                    return Err(Reject::Duplicate);
                }
            }
        }
        Ok(())
    }

    fn apply(&mut self, plan: Plan) {
        let Plan {
            c,
            p,
            error,
            edge,
            moves,
        } = plan;
        let group = self.groups;
        self.groups += 1;
        let faces_c = std::mem::take(&mut self.adj.face_lists[c as usize]);
        let moved: Vec<u32> = faces_c
            .iter()
            .copied()
            .filter(|f| edge.iter().all(|e| e.face != *f))
            .collect();

        for &(cw, pw) in &moves {
            let mut rec = Collapse {
                v_c: cw,
                v_p: pw,
                left: None,
                right: None,
                adjusted: Vec::new(),
                error: error.sqrt() as f32,
                group,
            };
            for e in &edge {
                let corners = self.adj.faces[e.face as usize];
                if !corners.contains(&cw) {
                    continue;
                }
                let k = corners.iter().position(|&v| v == pw).unwrap_or(0);
                let pivot = corners[3 - k - corners.iter().position(|&v| v == cw).unwrap_or(0)];
                let removed = Some(RemovedFace {
                    face: e.face,
                    pivot,
                    corner: k as u8,
                });
                if e.left {
                    rec.left = removed;
                } else {
                    rec.right = removed;
                }
            }
            rec.adjusted = moved
                .iter()
                .copied()
                .filter(|&f| self.adj.faces[f as usize].contains(&cw))
                .collect();
            self.collapses.push(rec);
        }

        for e in &edge {
            self.adj.alive[e.face as usize] = false;
        }
        for &f in &moved {
            for &(cw, pw) in &moves {
                self.adj.move_corner(f, cw, pw);
            }
        }
        let alive = &self.adj.alive;
        let lists = &mut self.adj.face_lists;
        lists[p as usize].retain(|&f| alive[f as usize]);
        lists[p as usize].extend_from_slice(&moved);
        for e in &edge {
            lists[e.pivot as usize].retain(|&f| alive[f as usize]);
        }
        let q = self.quadrics[c as usize];
        self.quadrics[p as usize] += q;

        // p and its neighbours are all whose fans, links or quadrics changed.
        let mut touched: Vec<u32> = self.adj.face_lists[p as usize]
            .iter()
            .flat_map(|&f| self.adj.corner_positions(f))
            .collect();
        // A pivot on a boundary can lose its last triangle with p.
        touched.extend(edge.iter().map(|e| e.pivot));
        touched.sort_unstable();
        touched.dedup();
        self.push(c, None);
        for &t in &touched {
            self.queue(t, false);
        }
    }
}
