//! Meshes the LOD tests share, and the checks every level must pass.

use std::collections::{HashMap, HashSet};

use glam::DVec3;

use citygen::Mesh;

use super::pm::Adjacency;
use super::pm::{ProgressiveMesh, SelectiveMesh};

/// The first generated building of at least 600 triangles: flat-shaded, every face with
/// its own vertices, so every corner and crease is a seam.
pub(crate) fn building() -> Mesh {
    citygen::sample_building(600).expect("a city of 64 has a building of 600 triangles")
}

/// A closed cube of side 2 at `centre`, subdivided `levels` times, smooth normals.
pub(crate) fn cube(centre: [f32; 3], levels: u32) -> Mesh {
    let mut positions = Vec::new();
    for i in 0..8 {
        positions.push([
            (i & 1) as f32 * 2.0 - 1.0,
            ((i >> 1) & 1) as f32 * 2.0 - 1.0,
            ((i >> 2) & 1) as f32 * 2.0 - 1.0,
        ]);
    }
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let indices = quads
        .iter()
        .flat_map(|q| [q[0], q[1], q[2], q[0], q[2], q[3]])
        .collect();
    let mut m = Mesh {
        positions,
        normals: Vec::new(),
        indices,
    };
    m.compute_smooth_normals();
    if m.signed_volume() < 0.0 {
        m.flip();
    }
    for _ in 0..levels {
        m = m.subdivide();
    }
    m.scale_translate(1.0, centre);
    m
}

/// [`cube`] flat-shaded: each side has its own vertices with the side's normal, so the
/// twelve edges are creases and the eight corners have three vertices each.
pub(crate) fn flat_cube(centre: [f32; 3], levels: u32) -> Mesh {
    let smooth = cube(centre, levels);
    let mut copies: HashMap<(u32, usize), u32> = HashMap::new();
    let mut m = Mesh::default();
    for t in smooth.indices.chunks_exact(3) {
        let n = normal(&smooth, t);
        let axis = (0..3)
            .max_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
            .unwrap_or(0);
        let side = 2 * axis + (n[axis] > 0.0) as usize;
        for &v in t {
            let next = m.positions.len() as u32;
            let copy = *copies.entry((v, side)).or_insert_with(|| {
                m.positions.push(smooth.positions[v as usize]);
                let mut unit = [0.0; 3];
                unit[axis] = n[axis].signum() as f32;
                m.normals.push(unit);
                next
            });
            m.indices.push(copy);
        }
    }
    m
}

/// The total length of the edges of one triangle, after welding co-located vertices:
/// what a crack along a crease would add to.
pub(crate) fn boundary_length(m: &Mesh) -> f64 {
    let adj = Adjacency::new(m);
    adj.boundary_edges()
        .iter()
        .map(|&(a, b, _)| adj.coords[a as usize].distance(adj.coords[b as usize]))
        .sum()
}

/// A flat n × n grid of unit quads in the xz plane from the origin, facing +y.
pub(crate) fn grid(n: u32) -> Mesh {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            positions.push([i as f32, 0.0, j as f32]);
        }
    }
    let v = |i: u32, j: u32| j * (n + 1) + i;
    let mut indices = Vec::new();
    for j in 0..n {
        for i in 0..n {
            indices.extend_from_slice(&[
                v(i, j),
                v(i, j + 1),
                v(i + 1, j + 1),
                v(i, j),
                v(i + 1, j + 1),
                v(i + 1, j),
            ]);
        }
    }
    let normals = vec![[0.0, 1.0, 0.0]; positions.len()];
    Mesh {
        positions,
        normals,
        indices,
    }
}

/// A random open patch for property tests: an 8 × 8 grid with random heights, about a
/// tenth of its triangles dropped (holes, ragged and pinched boundaries), the columns
/// left of a random line given their own copies of the vertices with other normals (a
/// seam), and for odd seeds a closed cube beside it.
pub(crate) fn random_patch(seed: u64) -> Mesh {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let n = 8;
    let mut m = grid(n);
    for p in &mut m.positions {
        p[1] = rng.gen_range(0.0..0.6);
    }
    m.compute_smooth_normals();
    let seam = rng.gen_range(1..n);
    let mut copies: HashMap<u32, u32> = HashMap::new();
    let mut indices = Vec::new();
    for (t, tri) in m.indices.clone().chunks_exact(3).enumerate() {
        if rng.gen_bool(0.1) {
            continue;
        }
        let column = (t / 2) as u32 % n;
        for &v in tri {
            if column < seam {
                let copy = *copies.entry(v).or_insert_with(|| {
                    m.positions.push(m.positions[v as usize]);
                    let tilted = (DVec3::from(m.normals[v as usize].map(|c| c as f64))
                        + DVec3::X * 0.5)
                        .normalize();
                    m.normals.push(tilted.to_array().map(|c| c as f32));
                    m.positions.len() as u32 - 1
                });
                indices.push(copy);
            } else {
                indices.push(v);
            }
        }
    }
    m.indices = indices;
    if seed % 2 == 1 {
        m.append(&cube([4.0, 3.0, 4.0], 1));
    }
    m
}

