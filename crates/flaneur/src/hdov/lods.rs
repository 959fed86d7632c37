//! Internal LODs (Shou 2002 §5.6): coarse representations, *proxies*, of the objects
//! below a node, made from the **simplified** geometry of the node's children (its
//! objects' coarsest stored levels for a leaf, its children's coarsest internal LODs
//! above), as the thesis chooses for fidelity, each stored with its geometric error.
//!
//! **Simplifiers.** The thesis runs Garland's pair contraction (qslim), which merges
//! disjoint objects. The LOD core's edge collapses (`lod::pm`) cannot: a group of
//! buildings already at their coarsest levels stops at about half its triangles, but
//! keeps every building, so its distance from the full geometry stays near the
//! source's own. The coarser levels are meshoptimizer's sloppy simplifier (vertex
//! clustering on a grid, each cell's vertex chosen by its quadric), which merges
//! neighbouring buildings and drops those smaller than a cell, so any share of the
//! source can be reached, at the cost of the dropped buildings' heights in error. Its
//! triangles take flat normals, recomputed: clustering moves vertices across creases,
//! so the source's normals no longer fit the faces, and a proxy of boxes drawn lit
//! reads as boxes only with flat shading. Vertices that share a position and a normal
//! are welded.
//!
//! **Levels** (choices the thesis leaves open): up to three, of [`LEVEL_SHARES`] of the
//! source's triangles (1/2, 1/8, 1/32), none under [`MIN_TRIANGLES`]. The finest is
//! the edge collapses' (sloppy's where they cannot simplify at all) at half the
//! children's coarsest together, under the thesis's rule (fewer than them); the two
//! coarser are sloppy's, steps of four so that each saves clearly over the one before
//! and a screen-space rule has distinct errors to choose from. Measured on the
//! 3,000-object city, clustering at half the source is twice as far from the full
//! geometry as the edge collapses (14–17 m against 7.5 m, sampled Hausdorff, groups of
//! 72 buildings), since it drops buildings; below half only clustering goes. A source
//! the simplifiers cannot shrink below itself (under 2 × [`MIN_TRIANGLES`]) gives no
//! internal LOD; the search then never stops at the node.
//!
//! **Error.** Each level's `error` is a sampled symmetric Hausdorff distance in metres,
//! in the objects' frame (the world's), between the proxy and the node's **full**
//! geometry (its objects' full meshes), measured by `lod::hausdorff` with
//! up to [`ERROR_SAMPLES`] points a surface plus every vertex of both. Where that geometry is
//! larger than [`DIRECT_TRIANGLES`] (the top nodes hold a whole district, the root the
//! city) it is not measured whole: the figure is then the proxy's distance to its
//! source plus the largest distance of the source's parts from their own full geometry
//! ([`Reference::Source`]), a bound by the triangle inequality
//! (d_H(P, F) ≤ d_H(P, S) + d_H(S, F), and d_H of a union is at most the largest of its
//! parts'), so an estimate of an upper bound, not of the distance itself. A level is
//! never stored with less error than a finer one: a coarser proxy that measures closer
//! takes its finer level's figure (a conservative bound still).

use std::collections::HashMap;

use glam::Vec3;
use meshopt::VertexDataAdapter;

use crate::error::{Error, Result};
use crate::lod::{hausdorff_above, Level, Measured, ProgressiveMesh};
use crate::scene::Mesh;

/// The share of its source's triangles each internal LOD keeps, finest first.
pub const LEVEL_SHARES: [f64; 3] = [0.5, 0.125, 1.0 / 32.0];
/// No internal LOD has fewer triangles.
pub const MIN_TRIANGLES: usize = 16;
/// The most points sampled on each surface, each way, when a proxy's error is measured
/// (every vertex of both meshes besides): two a triangle of the two meshes together, at
/// least 1,000 ([`error_above`]).
pub const ERROR_SAMPLES: usize = 20_000;
/// The most triangles of full geometry a node's proxies are measured against whole;
/// above it, [`Reference::Source`]'s bound.
pub const DIRECT_TRIANGLES: usize = 250_000;

/// The meshes of `parts` as one mesh.
pub fn aggregate<'m>(parts: impl IntoIterator<Item = &'m Mesh>) -> Mesh {
    let mut out = Mesh::default();
    for m in parts {
        let base = out.positions.len() as u32;
        out.positions.extend_from_slice(&m.positions);
        out.normals.extend_from_slice(&m.normals);
        out.indices.extend(m.indices.iter().map(|i| i + base));
    }
    out
}

