//! The symmetric Hausdorff distance between two triangle meshes, sampled as surface
//! comparison tools measure it: points spread over each mesh's surface by area, and
//! for each the distance to the nearest point of the other mesh's triangles, found
//! through a bounding volume hierarchy over those triangles. The sampled distance never
//! exceeds the true one, and reaches it as the samples grow dense.
//!
//! The samples are a fixed sequence (stratified by area, placed within a triangle by the
//! R2 low-discrepancy sequence), so the same meshes always give the same figure, and the
//! vertices of each mesh are always among them.
//!
//! Only the farthest sample counts, so a sample's search stops as soon as it finds a
//! triangle no farther than the farthest distance found so far (shared by all threads,
//! both ways): that sample cannot raise the maximum, and one that can is searched to its
//! end, from the triangle nearest the sample before (Taha and Hanbury's early break,
//! 2015, on the hierarchy's nearest-first search). The figure is the full search's
//! (exactly so on the bunny's levels against a search of every triangle, and on a
//! 3,000-object city's internal LODs; a nearest point on a box's very face could in
//! principle round a last bit otherwise).

use std::sync::atomic::{AtomicU32, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use crate::scene::Mesh;

use crate::error::{Error, Result};

/// The sampled symmetric Hausdorff distance between `a` and `b`, in the meshes' units:
/// the larger of the farthest any sample of `a` lies from `b` and the reverse. Each mesh
/// is sampled at `samples` points spread by area, plus its vertices.
///
/// An `Err` when either mesh fails `Mesh::validate` or has no triangles.
///
/// ```
/// let bunny = flaneur::scene::bunny();
/// let mut raised = bunny.clone();
/// raised.scale_translate(1.0, [0.0, 0.25, 0.0]);
/// let d = flaneur::lod::hausdorff(&bunny, &raised, 2_000)?;
/// assert!(d > 0.0 && d <= 0.25 + 1e-4);
/// // A point sampled inside a triangle is off it by rounding only.
/// assert!(flaneur::lod::hausdorff(&bunny, &bunny, 2_000)? < 1e-5);
/// # Ok::<(), flaneur::Error>(())
/// ```
pub fn hausdorff(a: &Mesh, b: &Mesh, samples: usize) -> Result<f32> {
    hausdorff_above(a, b, samples, 0.0)
}

/// `floor.max(hausdorff(a, b, samples))`, the same figure found sooner: a sample is
/// searched only until it is seen to lie within `floor` of the other mesh (callers that
/// keep the larger of several distances pass the largest so far). A `floor` that is not
/// a non-negative number counts as 0.
///
/// An `Err` when either mesh fails `Mesh::validate` or has no triangles.
pub(crate) fn hausdorff_above(a: &Mesh, b: &Mesh, samples: usize, floor: f32) -> Result<f32> {
    let (a, b) = rayon::join(|| Measured::new(a, "first"), || Measured::new(b, "second"));
    Ok(a?.hausdorff_above(&b?, samples, floor))
}

/// A mesh made ready to be measured against others, once for all of them: its
/// triangles' tree, the positions its triangles use and its sampler by area.
pub(crate) struct Measured<'a> {
    tree: TriangleTree<'a>,
    positions: Vec<[f32; 3]>,
    sampler: Sampler<'a>,
}

