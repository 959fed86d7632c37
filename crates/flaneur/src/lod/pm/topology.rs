//! The connectivity the simplifier reasons on: co-located vertices welded into one
//! *position*, each position's fan of triangles, and the manifold tests of a half-edge
//! collapse (Zheng 2007 §2.1.1: "only manifold operators").
//!
//! A mesh's vertices are (position, normal) pairs, so a crease or an attribute seam —
//! every edge of citygen's flat-shaded boxes — is made of two vertices at one point,
//! each used by the triangles on its side. Seen vertex by vertex such a mesh is a heap
//! of loose patches, and collapsing one patch's corner would open a crack along the
//! crease. So the topology here is that of positions: a vertex is one *wedge* of its
//! position, the fan and link tests run on positions, and a collapse moves every wedge
//! of a position at once (the simplifier decides where each wedge goes). Positions are
//! welded on exact bit equality (with −0 = +0): generators and exporters write the same
//! float for the same corner, and a tolerance would weld distinct nearby features.

use std::collections::HashMap;

use glam::DVec3;
use rayon::prelude::*;

use crate::scene::Mesh;

/// A position's fan of triangles, as the link of the position: for each triangle
/// (c, a, b) wound counter-clockwise, the link edge a → b.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Fan {
    /// A full disk (interior position) rather than a half-disk (boundary position).
    pub closed: bool,
    /// For a half-disk, the neighbour across the boundary edge wound c → first; for a
    /// disk, the first link vertex met.
    pub first: u32,
    /// For a half-disk, the neighbour across the boundary edge wound last → c.
    pub last: u32,
    /// The neighbouring positions, in fan order.
    pub neighbours: Vec<u32>,
    /// The link edges, sorted by source: kept to reuse the allocation.
    links: Vec<(u32, u32)>,
}

/// The welded, mutable connectivity of a mesh under half-edge collapses.
#[derive(Clone, Debug)]
pub(crate) struct Adjacency {
    /// The position of each vertex.
    pub pos_of: Vec<u32>,
    /// The coordinates of each position.
    pub coords: Vec<DVec3>,
    /// `wedges[wedge_start[p]..wedge_start[p + 1]]` are the vertices at position p.
    wedge_start: Vec<u32>,
    wedges: Vec<u32>,
    /// Each triangle's current corners (vertices); change them with `move_corner`.
    pub faces: Vec<[u32; 3]>,
    /// The positions of `faces`, kept beside them: the fan and link tests read little
    /// else, and a second lookup per corner doubles their cache misses.
    face_pos: Vec<[u32; 3]>,
    /// Whether each triangle is still in the mesh.
    pub alive: Vec<bool>,
    /// The live triangles around each position.
    pub face_lists: Vec<Vec<u32>>,
}

