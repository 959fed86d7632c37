//! An option's value as a refusal names it. The conservative test's own checks
//! (`conservative`) and the cost a build checks first (`cost`) both refuse values and
//! name them as they were typed, so the two share this one way of writing them.

/// An option's value as a person would have typed it: `1e-9`, not `0.000000001`.
pub(crate) fn shown(v: f32) -> String {
    if v != 0.0 && !(1e-3..1e7).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        v.to_string()
    }
}