/// What a node's proxies are measured against.
#[derive(Clone, Copy, Debug)]
pub enum Reference<'a> {
    /// The node's full geometry: its objects' full meshes, as one mesh.
    Full(&'a Mesh),
    /// The source itself, whose parts lie within `parts_error` metres (Hausdorff) of
    /// their full geometry: the stored figure is the proxy's distance to the source plus
    /// `parts_error`.
    Source {
        /// The largest Hausdorff distance of a part of the source from its full geometry.
        parts_error: f32,
    },
}

/// The internal LODs of a node whose source (its children's simplified geometry, as
/// one mesh) is `source`, finest first, each with its error against `reference` in
/// metres: each strictly coarser than the one before and than the source, none with
/// less error than a finer one. Empty when the source is too small to simplify. An
/// error when the source or the reference is not a valid mesh (a NaN position, a bad
/// index) or has no triangles.
pub fn internal_levels(source: &Mesh, reference: Reference<'_>) -> Result<Vec<Level>> {
    source
        .validate()
        .map_err(|e| Error::Invalid(format!("internal LODs: the source: {e}")))?;
    if source.indices.is_empty() {
        return Err(Error::Invalid(
            "internal LODs: the source has no triangles".into(),
        ));
    }
    if let Reference::Source { parts_error } = reference {
        if !(parts_error.is_finite() && parts_error >= 0.0) {
            return Err(Error::Invalid(format!(
                "internal LODs: the parts' error {parts_error} is not a distance"
            )));
        }
    }
    let full = source.triangle_count();
    if full < 2 * MIN_TRIANGLES {
        return Ok(Vec::new());
    }
    // What the proxies are measured against, made ready once for all of them.
    let (against, parts_error) = match reference {
        Reference::Full(f) => (Measured::new(f, "the node's full geometry")?, None),
        Reference::Source { parts_error } => {
            (Measured::new(source, "the source")?, Some(parts_error))
        }
    };
    let mut levels: Vec<Level> = Vec::new();
    let mut finer = (full, 0.0f32);
    for (k, share) in LEVEL_SHARES.into_iter().enumerate() {
        let target = (full as f64 * share) as usize;
        if target < MIN_TRIANGLES {
            break;
        }
        let collapsed = match k {
            0 => collapsed(source, target)?.filter(|m| m.triangle_count() < finer.0),
            _ => None,
        };
        let Some(mesh) = collapsed.or_else(|| proxy(source, target, finer.0)) else {
            continue;
        };
        let t = mesh.triangle_count();
        // A chain holds only levels coarser than the one before (`encode_chain` refuses
        // others): a level that is not is left out, as one that cannot be made.
        if t == 0 || t >= finer.0 {
            continue;
        }
        // Only a distance over the finer level's error changes what is stored: the
        // measure is told so, and stops early on samples under it.
        let proxy = Measured::new(&mesh, "a proxy")?;
        let samples = samples_for(proxy.triangle_count(), against.triangle_count());
        let error = match parts_error {
            None => against.hausdorff_above(&proxy, samples, finer.1),
            Some(e) => against.hausdorff_above(&proxy, samples, below_sum(finer.1, e)) + e,
        }
        .max(finer.1);
        finer = (t, error);
        levels.push(Level {
            mesh,
            splits: 0,
            error,
        });
    }
    Ok(levels)
}

/// The larger of `floor` and the sampled Hausdorff distance between `a` and `b`
/// (`lod::hausdorff`), with samples in proportion to their triangles up to
/// [`ERROR_SAMPLES`]: a small mesh's vertices already cover it, and a fixed 20,000 for
/// each of a city's thousands of small scene-tree nodes cost minutes. The measure stops
/// early on the samples that lie within `floor` (`lod::hausdorff_above`), the figure
/// the same: for the largest of several distances, pass the largest so far.
pub(crate) fn error_above(a: &Mesh, b: &Mesh, floor: f32) -> Result<f32> {
    let samples = samples_for(a.triangle_count(), b.triangle_count());
    hausdorff_above(a, b, samples, floor)
}

/// The points sampled on each surface when meshes of `a` and `b` triangles are compared
/// ([`error_above`]).
fn samples_for(a: usize, b: usize) -> usize {
    (2 * (a + b)).clamp(1_000, ERROR_SAMPLES)
}

