//! The symmetric Hausdorff distance between two triangle meshes, sampled as surface
//! comparison tools measure it: points spread over each mesh's surface by area, and
//! for each the distance to the nearest point of the other mesh's triangles, found
//! through a bounding volume hierarchy over those triangles. The sampled distance never
//! exceeds the true one, and reaches it as the samples grow dense.
//!
//! The samples are a fixed sequence (stratified by area, placed within a triangle by the
//! R2 low-discrepancy sequence), so the same meshes always give the same figure, and the
//! vertices of each mesh are always among them.

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
    for (name, m) in [("first", a), ("second", b)] {
        m.validate()
            .map_err(|e| Error::Invalid(format!("Hausdorff distance, {name} mesh: {e}")))?;
        if m.indices.is_empty() {
            return Err(Error::Invalid(format!(
                "Hausdorff distance, {name} mesh: no triangles"
            )));
        }
    }
    let (tree_a, tree_b) = rayon::join(|| TriangleTree::new(a), || TriangleTree::new(b));
    let (ab, ba) = rayon::join(
        || one_sided(a, &tree_b, samples),
        || one_sided(b, &tree_a, samples),
    );
    Ok(ab.max(ba))
}

/// The farthest that a sample of `from` lies from the triangles in `to`.
fn one_sided(from: &Mesh, to: &TriangleTree, samples: usize) -> f32 {
    let sampler = Sampler::new(from);
    let from_vertices = used_vertices(from)
        .par_iter()
        .map(|&v| to.distance(Vec3::from(from.positions[v as usize])))
        .reduce(|| 0.0, f32::max);
    let from_surface = (0..samples)
        .into_par_iter()
        .filter_map(|j| sampler.sample(j, samples))
        .map(|p| to.distance(p))
        .reduce(|| 0.0, f32::max);
    from_vertices.max(from_surface)
}

fn used_vertices(m: &Mesh) -> Vec<u32> {
    let mut used = m.indices.clone();
    used.sort_unstable();
    used.dedup();
    used
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
    nodes: Vec<Node>,
}

/// A box of the tree: a leaf holds `triangles[first..first + count]`; an inner node's
/// children are nodes `first` and `first + 1` (`count` = 0).
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
        let mut tree = TriangleTree {
            mesh,
            triangles: (0..n as u32).collect(),
            nodes: Vec::with_capacity(2 * n / LEAF_SIZE + 1),
        };
        tree.nodes.push(tree.leaf(0, n));
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
                tree.leaf(first, half),
                tree.leaf(first + half, count - half),
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
        tree
    }

    /// A leaf over `triangles[first..first + count]`, with their bounds.
    fn leaf(&self, first: usize, count: usize) -> Node {
        let (lo, hi) = self.triangles[first..first + count]
            .iter()
            .flat_map(|&t| corners(self.mesh, t as usize))
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p), hi.max(p))
            });
        Node {
            lo,
            hi,
            first: first as u32,
            count: count as u32,
        }
    }

    /// The distance from `p` to the nearest triangle.
    fn distance(&self, p: Vec3) -> f32 {
        let box_distance2 = |n: &Node| (p.clamp(n.lo, n.hi) - p).length_squared();
        let mut best2 = f32::INFINITY;
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i as usize];
            if box_distance2(node) >= best2 {
                continue;
            }
            if node.count > 0 {
                for &t in &self.triangles[node.first as usize..(node.first + node.count) as usize] {
                    let [a, b, c] = corners(self.mesh, t as usize);
                    best2 = best2.min((closest_on_triangle(p, a, b, c) - p).length_squared());
                }
            } else {
                let (l, r) = (node.first, node.first + 1);
                // The nearer child goes on top, to be searched first.
                if box_distance2(&self.nodes[l as usize]) < box_distance2(&self.nodes[r as usize]) {
                    stack.extend([r, l]);
                } else {
                    stack.extend([l, r]);
                }
            }
        }
        best2.sqrt()
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
