//! The settings every walk mode shares, with their defaults and checks: the frustum's
//! depth, a disk cell's scale factor, the prefetch factor k, the playback speed and the
//! object buffer's budget. REVIEW set them first (Shou 2002 §4.4); PVS, VISUAL and the
//! scene tree's walks, the CLI and the experiments that sweep them take them from here.

use crate::error::{Error, Result};

/// The thesis's prefetch factor k (§4.4), seconds.
pub const DEFAULT_K: f32 = 0.8;
/// SF: the thesis does not give its default. 1.2 is one of the sizes of its Table 4.2;
/// on the demo city's pattern table (`flaneur bench patterns`) it gives Optimal 10-25 %
/// of BOX's disk I/Os per query (the thesis: 9-21 %; measured again once a frame's count
/// included what the prefetch thread reads while the viewer waits for the clock, where an
/// earlier measure gave 4-14 %), while a cell still holds the frustum for 100 m of
/// forward motion. 1.5 gave a slow walk no query after the first in a minute.
pub const DEFAULT_SF: f32 = 1.2;
/// The thesis's frustum depth (§4.4), metres.
pub const DEFAULT_FAR: f32 = 1000.0;
/// Walks with prefetching play four times faster than real time by default: a
/// minute's path in 15 s, the prefetch thread getting a quarter of a viewer's time.
pub const DEFAULT_PACE: f32 = 4.0;
/// The thesis capped memory at 20 MB for objects of a few hundred bytes on disk; our
/// objects are 20 KB, so the default budget is scaled to hold a disk cell of the demo city.
pub const DEFAULT_MEMORY_BUDGET: usize = 256 << 20;

/// A playback speed must be a positive factor of real time.
pub fn check_pace(pace: f32) -> Result<()> {
    if !(pace.is_finite() && pace > 0.0) {
        return Err(Error::Invalid(format!(
            "playback speed {pace} must be a positive factor of real time"
        )));
    }
    Ok(())
}

/// A disk cell's scale factor SF must be at least 1.
pub fn check_sf(sf: f32) -> Result<()> {
    if !(sf.is_finite() && sf >= 1.0) {
        return Err(Error::Invalid(format!(
            "scale factor SF {sf} must be a number of at least 1"
        )));
    }
    Ok(())
}

/// A prefetch factor k must be a non-negative number of seconds.
pub fn check_k(k: f32) -> Result<()> {
    if !(k.is_finite() && k >= 0.0) {
        return Err(Error::Invalid(format!(
            "prefetch factor k {k} must be a non-negative number"
        )));
    }
    Ok(())
}

/// A frustum's depth must be more than a metre.
pub fn check_far(far: f32) -> Result<()> {
    if !(far.is_finite() && far > 1.0) {
        return Err(Error::Invalid(format!(
            "frustum depth {far} must be more than a metre"
        )));
    }
    Ok(())
}

/// A memory budget must be more than 0 bytes.
pub fn check_budget(bytes: usize) -> Result<()> {
    if bytes == 0 {
        return Err(Error::Invalid(
            "the memory budget must be more than 0 bytes".into(),
        ));
    }
    Ok(())
}

/// Whether `tau` can be the screen rule's threshold: a fraction of the viewport within
/// [0, 1), 0 letting no internal LOD pass.
pub(crate) fn check_screen_tau(tau: f32) -> Result<()> {
    if !(0.0..1.0).contains(&tau) {
        return Err(Error::Invalid(format!(
            "the screen rule's τ = {tau}: give a fraction of the viewport within [0, 1) (0: no internal LOD passes)"
        )));
    }
    Ok(())
}
