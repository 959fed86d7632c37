//! The visibility attributes of the DAG's nodes — Zheng 2007 §3.4: the radius of a
//! bounding sphere (§3.4.1), the sine of a normal cone's half-angle (§3.4.2) and the
//! approximation error (§3.4.3), each initialised from the node's own split and then
//! merged bottom-up from its children, with the formulas as the thesis writes them:
//!
//! - rad = max(|v_c − v_p|, |v_c − v_r|, |v_c − v_l|), then
//!   rad_i = max(rad_i, |v_c,i − v_c,d| + rad_d) for each child d;
//! - θ = min(π/2, max(δ_1, δ_2)), δ the angles between v_c's normal (the cone's axis)
//!   and the normals of f_l and f_r, then θ_i = max(θ_i, min(π/2, δ + θ_d)), δ the
//!   angle between the two axes; sin θ is stored (`cone_sin`), as the thesis does,
//!   since the back-face test reads only the sine;
//! - ap_err = the collapse's error, then ap_err_i = max(ap_err_i, ap_err_d).
//!
//! The sphere is centred on v_c and the cone anchored there, so neither centre nor axis
//! is stored: both are the first split's v_c position and normal.
//!
//! Choices the thesis leaves open, made here:
//! - A node of several splits (a run) is centred on their shared v_c position and
//!   takes the first split's normal as its axis; its initial radius and angle cover
//!   every split of the run, and its angle also the other wedges' normals, which differ
//!   from the axis across the crease.
//! - A degenerate f_l or f_r (no area, so no normal) adds nothing to the angle; a zero
//!   axis makes the cone a half-space (θ = π/2): such a node is never back-facing.
//! - The radius is rounded up to the next `f32`, so the stored sphere contains what the
//!   exact one does; merging uses the stored, rounded radii of the children.
//! - As in the thesis, the sphere bounds the positions the node and its descendants
//!   create or pivot on (v_c, v_p, v_l, v_r), not every corner of the adjusted
//!   triangles (those are the pivots' neighbours): the formulas stay the thesis's, so
//!   the run-time tests built on them behave as the thesis measured them.
//!
//! The merges are maxima along edges, and a redundant edge's term never exceeds the
//! one its longer path gives (triangle inequalities for distances and angles), so the
//! three constructions of one progressive mesh get the same attributes. The radius
//! merge adds a child's whole radius to the distance between the centres, so its slack
//! compounds toward the roots: conservative, but loose high in the hierarchy (the
//! attribute test in `dag::tests` prints by how much).

use std::f64::consts::FRAC_PI_2;

use glam::DVec3;

use super::build::{Csr, DagEdges};
use crate::error::{Error, Result};
use crate::lod::pm::{ProgressiveMesh, VertexSplit};

/// The visibility attributes of one DAG node (Zheng 2007 §3.4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeAttrs {
    /// The radius of the sphere about the node's v_c that bounds the region the node
    /// and all its descendants affect (metres).
    pub radius: f32,
    /// sin θ, θ ≤ π/2 the half-angle of the cone of normals about v_c's normal that
    /// bounds the normals of that region: 1 means the node is never back-facing.
    pub cone_sin: f32,
    /// The largest approximation error of the node and its descendants (metres):
    /// never smaller than a child's.
    pub error: f32,
}