fn point(p: [f32; 3]) -> DVec3 {
    DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

fn normal(m: &Mesh, t: &[u32]) -> DVec3 {
    let [a, b, c] = [t[0], t[1], t[2]].map(|i| point(m.positions[i as usize]));
    (b - a).cross(c - a)
}

/// Triangles with the same three positions as another (in any order).
pub(crate) fn duplicate_triangles(m: &Mesh) -> usize {
    let mut seen = HashSet::new();
    m.indices
        .chunks_exact(3)
        .filter(|t| {
            let mut key =
                [t[0], t[1], t[2]].map(|i| m.positions[i as usize].map(|c| (c + 0.0).to_bits()));
            key.sort_unstable();
            !seen.insert(key)
        })
        .count()
}

/// Checks the level of `pm` after `splits` splits against `original`: a valid compact
/// mesh, no degenerate or duplicate triangle, and no triangle turned by 90° or more
/// from the same triangle in the original.
pub(crate) fn check_level(original: &Mesh, pm: &ProgressiveMesh, splits: usize) {
    let cursor = pm.cursor_at(splits).unwrap();
    let level = cursor.to_mesh();
    level.validate().unwrap();
    assert_eq!(level.triangle_count(), cursor.triangle_count());
    let mut used = vec![false; level.positions.len()];
    for t in level.indices.chunks_exact(3) {
        assert!(
            t[0] != t[1] && t[1] != t[2] && t[2] != t[0],
            "{t:?} repeats a vertex"
        );
        assert!(normal(&level, t).length() > 0.0, "{t:?} has no area");
        for &v in t {
            used[v as usize] = true;
        }
    }
    assert!(used.iter().all(|&u| u), "a compact level uses every vertex");
    assert_eq!(duplicate_triangles(&level), duplicate_triangles(original));

    let mut original_of_slot = vec![u32::MAX; pm.triangle_slots()];
    for (t, &slot) in pm.triangle_map.iter().enumerate() {
        original_of_slot[slot as usize] = t as u32;
    }
    let mut original_of_vertex = vec![0u32; pm.vertex_count()];
    for (v, &n) in pm.vertex_map.iter().enumerate() {
        original_of_vertex[n as usize] = v as u32;
    }
    for (slot, t) in cursor.mesh().slots().iter().enumerate() {
        if *t == super::pm::NO_TRIANGLE {
            continue;
        }
        let o = original_of_slot[slot] as usize;
        let before = normal(original, &original.indices[3 * o..3 * o + 3]);
        let now = normal(original, &t.map(|v| original_of_vertex[v as usize]));
        assert!(
            before.dot(now) > 0.0 || before == DVec3::ZERO,
            "slot {slot} folds over: {before} → {now}"
        );
    }
}

/// Every split applied to the base gives the original through the renumbering:
/// vertex for vertex (bit for bit), triangle for triangle (corner for corner).
pub(crate) fn check_exact(original: &Mesh, pm: &ProgressiveMesh) {
    let nv = original.positions.len();
    let mut seen = vec![false; nv];
    for &n in &pm.vertex_map {
        assert!(
            !std::mem::replace(&mut seen[n as usize], true),
            "vertex {n} numbered twice"
        );
    }
    assert_eq!(pm.vertex_count(), nv);

    let full = pm.cursor_at(pm.splits.len()).unwrap();
    check_full_mesh(original, pm, full.mesh());
}

/// `mesh`, refined by every split, equals `original` through `pm`'s renumbering,
/// vertex for vertex (bit for bit) and triangle for triangle.
pub(crate) fn check_full_mesh(original: &Mesh, pm: &ProgressiveMesh, sm: &SelectiveMesh) {
    for v in 0..original.positions.len() {
        let n = pm.vertex_map[v] as usize;
        assert_eq!(
            sm.positions()[n].map(f32::to_bits),
            original.positions[v].map(f32::to_bits),
            "vertex {v}"
        );
        assert_eq!(
            sm.normals()[n].map(f32::to_bits),
            original.normals[v].map(f32::to_bits),
            "vertex {v}"
        );
    }
    assert_eq!(sm.triangle_count(), original.triangle_count());
    for (t, tri) in original.indices.chunks_exact(3).enumerate() {
        let expected = [tri[0], tri[1], tri[2]].map(|v| pm.vertex_map[v as usize]);
        assert_eq!(
            sm.slots()[pm.triangle_map[t] as usize],
            expected,
            "triangle {t}"
        );
    }
}