/// The largest `x` (at least 0) whose rounded sum with `part` is at most `total`: a
/// distance up to it, plus `part`, stores no more than `total`, so the measure of it
/// may stop there and the figure stored is the same.
fn below_sum(total: f32, part: f32) -> f32 {
    let mut x = (total - part).max(0.0);
    while x > 0.0 && x + part > total {
        x = f32::from_bits(x.to_bits() - 1);
    }
    x
}

/// `source` simplified by the LOD core's edge collapses towards `target` triangles,
/// every building kept; `None` when it cannot simplify at all.
fn collapsed(source: &Mesh, target: usize) -> Result<Option<Mesh>> {
    let pm = ProgressiveMesh::build(source)?;
    let mesh = pm.cursor_at(pm.splits_for_triangles(target))?.to_mesh();
    Ok((mesh.triangle_count() > 0).then_some(mesh))
}

/// `source` clustered on a grid to the most triangles not over `target` that any grid
/// tried gives (meshoptimizer's sloppy simplifier), with flat normals, degenerate
/// triangles dropped; failing that, the fewest over it but under `below`. `None` when
/// no grid tried gives a mesh under `below`.
///
/// The grid is searched here, not by the simplifier: its own search assumes the count
/// grows with the grid, and on a sparse source (buildings apart) the count can fall
/// from hundreds to nothing between two sizes, where it answers nothing. Asked for no
/// triangles at a given error, it clusters at exactly the grid 1/error; a binary search
/// over the grid's cells a side (2 to 1,024) keeps the best of the counts it sees.
fn proxy(source: &Mesh, target: usize, below: usize) -> Option<Mesh> {
    let adapter = VertexDataAdapter::new(
        meshopt::typed_to_bytes(&source.positions),
        std::mem::size_of::<[f32; 3]>(),
        0,
    )
    .expect("tightly packed positions");
    let at = |grid: u32| {
        let error = 1.0 / (grid as f32 + 0.5);
        meshopt::simplify_sloppy(&source.indices, &adapter, 0, error, None)
    };
    // Each grid's triangles counted as `flat` would keep them; only the two kept become
    // meshes.
    let (mut lo, mut hi) = (2u32, 1024u32);
    // The best grid's clustering under the target and over it: (triangles, indices).
    let mut under: Option<(usize, Vec<u32>)> = None;
    let mut over: Option<(usize, Vec<u32>)> = None;
    while lo <= hi {
        let grid = (lo + hi) / 2;
        let indices = at(grid);
        let t = indices
            .chunks_exact(3)
            .filter(|t| face_normal(&source.positions, t).is_some())
            .count();
        if t <= target {
            lo = grid + 1;
            if t > 0 && t < below && under.as_ref().is_none_or(|u| t > u.0) {
                under = Some((t, indices));
            }
        } else {
            hi = grid - 1;
            if t < below && over.as_ref().is_none_or(|o| t < o.0) {
                over = Some((t, indices));
            }
        }
    }
    under
        .or(over)
        .map(|(_, indices)| flat(&source.positions, &indices))
}

/// Triangle `t`'s corners in `positions` and its unit normal; `None` for a triangle of
/// no area.
fn face_normal(positions: &[[f32; 3]], t: &[u32]) -> Option<([[f32; 3]; 3], [f32; 3])> {
    let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
    let n = (Vec3::from(b) - Vec3::from(a)).cross(Vec3::from(c) - Vec3::from(a));
    let len = n.length();
    (len > 0.0 && len.is_finite()).then(|| ([a, b, c], (n / len).to_array()))
}

