//! Internal LODs (Shou 2002 §5.6): coarse representations of the objects below a node,
//! made by the LOD core's quadric simplification from the **simplified** geometry of
//! the node's children (its objects' coarsest stored levels for a leaf, its children's
//! coarsest internal LODs above), as the thesis chooses for fidelity.
//!
//! Choices the thesis leaves open, made here: a node has up to three internal LODs, of
//! about 1/2, 1/8 and 1/32 of its source's triangles, so that its finest has fewer
//! triangles than the sum of its children's coarsest (the thesis's rule); none smaller
//! than [`MIN_TRIANGLES`]. A source the simplifier cannot shrink gives the node no
//! internal LOD, and the search then never stops there.
//!
//! The LOD core collapses edges; it does not contract pairs of unconnected vertices
//! as Garland's qslim does, so it cannot merge the disjoint objects of a group: a group
//! of buildings already at their coarsest levels simplifies to about half their
//! triangles and no further, and most nodes get one internal LOD rather than three.

use crate::error::Result;
use crate::lod::{Level, ProgressiveMesh};
use crate::scene::Mesh;

/// The share of its source's triangles each internal LOD keeps, finest first.
pub const LEVEL_SHARES: [f64; 3] = [0.5, 0.125, 1.0 / 32.0];
/// No internal LOD has fewer triangles.
pub const MIN_TRIANGLES: usize = 8;

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

/// The internal LODs of a node whose source (its children's simplified geometry, as
/// one mesh) is `source`, finest first: each strictly coarser than the one before and
/// than the source. Empty when the source cannot be simplified that far.
pub fn internal_levels(source: &Mesh) -> Result<Vec<Level>> {
    let full = source.triangle_count();
    if full < 2 * MIN_TRIANGLES {
        return Ok(Vec::new());
    }
    let pm = ProgressiveMesh::build(source)?;
    let mut levels: Vec<Level> = Vec::new();
    let mut finer = full;
    for share in LEVEL_SHARES {
        let target = (full as f64 * share) as usize;
        if target < MIN_TRIANGLES {
            break;
        }
        let splits = pm.splits_for_triangles(target);
        let mesh = pm.cursor_at(splits)?.to_mesh();
        let t = mesh.triangle_count();
        if t >= finer || t == 0 {
            continue;
        }
        finer = t;
        levels.push(Level {
            mesh,
            splits,
            error: pm.error_after(splits),
        });
    }
    Ok(levels)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_group_is_simplified_below_its_parts() {
        let a = crate::lod::bumpy_torus(600);
        let mut b = a.clone();
        b.positions.iter_mut().for_each(|p| p[0] += 10.0);
        let source = aggregate([&a, &b]);
        assert_eq!(source.triangle_count(), 2 * a.triangle_count());
        let levels = internal_levels(&source).unwrap();
        assert!(!levels.is_empty());
        assert!(levels[0].mesh.triangle_count() <= source.triangle_count() / 2);
        for w in levels.windows(2) {
            assert!(w[1].mesh.triangle_count() < w[0].mesh.triangle_count());
            assert!(w[1].error >= w[0].error);
        }
        // A source too small to simplify gives no internal LOD.
        let tiny = aggregate([&Mesh::default()]);
        assert!(internal_levels(&tiny).unwrap().is_empty());
    }
}