impl<'a> Measured<'a> {
    /// `mesh` made ready; `name` says which mesh it is in an error. An `Err` when it fails
    /// `Mesh::validate` or has no triangles.
    pub(crate) fn new(mesh: &'a Mesh, name: &str) -> Result<Measured<'a>> {
        mesh.validate()
            .map_err(|e| Error::Invalid(format!("Hausdorff distance, {name} mesh: {e}")))?;
        if mesh.indices.is_empty() {
            return Err(Error::Invalid(format!(
                "Hausdorff distance, {name} mesh: no triangles"
            )));
        }
        let (tree, (positions, sampler)) = rayon::join(
            || TriangleTree::new(mesh),
            || (used_positions(mesh), Sampler::new(mesh)),
        );
        Ok(Measured {
            tree,
            positions,
            sampler,
        })
    }

    /// Its triangles.
    pub(crate) fn triangle_count(&self) -> usize {
        self.tree.mesh.triangle_count()
    }

    /// `floor.max(hausdorff(self, other, samples))`, as [`hausdorff_above`].
    pub(crate) fn hausdorff_above(&self, other: &Measured<'_>, samples: usize, floor: f32) -> f32 {
        // f32::max drops a NaN; the bits of non-negative floats order as the numbers do.
        let farthest = Farthest(AtomicU32::new(floor.max(0.0).to_bits()));
        rayon::join(
            || self.one_sided(&other.tree, samples, &farthest),
            || other.one_sided(&self.tree, samples, &farthest),
        );
        farthest.get()
    }

    /// Raises `farthest` to the farthest that a sample of it lies from the triangles in
    /// `to`.
    fn one_sided(&self, to: &TriangleTree, samples: usize, farthest: &Farthest) {
        // Runs of a few hundred searches a task: a small mesh's are over in microseconds.
        const RUN: usize = 256;
        self.positions
            .par_iter()
            .with_min_len(RUN)
            .for_each_init(|| 0, |near, &p| farthest.offer(to, Vec3::from(p), near));
        (0..samples)
            .into_par_iter()
            .with_min_len(RUN)
            .filter_map(|j| self.sampler.sample(j, samples))
            .for_each_init(|| 0, |near, p| farthest.offer(to, p, near));
    }
}

/// The farthest distance of a sample from the other mesh found so far, shared by threads.
struct Farthest(AtomicU32);

impl Farthest {
    fn get(&self) -> f32 {
        f32::from_bits(self.0.load(Ordering::Relaxed))
    }

    /// Searches `p` against `to` and keeps its distance if it is farther; `near` is the
    /// triangle nearest the search before (samples come in runs over the surface).
    fn offer(&self, to: &TriangleTree, p: Vec3, near: &mut u32) {
        if let Some(d) = to.distance_beyond(p, self.get(), near) {
            self.0.fetch_max(d.to_bits(), Ordering::Relaxed);
        }
    }
}

/// The positions of the vertices that triangles use, each once: vertices split for
/// their normals share a position, and the distance from it.
fn used_positions(m: &Mesh) -> Vec<[f32; 3]> {
    let mut used = m.indices.clone();
    used.sort_unstable();
    used.dedup();
    let mut at: Vec<[u32; 3]> = used
        .into_iter()
        .map(|i| m.positions[i as usize].map(f32::to_bits))
        .collect();
    at.sort_unstable();
    at.dedup();
    at.into_iter().map(|p| p.map(f32::from_bits)).collect()
}

fn corners(m: &Mesh, t: usize) -> [Vec3; 3] {
    [0, 1, 2].map(|k| Vec3::from(m.positions[m.indices[3 * t + k] as usize]))
}

/// Points spread over a mesh's surface in proportion to area.
struct Sampler<'a> {
    mesh: &'a Mesh,
    /// The running total of triangle areas.
    cumulative: Vec<f64>,
}