/// The triangles `indices` names in `positions` as a compact mesh with a normal per
/// face, a vertex shared where position and normal are the same; triangles of no area
/// left out.
fn flat(positions: &[[f32; 3]], indices: &[u32]) -> Mesh {
    let mut out = Mesh::default();
    let mut welded: HashMap<([u32; 3], [u32; 3]), u32> = HashMap::new();
    for t in indices.chunks_exact(3) {
        let Some((corners, n)) = face_normal(positions, t) else {
            continue;
        };
        for p in corners {
            let key = (p.map(f32::to_bits), n.map(f32::to_bits));
            let next = out.positions.len() as u32;
            let v = *welded.entry(key).or_insert(next);
            if v == next {
                out.positions.push(p);
                out.normals.push(n);
            }
            out.indices.push(v);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lod::hausdorff;

    /// An axis-aligned box from `lo` to `hi`, 12 triangles, flat normals.
    fn cuboid(lo: [f32; 3], hi: [f32; 3]) -> Mesh {
        let c = |i: usize| {
            [
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            ]
        };
        // Each face's corners, wound outwards.
        let faces: [[usize; 4]; 6] = [
            [0, 2, 6, 4],
            [1, 5, 7, 3],
            [0, 4, 5, 1],
            [2, 3, 7, 6],
            [0, 1, 3, 2],
            [4, 6, 7, 5],
        ];
        let mut m = Mesh::default();
        for f in faces {
            let p = f.map(c);
            let n = (Vec3::from(p[1]) - Vec3::from(p[0]))
                .cross(Vec3::from(p[2]) - Vec3::from(p[0]))
                .normalize()
                .to_array();
            let base = m.positions.len() as u32;
            m.positions.extend(p);
            m.normals.extend([n; 4]);
            m.indices.extend([0, 1, 2, 0, 2, 3].map(|k: u32| base + k));
        }
        m
    }

    /// A block of `n` × `n` disjoint buildings of varied heights, 4 m apart, each
    /// subdivided so that it has some triangles to lose.
    fn block(n: usize) -> Mesh {
        let mut parts = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let (x, z) = (i as f32 * 14.0, j as f32 * 14.0);
                let h = 8.0 + ((i * 7 + j * 3) % 5) as f32 * 6.0;
                parts.push(cuboid([x, 0.0, z], [x + 10.0, h, z + 10.0]).subdivide());
            }
        }
        aggregate(&parts)
    }

    #[test]
    fn disjoint_boxes_merge_far_below_half_with_measured_errors() {
        let full = block(6);
        let levels = internal_levels(&full, Reference::Full(&full)).unwrap();
        assert!(levels.len() >= 2, "{} levels", levels.len());
        assert!(
            levels.last().unwrap().mesh.triangle_count() * 4 <= full.triangle_count(),
            "{} of {}",
            levels.last().unwrap().mesh.triangle_count(),
            full.triangle_count()
        );
        for w in levels.windows(2) {
            assert!(w[1].mesh.triangle_count() < w[0].mesh.triangle_count());
            assert!(w[1].error >= w[0].error);
        }
        for l in &levels {
            l.mesh.validate().unwrap();
            // Measured afresh on other samples, the figure stored is no less (but for
            // rounding, a tenth of a millimetre) and not absurdly more.
            let fresh = hausdorff(&l.mesh, &full, 3_000).unwrap();
            assert!(l.error >= fresh * 0.999 - 1e-4, "{} < {fresh}", l.error);
            assert!(l.error <= 2.0 * fresh + 1e-3, "{} against {fresh}", l.error);
            // Lit as faces: every normal a unit vector, each triangle's its own.
            for t in l.mesh.indices.chunks_exact(3) {
                let [a, b, c] =
                    [t[0], t[1], t[2]].map(|i| Vec3::from(l.mesh.positions[i as usize]));
                let n = (b - a).cross(c - a).normalize();
                for &i in t {
                    assert!(Vec3::from(l.mesh.normals[i as usize]).dot(n) > 0.999);
                }
            }
        }
        // The coarsest level has merged or dropped buildings: fewer triangles than
        // the 36 boxes' 12 each.
        assert!(levels.last().unwrap().mesh.triangle_count() < 36 * 12);
    }

    #[test]
    fn every_chain_a_node_gets_can_be_stored() {
        // Small groups, as the leaves of a tree of small fan-out make: the clustering's
        // best count under one share may be no coarser than the level before, which
        // the stored chain refuses.
        for side in 1..=4 {
            for raise in [0.0, 3.0, 7.5] {
                let mut full = block(side);
                full.positions
                    .iter_mut()
                    .filter(|p| p[1] > 0.0)
                    .for_each(|p| p[1] += raise);
                let levels = internal_levels(&full, Reference::Full(&full)).unwrap();
                if levels.is_empty() {
                    continue;
                }
                crate::lod::stored::encode_chain(1, full.triangle_count(), &levels)
                    .unwrap_or_else(|e| panic!("{side} × {side} raised {raise}: {e}"));
            }
        }
    }

    #[test]
    fn the_source_bound_is_at_least_the_distance_to_the_full_geometry() {
        let full = block(4);
        // A coarser source: the same buildings unsubdivided are on the same surface, so
        // their own error is 0; one raised by 0.5 m lies 0.5 m off.
        let mut source = block(4);
        source.positions.iter_mut().for_each(|p| p[1] += 0.5);
        let levels = internal_levels(&source, Reference::Source { parts_error: 0.5 }).unwrap();
        assert!(!levels.is_empty());
        for l in &levels {
            let fresh = hausdorff(&l.mesh, &full, 3_000).unwrap();
            assert!(l.error >= fresh * 0.999, "{} < {fresh}", l.error);
        }
    }

    #[test]
    fn bad_input_is_an_error_and_a_tiny_source_gets_no_level() {
        let full = block(2);
        assert!(internal_levels(&Mesh::default(), Reference::Full(&full)).is_err());
        let mut nan = full.clone();
        nan.positions[5][1] = f32::NAN;
        assert!(internal_levels(&nan, Reference::Full(&full)).is_err());
        assert!(internal_levels(&full, Reference::Full(&nan)).is_err());
        assert!(internal_levels(&full, Reference::Full(&Mesh::default())).is_err());
        let bad = Reference::Source {
            parts_error: f32::NAN,
        };
        assert!(internal_levels(&full, bad).is_err());
        let one = cuboid([0.0; 3], [1.0; 3]);
        assert!(internal_levels(&one, Reference::Full(&one))
            .unwrap()
            .is_empty());
    }
}

