//! What every encoding of a progressive mesh shares: the magic its bytes begin with, and
//! what each vertex split decoded from them must be. Version 1 (`codec`) and version 2
//! (`compact`) both check every split with it, so that bytes of either that pass are a
//! mesh `PmCursor` and `SelectiveMesh` walk without an index check failing; it lies
//! below both because `codec` hands version-2 bytes on to `compact`.

use super::vsplit::VertexSplit;

/// The first four bytes of an encoded progressive mesh.
pub const PM_MAGIC: [u8; 4] = *b"FLPM";

/// What split `i` of a progressive mesh of `nv` base vertices and `nt` base triangles
/// must be, whatever its encoding: it names only vertices and triangle slots that exist
/// before it, its corners are below 3, its numbers finite, and the first split joins
/// none before it. The fault, for the caller to prefix with the split.
pub(super) fn check_split(
    split: &VertexSplit,
    i: usize,
    nv: usize,
    nt: usize,
) -> std::result::Result<(), String> {
    let (vertices_before, slots_before) = (nv + i, nt + 2 * i);
    let v_p = split.v_p;
    if v_p as usize >= vertices_before {
        return Err(format!(
            "v_p {v_p} does not exist before it ({vertices_before} vertices)"
        ));
    }
    for p in [split.v_l, split.v_r].into_iter().flatten() {
        if p as usize >= vertices_before || p == v_p {
            return Err(format!(
                "pivot {p} is v_p or does not exist before it ({vertices_before} vertices)"
            ));
        }
    }
    if split.corners.iter().any(|&c| c > 2) {
        return Err(format!("corners {:?} (each 0, 1 or 2)", split.corners));
    }
    if split.joins_previous && i == 0 {
        return Err("the first split joins no split before it".into());
    }
    let (position, normal, error) = (split.position, split.normal, split.error);
    let finite = position.iter().chain(&normal).all(|c| c.is_finite());
    if !(finite && error >= 0.0 && error.is_finite()) {
        return Err(format!(
            "position {position:?}, normal {normal:?} or error {error} is not finite"
        ));
    }
    let adjusted = &split.adjusted;
    if adjusted.iter().any(|&f| f as usize >= slots_before)
        || adjusted.windows(2).any(|w| w[0] >= w[1])
    {
        return Err(format!(
            "adjusted triangles {adjusted:?} are not ascending below {slots_before}"
        ));
    }
    Ok(())
}