impl<'a> Sampler<'a> {
    fn new(mesh: &'a Mesh) -> Sampler<'a> {
        let mut total = 0.0;
        let cumulative = (0..mesh.triangle_count())
            .map(|t| {
                let [a, b, c] = corners(mesh, t);
                total += 0.5 * (b - a).cross(c - a).length() as f64;
                total
            })
            .collect();
        Sampler { mesh, cumulative }
    }

    /// Sample `j` of `n`: the point at area (j + ½)/n of the total, placed inside its
    /// triangle by the R2 sequence. `None` when the mesh has no area.
    fn sample(&self, j: usize, n: usize) -> Option<Vec3> {
        let total = *self.cumulative.last()?;
        if total <= 0.0 {
            return None;
        }
        let at = (j as f64 + 0.5) / n as f64 * total;
        let t = self
            .cumulative
            .partition_point(|&c| c < at)
            .min(self.cumulative.len() - 1);
        // R2: the plastic number's reciprocals give well-spread points in the unit square.
        const G: f64 = 1.324_717_957_244_746;
        let mut u = (0.5 + j as f64 / G).fract();
        let mut v = (0.5 + j as f64 / (G * G)).fract();
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let [a, b, c] = corners(self.mesh, t);
        Some(a + (b - a) * u as f32 + (c - a) * v as f32)
    }
}

/// A bounding volume hierarchy over a mesh's triangles: boxes split at the median
/// centroid along their longest side, down to a few triangles a leaf. Searched nearest
/// box first, so a query far from the surface costs about what a near one does.
struct TriangleTree<'a> {
    mesh: &'a Mesh,
    /// Triangle numbers, grouped by leaf.
    triangles: Vec<u32>,
    /// Their corners, in the same order: a search reads a leaf's in one run.
    slots: Vec<[Vec3; 3]>,
    nodes: Vec<Node>,
}

/// A box of the tree: a leaf holds `triangles[first..first + count]` (their corners at
/// the same places in `slots`); an inner node's children are nodes `first` and
/// `first + 1` (`count` = 0).
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    first: u32,
    count: u32,
}

/// The most triangles in a leaf.
const LEAF_SIZE: usize = 4;

impl<'a> TriangleTree<'a> {
    fn new(mesh: &'a Mesh) -> TriangleTree<'a> {
        let n = mesh.triangle_count();
        let centroids: Vec<Vec3> = (0..n)
            .map(|t| corners(mesh, t).iter().sum::<Vec3>() / 3.0)
            .collect();
        // Each triangle's bounds, once: a box is the union of its triangles'.
        let bounds: Vec<(Vec3, Vec3)> = (0..n)
            .map(|t| {
                let [a, b, c] = corners(mesh, t);
                (a.min(b).min(c), a.max(b).max(c))
            })
            .collect();
        let mut tree = TriangleTree {
            mesh,
            triangles: (0..n as u32).collect(),
            slots: Vec::new(),
            nodes: Vec::with_capacity(2 * n / LEAF_SIZE + 1),
        };
        let leaf = |triangles: &[u32], first: usize, count: usize| {
            let (lo, hi) = triangles[first..first + count].iter().fold(
                (Vec3::INFINITY, Vec3::NEG_INFINITY),
                |(lo, hi), &t| {
                    let (l, h) = bounds[t as usize];
                    (lo.min(l), hi.max(h))
                },
            );
            Node {
                lo,
                hi,
                first: first as u32,
                count: count as u32,
            }
        };
        tree.nodes.push(leaf(&tree.triangles, 0, n));
        // Split leaves until small; a stack of nodes to split instead of recursion.
        let mut pending = vec![0usize];
        while let Some(i) = pending.pop() {
            let Node {
                lo,
                hi,
                first,
                count,
            } = tree.nodes[i];
            let (first, count) = (first as usize, count as usize);
            if count <= LEAF_SIZE {
                continue;
            }
            let size = hi - lo;
            let axis = (0..3)
                .max_by(|&a, &b| size[a].total_cmp(&size[b]))
                .unwrap_or(0);
            let half = count / 2;
            tree.triangles[first..first + count].select_nth_unstable_by(half, |&a, &b| {
                centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
            });
            let left = tree.nodes.len();
            let (l, r) = (
                leaf(&tree.triangles, first, half),
                leaf(&tree.triangles, first + half, count - half),
            );
            tree.nodes.extend([l, r]);
            tree.nodes[i] = Node {
                lo,
                hi,
                first: left as u32,
                count: 0,
            };
            pending.extend([left, left + 1]);
        }
        tree.slots = tree
            .triangles
            .iter()
            .map(|&t| corners(mesh, t as usize))
            .collect();
        tree
    }

    /// The distance from `p` to the nearest triangle.
    #[cfg(test)]
    fn distance(&self, p: Vec3) -> f32 {
        self.distance_beyond(p, -1.0, &mut 0).unwrap_or(0.0)
    }

    /// The distance from `p` to the nearest triangle when it is more than `floor`; `None`
    /// as soon as a triangle within `floor` is found. The triangle in slot `near` is
    /// tried first, and the slot becomes the nearest found's.
    fn distance_beyond(&self, p: Vec3, floor: f32, near: &mut u32) -> Option<f32> {
        let box_distance2 = |n: &Node| (p.clamp(n.lo, n.hi) - p).length_squared();
        let distance2 = |slot: u32| {
            let [a, b, c] = self.slots[slot as usize];
            (closest_on_triangle(p, a, b, c) - p).length_squared()
        };
        // Compared squared first, then as the figure itself would be, rounding and all.
        let floor2 = if floor >= 0.0 { floor * floor } else { -1.0 };
        let within = |d2: f32| d2 <= floor2 && d2.sqrt() <= floor;
        // A triangle's own distance bounds the search; the minimum over all is the same.
        if *near as usize >= self.slots.len() {
            *near = 0;
        }
        let mut best2 = distance2(*near);
        if within(best2) {
            return None;
        }
        // Nodes to visit; a median split makes a tree at most 32 deep, and the search
        // holds at most one node a depth besides the one it descends into.
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if box_distance2(node) >= best2 {
                continue;
            }
            if node.count > 0 {
                for slot in node.first..node.first + node.count {
                    let d2 = distance2(slot);
                    if d2 < best2 {
                        (best2, *near) = (d2, slot);
                    }
                }
                if within(best2) {
                    return None;
                }
            } else {
                let (l, r) = (node.first, node.first + 1);
                // The nearer child goes on top, to be searched first.
                let pair = if box_distance2(&self.nodes[l as usize])
                    < box_distance2(&self.nodes[r as usize])
                {
                    [r, l]
                } else {
                    [l, r]
                };
                stack[top..top + 2].copy_from_slice(&pair);
                top += 2;
            }
        }
        Some(best2.sqrt())
    }
}