/// A measuring aid, not a check: the internal LODs of the database named by
/// `FLANEUR_DB` by tree level (triangles, stored errors, and each level's Hausdorff
/// distance from its node's full geometry measured afresh), as
/// `FLANEUR_DB=city.flaneur cargo test --release -p flaneur --lib report_internal_lods
/// -- --ignored --nocapture` prints them.
#[cfg(test)]
mod report {
    use super::*;
    use crate::hdov::node::HNodeKind;
    use crate::lod::hausdorff;
    use crate::lod::stored::{chain_level, chain_levels};
    use crate::rtree::ObjectEntry;

    fn objects_below(
        db: &crate::Database,
        tree: &crate::hdov::HdovTree,
        n: u32,
        out: &mut Vec<ObjectEntry>,
    ) {
        match tree.node(db.store(), n).unwrap().kind {
            HNodeKind::Leaf(o) => out.extend(o),
            HNodeKind::Internal { children, .. } => {
                for c in children {
                    objects_below(db, tree, c.node, out);
                }
            }
        }
    }

    #[test]
    #[ignore]
    fn report_internal_lods() {
        let Ok(path) = std::env::var("FLANEUR_DB") else {
            return;
        };
        let db = crate::Database::open(path.as_ref()).unwrap();
        let tree = db.hdov_tree().unwrap();
        let head = tree.head(db.store()).unwrap().clone();
        println!("{path}: {:?} errors", head.proxy_errors);
        // (tree level, LOD level) -> nodes, triangles, stored error sum/max, fresh sum/max, full triangles
        let mut rows: std::collections::BTreeMap<(u16, usize), [f64; 7]> = Default::default();
        for n in 0..head.nodes {
            let node = tree.node(db.store(), n).unwrap();
            let HNodeKind::Internal { level, children } = node.kind else {
                continue;
            };
            for c in children.iter().filter(|c| !c.lods.is_empty()) {
                let mut below = Vec::new();
                objects_below(&db, tree, c.node, &mut below);
                let meshes: Vec<Mesh> = below.iter().map(|o| db.mesh(o).unwrap()).collect();
                let full = aggregate(&meshes);
                let levels = chain_levels(db.store(), &c.lods, "chain").unwrap();
                for (k, info) in levels.iter().enumerate() {
                    let (_, mesh) = chain_level(db.store(), &c.lods, "chain", |_| k).unwrap();
                    let fresh = hausdorff(&mesh, &full, ERROR_SAMPLES).unwrap() as f64;
                    let r = rows.entry((level - 1, k + 1)).or_default();
                    r[0] += 1.0;
                    r[1] += info.triangles as f64;
                    r[2] += info.error as f64;
                    r[3] = r[3].max(info.error as f64);
                    r[4] += fresh;
                    r[5] = r[5].max(fresh);
                    r[6] += full.triangle_count() as f64;
                }
            }
        }
        println!("| tree level | LOD level | nodes | triangles (sum) | full triangles (sum) | stored error mean / max (m) | Hausdorff afresh mean / max (m) |");
        println!("|---|---|---|---|---|---|---|");
        for ((tl, l), r) in rows {
            println!(
                "| {tl} | {l} | {} | {} | {} | {:.2} / {:.2} | {:.2} / {:.2} |",
                r[0],
                r[1],
                r[6],
                r[2] / r[0],
                r[3],
                r[4] / r[0],
                r[5]
            );
        }
    }
}
