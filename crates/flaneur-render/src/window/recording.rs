//! Recorded paths: what `--record` saves of a session's poses. Apart because it is
//! the window's one way out to a file, and what it writes must read back as a path.

use std::path::Path;

use flaneur::error::Result;
use flaneur::walk::{CameraPath, Pose};

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
