//! Playing a path at its poses' times: a walk paced at `speed` times real time waits,
//! before each frame, until its pose is due on the walk's clock, so that the loader
//! threads get the real time a viewer would give them.

use std::time::{Duration, Instant};

/// Waits until the pose at `time` (seconds of the path) is due, the path having started
/// at `start` when `clock` did and playing `speed` times faster than real time; returns
/// at once for a pose already late.
pub(crate) fn wait_until_due(time: f64, start: f64, speed: f32, clock: Instant) {
    let due = Duration::from_secs_f64(((time - start) / f64::from(speed)).max(0.0));
    if let Some(wait) = due.checked_sub(clock.elapsed()) {
        std::thread::sleep(wait);
    }
}
