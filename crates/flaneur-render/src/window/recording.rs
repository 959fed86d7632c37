//! Recorded paths: what `--record` saves of a session's poses, and the pace a path
//! given to `--play` goes at. Apart from steering because a played path replaces the
//! person, and what is saved must play back as it was walked.

use std::path::Path;
use std::time::{Duration, Instant};

use super::WalkWindow;
use flaneur::error::Result;
use flaneur::path::{CameraPath, Pose};

impl WalkWindow {
    /// Holds the played pose `p` back until its time, counted from the first pose
    /// played since the walk (re)started.
    pub(super) fn wait_for(&mut self, p: &Pose) {
        // Played at the pace it was walked: a frame drawn early waits for
        // its pose's time; a late one does not catch up.
        let (t0, started) = *self.play_clock.get_or_insert((p.time, Instant::now()));
        let due = Duration::from_secs_f64((p.time - t0).max(0.0));
        if let Some(wait) = due.checked_sub(started.elapsed()) {
            std::thread::sleep(wait);
        }
    }
}

/// Where `--record` writes a session's poses: a path CSV that `--play` (and `flaneur
/// walk --path`) read back.
pub fn save_recording(poses: &[Pose], path: &Path) -> Result<()> {
    // Restarts after a change begin a new clock: renumber times so they increase.
    let mut out = Vec::with_capacity(poses.len());
    let mut t = 0.0;
    for (i, p) in poses.iter().enumerate() {
        if i > 0 {
            let dt = p.time - poses[i - 1].time;
            t += if dt > 0.0 { dt } else { 1.0 / 60.0 };
        }
        out.push(Pose { time: t, ..*p });
    }
    CameraPath::new(out)?.save_csv(path)
}