pub(super) fn vec(p: [f32; 3]) -> DVec3 {
    DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

/// The angle between two directions; `None` when either is zero.
pub(super) fn angle(a: DVec3, b: DVec3) -> Option<f64> {
    let (a, b) = (a.try_normalize()?, b.try_normalize()?);
    // atan2 of |a × b| and a · b stays accurate at small angles, where acos does not.
    Some(a.cross(b).length().atan2(a.dot(b)))
}

/// The smallest `f32` not below `x` (x ≥ 0 and finite).
fn f32_up(x: f64) -> f32 {
    let r = x as f32;
    if (r as f64) < x {
        f32::from_bits(r.to_bits() + 1)
    } else {
        r
    }
}

impl DagEdges {
    /// The attributes of every node, merged bottom-up along these edges, for
    /// [`Dag::build`](super::Dag::build). An `Err` when a split of `pm` (the progressive
    /// mesh the edges were built from) carries a non-finite position, normal or error.
    pub fn attributes(&self, pm: &ProgressiveMesh) -> Result<Vec<NodeAttrs>> {
        attributes(pm, &self.run_starts, &self.children)
    }
}

/// The attributes of every node, given its runs and children.
fn attributes(pm: &ProgressiveMesh, run_starts: &[u32], children: &Csr) -> Result<Vec<NodeAttrs>> {
    let base_v = pm.base.positions.len();
    let position = |v: u32| -> DVec3 {
        let v = v as usize;
        vec(if v < base_v {
            pm.base.positions[v]
        } else {
            pm.splits[v - base_v].position
        })
    };
    let n = run_starts.len() - 1;
    let mut centre = Vec::with_capacity(n);
    let mut axis = Vec::with_capacity(n);
    let mut rad = Vec::with_capacity(n);
    let mut theta = Vec::with_capacity(n);
    let mut err = Vec::with_capacity(n);
    for w in run_starts.windows(2) {
        let run = &pm.splits[w[0] as usize..w[1] as usize];
        let head = &run[0];
        for (k, s) in run.iter().enumerate() {
            let finite = s.position.iter().chain(&s.normal).all(|c| c.is_finite());
            if !(finite && s.error >= 0.0 && s.error.is_finite()) {
                return Err(Error::Invalid(format!(
                    "LOD DAG: vertex split {}: a non-finite position, normal or error",
                    w[0] as usize + k
                )));
            }
        }
        let c = vec(head.position);
        let a = vec(head.normal);
        let (mut r, mut th, mut e) = (0.0f64, 0.0f64, 0.0f32);
        for s in run {
            let others = [Some(s.v_p), s.v_l, s.v_r];
            for v in others.into_iter().flatten() {
                r = r.max(c.distance(position(v)));
            }
            r = r.max(c.distance(vec(s.position)));
            th = th.max(initial_angle(a, s, &position));
            e = e.max(s.error);
        }
        centre.push(c);
        axis.push(a.try_normalize());
        rad.push(f32_up(r));
        theta.push(th.min(FRAC_PI_2));
        err.push(e);
    }
    // Children have larger numbers than their parents: one pass from the end sees
    // every child complete before its parents.
    for i in (0..n).rev() {
        for &d in children.row(i) {
            let d = d as usize;
            let r = centre[i].distance(centre[d]) + rad[d] as f64;
            if r > rad[i] as f64 {
                rad[i] = f32_up(r);
            }
            // A half-space cone cannot widen: skip the angle, the pass's costliest step.
            if theta[i] < FRAC_PI_2 {
                let spread = match (axis[i], axis[d]) {
                    (Some(a), Some(b)) => a.cross(b).length().atan2(a.dot(b)) + theta[d],
                    _ => FRAC_PI_2,
                };
                theta[i] = theta[i].max(spread.min(FRAC_PI_2));
            }
            err[i] = err[i].max(err[d]);
        }
    }
    Ok((0..n)
        .map(|i| NodeAttrs {
            radius: rad[i],
            cone_sin: if theta[i] >= FRAC_PI_2 {
                1.0
            } else {
                theta[i].sin() as f32
            },
            error: err[i],
        })
        .collect())
}

/// One split's share of θ before merging: the angles from the axis to its f_l and
/// f_r and to its own v_c normal (another wedge's, in a run).
fn initial_angle(axis: DVec3, s: &VertexSplit, position: &impl Fn(u32) -> DVec3) -> f64 {
    if axis.length_squared() == 0.0 {
        return FRAC_PI_2;
    }
    let (p, c) = (position(s.v_p), vec(s.position));
    let mut th = match angle(axis, vec(s.normal)) {
        Some(t) => t,
        None => return FRAC_PI_2,
    };
    // f_l = (v_p, v_c, v_l), f_r = (v_c, v_p, v_r), as the split winds them.
    let faces = [
        s.v_l.map(|l| (c - p).cross(position(l) - p)),
        s.v_r.map(|r| (p - c).cross(position(r) - c)),
    ];
    for n in faces.into_iter().flatten() {
        if let Some(delta) = angle(axis, n) {
            th = th.max(delta);
        }
    }
    th
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_up_never_shrinks() {
        for x in [0.0, 1e-9, 0.1, 1.0 / 3.0, 12345.678901234, 1e30] {
            assert!(f32_up(x) as f64 >= x, "{x}");
            assert!((f32_up(x) as f64 - x) <= x * 1.2e-7, "{x}");
        }
    }

    #[test]
    fn angles() {
        assert_eq!(angle(DVec3::Y, DVec3::ZERO), None);
        assert!((angle(DVec3::Y, DVec3::X).unwrap() - FRAC_PI_2).abs() < 1e-12);
        assert!(angle(DVec3::Y, DVec3::Y * 3.0).unwrap().abs() < 1e-12);
        let tiny = angle(DVec3::Y, DVec3::new(1e-9, 1.0, 0.0)).unwrap();
        assert!((tiny - 1e-9).abs() < 1e-15, "{tiny}");
    }
}