/// The point of triangle (a, b, c) nearest to `p`, by the Voronoi regions of its
/// corners and edges (Real-Time Collision Detection, §5.1.5).
fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if denom == 0.0 {
        // A degenerate triangle that none of the tests above caught: its corners will do.
        return [a, b, c]
            .into_iter()
            .min_by(|x, y| {
                (*x - p)
                    .length_squared()
                    .total_cmp(&(*y - p).length_squared())
            })
            .unwrap_or(a);
    }
    let (v, w) = (vb / denom, vc / denom);
    a + ab * v + ac * w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_point_regions() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Z);
        assert!(
            (closest_on_triangle(Vec3::new(0.2, 1.0, 0.2), a, b, c) - Vec3::new(0.2, 0.0, 0.2))
                .length()
                < 1e-6
        );
        assert_eq!(closest_on_triangle(Vec3::new(-1.0, 0.0, -1.0), a, b, c), a);
        assert_eq!(
            closest_on_triangle(Vec3::new(0.5, 0.0, -1.0), a, b, c),
            Vec3::new(0.5, 0.0, 0.0)
        );
        assert_eq!(closest_on_triangle(Vec3::new(2.0, 0.0, 0.0), a, b, c), b);
        let on_bc = closest_on_triangle(Vec3::new(1.0, 0.0, 1.0), a, b, c);
        assert!((on_bc - Vec3::new(0.5, 0.0, 0.5)).length() < 1e-6);
    }

    #[test]
    fn tree_agrees_with_brute_force() {
        let bunny = crate::scene::bunny();
        let tree = TriangleTree::new(&bunny);
        let (lo, hi) = bunny.bounds();
        let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
        for i in 0..300 {
            let f = |k: u32| ((i * 7919 + k * 104_729) % 1000) as f32 / 1000.0;
            // Inside and around the bounds, some well outside.
            let p = lo - (hi - lo) * 0.3 + (hi - lo) * 1.6 * Vec3::new(f(1), f(2), f(3));
            let brute = (0..bunny.triangle_count())
                .map(|t| {
                    let [a, b, c] = corners(&bunny, t);
                    (closest_on_triangle(p, a, b, c) - p).length()
                })
                .fold(f32::INFINITY, f32::min);
            assert!(
                (tree.distance(p) - brute).abs() <= 1e-5 * (1.0 + brute),
                "{p}: {} vs {brute}",
                tree.distance(p)
            );
        }
    }

    /// The sampled distance as first written: every sample of each mesh (each vertex by
    /// its index) against every triangle of the other.
    fn brute_force(a: &Mesh, b: &Mesh, samples: usize) -> f32 {
        let one_sided = |from: &Mesh, to: &Mesh| {
            let sampler = Sampler::new(from);
            let mut used = from.indices.clone();
            used.sort_unstable();
            used.dedup();
            used.iter()
                .map(|&v| Vec3::from(from.positions[v as usize]))
                .chain((0..samples).filter_map(|j| sampler.sample(j, samples)))
                .map(|p| {
                    (0..to.triangle_count())
                        .map(|t| {
                            let [a, b, c] = corners(to, t);
                            (closest_on_triangle(p, a, b, c) - p).length_squared()
                        })
                        .fold(f32::INFINITY, f32::min)
                        .sqrt()
                })
                .fold(0.0, f32::max)
        };
        one_sided(a, b).max(one_sided(b, a))
    }

    #[test]
    fn stopping_early_gives_the_full_search_figure_to_the_bit() {
        let bunny = crate::scene::bunny();
        let coarse = crate::lod::ProgressiveMesh::build(&bunny)
            .unwrap()
            .mesh_at_triangles(bunny.triangle_count() / 10)
            .unwrap();
        let mut moved = bunny.clone();
        moved.scale_translate(1.0, [0.01, 0.02, 0.0]);
        for (a, b) in [(&bunny, &coarse), (&coarse, &moved), (&bunny, &moved)] {
            let brute = brute_force(a, b, 1_500);
            assert!(brute > 0.0);
            assert_eq!(hausdorff(a, b, 1_500).unwrap().to_bits(), brute.to_bits());
            for floor in [0.0, brute * 0.5, brute, brute * 2.0, f32::NAN, -1.0] {
                let want = floor.max(0.0).max(brute);
                assert_eq!(
                    hausdorff_above(a, b, 1_500, floor).unwrap().to_bits(),
                    want.to_bits(),
                    "floor {floor}"
                );
            }
        }
    }

    #[test]
    fn a_missing_piece_is_seen_from_the_other_side() {
        let quad = |x: f32| Mesh {
            positions: vec![
                [x, 0.0, 0.0],
                [x + 1.0, 0.0, 0.0],
                [x + 1.0, 0.0, 1.0],
                [x, 0.0, 1.0],
            ],
            normals: vec![[0.0, 1.0, 0.0]; 4],
            indices: vec![0, 2, 1, 0, 3, 2],
        };
        let mut two = quad(0.0);
        two.append(&quad(5.0));
        // The first quad lies on the pair; the far side of the second is 5 m from it.
        let d = hausdorff(&quad(0.0), &two, 1000).unwrap();
        assert!((d - 5.0).abs() < 1e-5, "{d}");
    }

    #[test]
    fn bad_input_is_an_error() {
        let bunny = crate::scene::bunny();
        assert!(hausdorff(&bunny, &Mesh::default(), 10).is_err());
        let mut nan = bunny.clone();
        nan.positions[3][1] = f32::NAN;
        assert!(hausdorff(&nan, &bunny, 10).is_err());
    }
}
