//! The visibility attributes (Zheng 2007 §3.4) checked on built DAGs: a node's sphere,
//! cone and error must bound everything its descendants do, which only the finished
//! hierarchy shows.

use std::f64::consts::FRAC_PI_2;

use super::attrs::{angle, vec};
use super::{Dag, DagConstruction};
use crate::lod::fixtures::{building, random_patch};
use crate::lod::pm::ProgressiveMesh;

/// Every node's sphere holds the positions that it and its descendants split, pivot
/// on or create; its cone the normals of their v_c and of their f_l and f_r; its
/// error each of its splits' and children's.
/// Returns the nodes with a cone narrower than a half-space, and each node's stored
/// radius over the exact one (the farthest of those positions).
fn check_attrs(pm: &ProgressiveMesh, dag: &Dag) -> (usize, Vec<f64>) {
    let base_v = pm.base.positions.len();
    let position = |v: u32| {
        let v = v as usize;
        vec(if v < base_v {
            pm.base.positions[v]
        } else {
            pm.splits[v - base_v].position
        })
    };
    let mut narrow = 0;
    let mut slack = Vec::with_capacity(dag.node_count());
    let mut seen = vec![u32::MAX; dag.node_count()];
    for k in 0..dag.node_count() as u32 {
        let a = dag.attrs(k);
        let head = &pm.splits[dag.splits(k).start];
        let (c, axis) = (vec(head.position), vec(head.normal));
        for &d in dag.children(k) {
            assert!(
                dag.attrs(d).error <= a.error,
                "{k} → {d}: error grows downward"
            );
        }
        for i in dag.splits(k) {
            assert!(pm.splits[i].error <= a.error);
        }
        narrow += (a.cone_sin < 1.0) as usize;
        let mut exact = 0.0f64;
        let mut stack = vec![k];
        seen[k as usize] = k;
        while let Some(x) = stack.pop() {
            for i in dag.splits(x) {
                let s = &pm.splits[i];
                let corners = [Some(s.v_p), s.v_l, s.v_r]
                    .into_iter()
                    .flatten()
                    .map(position);
                for p in corners.chain([vec(s.position)]) {
                    let d = c.distance(p);
                    exact = exact.max(d);
                    assert!(
                        d <= a.radius as f64 * (1.0 + 1e-6),
                        "node {k}, split {i}: {d} > {}",
                        a.radius
                    );
                }
                if a.cone_sin < 1.0 {
                    let (p, q) = (position(s.v_p), vec(s.position));
                    let normals = [
                        Some(vec(s.normal)),
                        s.v_l.map(|l| (q - p).cross(position(l) - p)),
                        s.v_r.map(|r| (p - q).cross(position(r) - q)),
                    ];
                    for n in normals.into_iter().flatten() {
                        let Some(delta) = angle(axis, n) else {
                            continue;
                        };
                        assert!(
                            delta <= FRAC_PI_2 && delta.sin() <= a.cone_sin as f64 + 1e-6,
                            "node {k}, split {i}: a normal {delta} rad off the axis, sin θ = {}",
                            a.cone_sin
                        );
                    }
                }
            }
            for &d in dag.children(x) {
                if seen[d as usize] != k {
                    seen[d as usize] = k;
                    stack.push(d);
                }
            }
        }
        if exact > 0.0 {
            slack.push(a.radius as f64 / exact);
        }
    }
    (narrow, slack)
}

#[test]
fn spheres_cones_and_errors_bound_the_descendants() {
    let pm = ProgressiveMesh::build(&crate::scene::bunny()).unwrap();
    let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
    let (narrow, mut slack) = check_attrs(&pm, &dag);
    // Most of a smooth surface's nodes do have a cone narrower than a half-space.
    let nodes = dag.node_count();
    assert!(narrow * 2 > nodes, "{narrow} of {nodes}");
    // The thesis's merge adds each child's whole radius to the distance between
    // centres, so the slack compounds up the hierarchy; measured, not bounded.
    slack.sort_by(f64::total_cmp);
    let at = |q: f64| slack[((slack.len() - 1) as f64 * q) as usize];
    let (lo, hi) = crate::scene::bunny().bounds();
    eprintln!(
        "bunny: radius over the exact one: median {:.2}, 90 % {:.2}, max {:.2}; \
         {narrow} of {nodes} cones narrower than a half-space; root radius {:.1} m, \
         bounding-box diagonal {:.1} m",
        at(0.5),
        at(0.9),
        at(1.0),
        dag.attrs(dag.roots()[0]).radius,
        vec(hi).distance(vec(lo)),
    );
    let pm = ProgressiveMesh::build(&building()).unwrap();
    check_attrs(
        &pm,
        &Dag::build(&pm, DagConstruction::NonRedundant).unwrap(),
    );
    for seed in 0..6 {
        let pm = ProgressiveMesh::build(&random_patch(seed)).unwrap();
        check_attrs(
            &pm,
            &Dag::build(&pm, DagConstruction::MiniRedundant).unwrap(),
        );
    }
}
