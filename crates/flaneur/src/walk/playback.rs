//! The viewer of a walk along given poses: a camera path, or an iterator making them
//! as the walk asks, each frame drawn by a sink (a renderer) or by no one.

use super::buffer::ObjectBuffer;
use super::sink::{FrameFigures, FrameSink, Selection, Viewer};
use crate::error::{Error, Result};
use crate::geom::Camera;
use crate::path::{CameraPath, Pose};

/// Poses played to a sink in order: the viewer of a walk along a fixed path, or along
/// poses an iterator makes as the walk asks for them (a walk too long to hold its path),
/// each checked as a [`CameraPath`]'s are. `I` is the poses' iterator: a path's
/// ([`PathPoses`]), or any that [`Playback::poses`] is given.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, file) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # citygen::write_city(&citygen::CityConfig { objects: 40, ..Default::default() }, &scene)?;
/// # flaneur::build_from_scene(&scene, &file, &flaneur::BuildOptions::default())?;
/// use flaneur::walk::{self, Frames, Playback, WalkMode};
/// let db = flaneur::Database::open(&file)?;
/// let path = flaneur::path::street_walk(&db.bounds(), 20, 5.0, 10, 7)?;
/// let mut done = 0;
/// let mut tick = |frame: usize| done = frame + 1;
/// // A renderer would come in with `.drawn_by(&mut renderer)`.
/// let mut viewer = Playback::path(&path).with_progress(&mut tick);
/// walk::run(&db, &WalkMode::Box.into(), &mut viewer, Frames::Keep)?;
/// assert_eq!(done, 20);
/// # Ok(()) }
/// ```
// Generic over its poses rather than boxing them, so that a path's playback has no
// destructor: the sink and the progress it borrows are free again once the walk is over,
// with the playback still in scope.
pub struct Playback<'a, I = PathPoses<'a>> {
    poses: I,
    checks: PoseChecks,
    /// Whoever draws the frames; none draws nothing.
    sink: Option<&'a mut dyn FrameSink>,
    progress: Option<&'a mut dyn FnMut(usize)>,
    at: usize,
}

/// Whether [`Playback`] checks its poses as they come, and the last one's time if so.
#[derive(Clone, Copy, Debug)]
enum PoseChecks {
    /// A [`CameraPath`](crate::path::CameraPath)'s, checked when it was made.
    Made,
    /// An iterator's, each checked against the pose before (none yet: `None`).
    AsTheyCome { last_time: Option<f64> },
}

/// A camera path's poses, in order.
pub type PathPoses<'a> = std::iter::Copied<std::slice::Iter<'a, Pose>>;

impl<'a> Playback<'a> {
    /// The poses of `path` (checked when it was made), drawn by no one.
    pub fn path(path: &'a CameraPath) -> Self {
        Playback {
            poses: path.poses.iter().copied(),
            checks: PoseChecks::Made,
            sink: None,
            progress: None,
            at: 0,
        }
    }
}

impl<'a, I: Iterator<Item = Pose>> Playback<'a, I> {
    /// The poses `poses` gives, checked one by one, drawn by no one.
    pub fn poses(poses: I) -> Self {
        Playback {
            poses,
            checks: PoseChecks::AsTheyCome { last_time: None },
            sink: None,
            progress: None,
            at: 0,
        }
    }

    /// The same, each frame handed to `sink` to draw (a renderer).
    pub fn drawn_by(self, sink: &'a mut dyn FrameSink) -> Self {
        Playback {
            sink: Some(sink),
            ..self
        }
    }

    /// The same, telling `progress` the index of each frame once its figures are
    /// taken (a progress bar).
    pub fn with_progress(self, progress: &'a mut dyn FnMut(usize)) -> Self {
        Playback {
            progress: Some(progress),
            ..self
        }
    }
}

impl<I: Iterator<Item = Pose>> FrameSink for Playback<'_, I> {
    fn frame(
        &mut self,
        index: usize,
        camera: &Camera,
        buffer: &ObjectBuffer,
        selection: &mut Selection<'_>,
    ) -> Result<()> {
        match &mut self.sink {
            Some(sink) => sink.frame(index, camera, buffer, selection),
            None => Ok(()),
        }
    }

    fn draws(&self) -> bool {
        self.sink.as_ref().is_some_and(|s| s.draws())
    }

    fn lod_tau(&self) -> Option<f32> {
        self.sink.as_ref().and_then(|s| s.lod_tau())
    }

    fn aspect(&self) -> Option<f32> {
        self.sink.as_ref().and_then(|s| s.aspect())
    }

    fn lod_restart(&mut self) -> bool {
        self.sink.as_mut().is_some_and(|s| s.lod_restart())
    }

    fn lod_settled(&self) -> bool {
        self.sink.as_ref().is_some_and(|s| s.lod_settled())
    }

    fn lod_adapt_ahead(&self) -> bool {
        self.sink.as_ref().is_some_and(|s| s.lod_adapt_ahead())
    }

    fn lod_remote(&mut self) -> Option<Box<dyn super::RemoteRefinements>> {
        self.sink.as_mut().and_then(|s| s.lod_remote())
    }
}

impl<I: Iterator<Item = Pose>> Viewer for Playback<'_, I> {
    fn next_pose(&mut self, frame: usize) -> Result<Option<Pose>> {
        self.at = frame;
        let Some(pose) = self.poses.next() else {
            return match self.checks {
                PoseChecks::Made if frame == 0 => {
                    Err(Error::Invalid("the camera path has no poses".into()))
                }
                _ => Ok(None),
            };
        };
        if let PoseChecks::AsTheyCome { last_time } = &mut self.checks {
            crate::path::check_pose(&pose, *last_time)
                .map_err(|what| Error::Invalid(format!("camera path, pose {frame}: {what}")))?;
            *last_time = Some(pose.time);
        }
        Ok(Some(pose))
    }

    fn figures(&mut self, _: &FrameFigures) {
        if let Some(progress) = &mut self.progress {
            progress(self.at);
        }
    }
}