impl Adjacency {
    /// Welds `mesh`'s positions and gathers each position's triangles. The mesh must
    /// have passed `Mesh::validate`.
    pub(crate) fn new(mesh: &Mesh) -> Adjacency {
        let n = mesh.positions.len();
        let mut ids: HashMap<[u32; 3], u32> = HashMap::with_capacity(n);
        let mut coords = Vec::new();
        // Ids follow first use in vertex order, so the map's own order never shows.
        let pos_of: Vec<u32> = mesh
            .positions
            .iter()
            .map(|p| {
                let key = p.map(|c| (c + 0.0).to_bits());
                *ids.entry(key).or_insert_with(|| {
                    coords.push(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64));
                    coords.len() as u32 - 1
                })
            })
            .collect();
        Adjacency::from_welded(mesh, pos_of, coords)
    }

    /// The connectivity of `mesh` with its vertices already welded: vertex v at
    /// position `pos_of[v]`, at `coords`. For a part of a mesh whose welding is known
    /// (`parallel`), where hashing every vertex again would be wasted.
    pub(crate) fn from_welded(mesh: &Mesh, pos_of: Vec<u32>, coords: Vec<DVec3>) -> Adjacency {
        let n = mesh.positions.len();
        let mut wedge_start = vec![0u32; coords.len() + 1];
        for &p in &pos_of {
            wedge_start[p as usize + 1] += 1;
        }
        for i in 1..wedge_start.len() {
            wedge_start[i] += wedge_start[i - 1];
        }
        let mut fill = wedge_start.clone();
        let mut wedges = vec![0u32; n];
        for (v, &p) in pos_of.iter().enumerate() {
            wedges[fill[p as usize] as usize] = v as u32;
            fill[p as usize] += 1;
        }
        let faces: Vec<[u32; 3]> = mesh
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        let mut face_lists = vec![Vec::new(); coords.len()];
        for (f, t) in faces.iter().enumerate() {
            let ps = t.map(|v| pos_of[v as usize]);
            for (k, &p) in ps.iter().enumerate() {
                // A triangle with a position twice is listed there once.
                if !ps[..k].contains(&p) {
                    face_lists[p as usize].push(f as u32);
                }
            }
        }
        let face_pos = faces
            .iter()
            .map(|t| t.map(|v| pos_of[v as usize]))
            .collect();
        Adjacency {
            face_pos,
            pos_of,
            coords,
            wedge_start,
            wedges,
            alive: vec![true; faces.len()],
            faces,
            face_lists,
        }
    }

    /// The number of positions.
    pub(crate) fn position_count(&self) -> usize {
        self.coords.len()
    }

    /// The vertices welded at position `p`, in index order.
    pub(crate) fn wedges(&self, p: u32) -> &[u32] {
        &self.wedges
            [self.wedge_start[p as usize] as usize..self.wedge_start[p as usize + 1] as usize]
    }

    /// The positions of triangle `f`'s corners.
    pub(crate) fn corner_positions(&self, f: u32) -> [u32; 3] {
        self.face_pos[f as usize]
    }

    /// Sets triangle `f`'s corners and whether it is alive, leaving the position lists
    /// to the caller: for merging back what a part of the mesh did on its own, which
    /// knows the new lists whole.
    pub(crate) fn set_face(&mut self, f: u32, corners: [u32; 3], alive: bool) {
        let fu = f as usize;
        self.face_pos[fu] = corners.map(|v| self.pos_of[v as usize]);
        self.faces[fu] = corners;
        self.alive[fu] = alive;
    }

    /// Replaces vertex `from` by `to` among triangle `f`'s corners.
    pub(crate) fn move_corner(&mut self, f: u32, from: u32, to: u32) {
        for k in 0..3 {
            if self.faces[f as usize][k] == from {
                self.faces[f as usize][k] = to;
                self.face_pos[f as usize][k] = self.pos_of[to as usize];
            }
        }
    }

    /// The corner (0–2) of triangle `f` at position `p`, if any.
    pub(crate) fn corner_at(&self, f: u32, p: u32) -> Option<usize> {
        self.corner_positions(f).iter().position(|&q| q == p)
    }

    /// The coordinates of triangle `f`'s corners.
    pub(crate) fn corner_coords(&self, f: u32) -> [DVec3; 3] {
        self.corner_positions(f).map(|p| self.coords[p as usize])
    }

    /// Whether a triangle names one position at two corners: no fan through such a
    /// position is a manifold one, so it is kept as it is.
    pub(crate) fn is_pinched(&self, f: u32) -> bool {
        let [a, b, c] = self.corner_positions(f);
        a == b || b == c || c == a
    }

    /// The fan of position `c`: `None` when its triangles do not form one manifold disk
    /// or half-disk (an edge shared by three triangles, two fans meeting at a point,
    /// inconsistent winding, or a pinched triangle), or when it has no triangles.
    #[cfg(test)]
    pub(crate) fn fan(&self, c: u32) -> Option<Fan> {
        let mut fan = Fan::default();
        self.fan_into(c, &mut fan).then_some(fan)
    }

    /// [`fan`](Self::fan) into `fan`'s buffers: this runs for every position a collapse
    /// touches, so it allocates nothing once warm. `false` where `fan` gives `None`.
    pub(crate) fn fan_into(&self, c: u32, fan: &mut Fan) -> bool {
        let faces = &self.face_lists[c as usize];
        fan.links.clear();
        fan.neighbours.clear();
        for &f in faces {
            let ps = self.corner_positions(f);
            let Some(k) = ps.iter().position(|&q| q == c) else {
                return false;
            };
            let (a, b) = (ps[(k + 1) % 3], ps[(k + 2) % 3]);
            if a == b || a == c || b == c {
                return false;
            }
            fan.links.push((a, b));
        }
        let links = &mut fan.links;
        if links.is_empty() {
            return false;
        }
        links.sort_unstable();
        if links.windows(2).any(|w| w[0].0 == w[1].0) {
            return false;
        }
        // With every source once, one walk along the links that takes each exactly once
        // makes every target once too: the fan is one disk (a cycle) or one half-disk
        // (a chain). A chain's start is the one source that is no target, which the
        // sums give: Σ sources − Σ targets = first − last.
        let walk = |from: u32, out: &mut Vec<u32>| -> (usize, u32) {
            let (mut cur, mut steps) = (from, 0);
            out.push(cur);
            while let Ok(i) = links.binary_search_by_key(&cur, |l| l.0) {
                steps += 1;
                cur = links[i].1;
                if cur == from || steps > links.len() {
                    break;
                }
                out.push(cur);
            }
            (steps, cur)
        };
        let start = links[0].0;
        let (steps, end) = walk(start, &mut fan.neighbours);
        if end == start {
            fan.closed = true;
            (fan.first, fan.last) = (start, *fan.neighbours.last().unwrap_or(&start));
            return steps == links.len();
        }
        let sum = |f: fn(&(u32, u32)) -> u32| links.iter().fold(0u32, |s, l| s.wrapping_add(f(l)));
        let first = sum(|l| l.0).wrapping_sub(sum(|l| l.1)).wrapping_add(end);
        fan.neighbours.clear();
        let (steps, last) = walk(first, &mut fan.neighbours);
        fan.closed = false;
        (fan.first, fan.last) = (first, last);
        steps == links.len() && last != first && links.binary_search_by_key(&last, |l| l.0).is_err()
    }

    /// The position-level boundary edges (a → b as wound in their one triangle), with
    /// that triangle: edges of exactly one triangle. Edges of three or more triangles
    /// are neither boundary nor interior; their positions fail `fan` and stay put.
    pub(crate) fn boundary_edges(&self) -> Vec<(u32, u32, u32)> {
        let mut edges: Vec<(u32, u32, u32, u32)> = Vec::with_capacity(self.faces.len() * 3);
        for f in 0..self.faces.len() as u32 {
            let ps = self.corner_positions(f);
            for k in 0..3 {
                let (a, b) = (ps[k], ps[(k + 1) % 3]);
                if a != b {
                    edges.push((a.min(b), a.max(b), f, (a > b) as u32));
                }
            }
        }
        edges.par_sort_unstable();
        let mut out = Vec::new();
        let mut i = 0;
        while i < edges.len() {
            let mut j = i + 1;
            while j < edges.len() && (edges[j].0, edges[j].1) == (edges[i].0, edges[i].1) {
                j += 1;
            }
            if j == i + 1 {
                let (lo, hi, f, swapped) = edges[i];
                let (a, b) = if swapped == 1 { (hi, lo) } else { (lo, hi) };
                out.push((a, b, f));
            }
            i = j;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3×3-vertex grid in the xz plane, facing +y, with an extra copy of the centre
    /// vertex used by the two triangles of the upper-right quad (a seam).
    fn grid_with_seam() -> Mesh {
        let mut positions = Vec::new();
        for j in 0..3 {
            for i in 0..3 {
                positions.push([i as f32, 0.0, j as f32]);
            }
        }
        positions.push([1.0, 0.0, 1.0]); // vertex 9: the centre again
        let mut indices = Vec::new();
        for j in 0..2u32 {
            for i in 0..2u32 {
                let v = |di: u32, dj: u32| {
                    let v = (j + dj) * 3 + i + di;
                    if v == 4 && (i, j) == (1, 1) {
                        9
                    } else {
                        v
                    }
                };
                indices.extend_from_slice(&[v(0, 0), v(0, 1), v(1, 1), v(0, 0), v(1, 1), v(1, 0)]);
            }
        }
        let normals = vec![[0.0, 1.0, 0.0]; positions.len()];
        Mesh {
            positions,
            normals,
            indices,
        }
    }

    #[test]
    fn welding_joins_the_seam() {
        let adj = Adjacency::new(&grid_with_seam());
        assert_eq!(adj.position_count(), 9);
        assert_eq!(adj.wedges(4), &[4, 9]);
        assert_eq!(adj.face_lists[4].len(), 6);
        let fan = adj.fan(4).unwrap();
        assert!(fan.closed);
        assert_eq!(fan.neighbours.len(), 6);
    }

    #[test]
    fn boundary_fans_are_open() {
        let adj = Adjacency::new(&grid_with_seam());
        let corner = adj.fan(0).unwrap();
        assert!(!corner.closed);
        let side = adj.fan(1).unwrap();
        assert!(!side.closed);
        assert_eq!((side.first, side.last), (0, 2));
        assert_eq!(side.neighbours, vec![0, 4, 5, 2]);
        assert_eq!(adj.boundary_edges().len(), 8);
    }

    #[test]
    fn bow_tie_is_not_manifold() {
        // Two triangles that share only vertex 0.
        let m = Mesh {
            positions: vec![
                [0.0; 3],
                [1.0, 0.0, 0.0],
                [1.0, 0.0, 1.0],
                [-1.0, 0.0, 0.0],
                [-1.0, 0.0, -1.0],
            ],
            normals: vec![[0.0, 1.0, 0.0]; 5],
            indices: vec![0, 2, 1, 0, 4, 3],
        };
        let adj = Adjacency::new(&m);
        assert!(adj.fan(0).is_none());
        assert!(adj.fan(1).is_some());
    }
}
