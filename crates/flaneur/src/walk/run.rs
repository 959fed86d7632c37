//! The one way to walk: a [`WalkConfig`] and a [`Viewer`] in, every frame kept or handed
//! on, the walk's [`Report`] out. Each mode's folder has the walk `run` calls; adding a
//! mode is a folder and a variant of [`WalkConfig`], [`Frame`] and [`Report`].

use super::config::WalkConfig;
use super::frame::Frame;
use super::report::Report;
use super::scene::SceneTree;
use super::sink::Viewer;
use super::walk_lods::WalkLods;
use crate::database::Database;
use crate::error::Result;

/// What a walk does with each frame's figures.
pub enum Frames<'a> {
    /// Keeps them in the report (a walk of a path a person can read).
    Keep,
    /// Hands each to the closure as its frame ends and keeps none (a report's frames
    /// are then empty, its summary whole): a walk of any length in constant memory.
    Each(&'a mut dyn FnMut(&Frame) -> Result<()>),
}

/// Walks `db` under `cfg`, the poses coming from `viewer` until it has none (a
/// [`Playback`](super::Playback) of a path or of generated poses, or a person at a
/// window), each frame handed to `viewer` to draw and its figures kept or handed on as
/// `frames` says.
///
/// ```
/// # fn main() -> flaneur::Result<()> {
/// # let dir = tempfile::tempdir().unwrap();
/// # let (scene, file) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
/// # citygen::write_city(&citygen::CityConfig { objects: 60, ..Default::default() }, &scene)?;
/// # flaneur::build_from_scene(&scene, &file, &flaneur::BuildOptions::default())?;
/// use flaneur::walk::{self, review, Frames, Playback, WalkConfig};
/// let db = flaneur::Database::open(&file)?;
/// let path = flaneur::path::street_walk(&db.bounds(), 30, 5.0, 10, 7)?;
/// let cfg = WalkConfig::Review(review::ReviewConfig::preset(review::Preset::Np));
/// let report = walk::run(&db, &cfg, &mut Playback::path(&path), Frames::Keep)?;
/// assert_eq!(report.frames_walked(), 30);
/// let review: review::WalkReport = report.try_into()?;
/// assert!(review.frames[0].queried && review.summary.queries >= 1);
/// # Ok(()) }
/// ```
pub fn run(
    db: &Database,
    cfg: &WalkConfig,
    viewer: &mut dyn Viewer,
    frames: Frames<'_>,
) -> Result<Report> {
    WalkState::new(db).run(cfg, viewer, frames)
}

/// What walks at one viewer keep from one to the next: LOD selection's levels read and
/// objects refined, and the memory scene tree once loaded. [`run`] starts from nothing;
/// a window that restarts its walk when its person changes the mode keeps a state.
pub struct WalkState<'db> {
    db: &'db Database,
    lods: WalkLods<'db>,
    tree: Option<SceneTree>,
}

impl<'db> WalkState<'db> {
    /// Nothing read yet.
    pub fn new(db: &'db Database) -> WalkState<'db> {
        WalkState {
            db,
            lods: WalkLods::new(db),
            tree: None,
        }
    }

    /// With `tree`, `db`'s memory scene tree loaded already (with a progress bar, say),
    /// for the VSC, PB and CONV walks.
    pub fn with_scene_tree(self, tree: SceneTree) -> WalkState<'db> {
        WalkState {
            tree: Some(tree),
            ..self
        }
    }

    /// Whether the memory scene tree is loaded.
    pub fn has_scene_tree(&self) -> bool {
        self.tree.is_some()
    }

    /// [`run`], from what the walks before it left.
    pub fn run(
        &mut self,
        cfg: &WalkConfig,
        viewer: &mut dyn Viewer,
        frames: Frames<'_>,
    ) -> Result<Report> {
        let db = self.db;
        let lods = &mut self.lods;
        let mut keep = Kept::new(frames);
        Ok(match cfg {
            WalkConfig::Review(c) => {
                let mut r =
                    super::review::walk(db, c, lods, viewer, &mut |f| keep.take(f, Frame::Review))?;
                r.frames = keep.into_frames(|f| match f {
                    Frame::Review(f) => Some(f),
                    _ => None,
                });
                Report::Review(r)
            }
            WalkConfig::Pvs(c) => {
                let mut r =
                    super::pvs::walk(db, *c, lods, viewer, &mut |f| keep.take(f, Frame::Pvs))?;
                r.frames = keep.into_frames(|f| match f {
                    Frame::Pvs(f) => Some(f),
                    _ => None,
                });
                Report::Pvs(r)
            }
            WalkConfig::Visual(c) => {
                let mut r =
                    super::visual::walk(db, c, lods, viewer, &mut |f| keep.take(f, Frame::Visual))?;
                r.frames = keep.into_frames(|f| match f {
                    Frame::Visual(f) => Some(f),
                    _ => None,
                });
                Report::Visual(r)
            }
            WalkConfig::Scene(c) => {
                if self.tree.is_none() {
                    self.tree = Some(SceneTree::load(db, &crate::progress::Silent)?);
                }
                let tree = self.tree.as_mut().expect("loaded above");
                let mut r = super::scene::walk(db, tree, c, lods, viewer, &mut |f| {
                    keep.take(f, Frame::Scene)
                })?;
                r.frames = keep.into_frames(|f| match f {
                    Frame::Scene(f) => Some(f),
                    _ => None,
                });
                Report::Scene(r)
            }
        })
    }
}

/// [`Frames`] as a walk goes: the frames kept, or each handed on.
struct Kept<'a> {
    frames: Frames<'a>,
    kept: Vec<Frame>,
}

impl<'a> Kept<'a> {
    fn new(frames: Frames<'a>) -> Kept<'a> {
        Kept {
            frames,
            kept: Vec::new(),
        }
    }

    /// Takes the mode's frame `f`, as a [`Frame`] by `wrap`.
    fn take<F: Clone>(&mut self, f: &F, wrap: fn(F) -> Frame) -> Result<()> {
        match &mut self.frames {
            Frames::Keep => self.kept.push(wrap(f.clone())),
            Frames::Each(each) => each(&wrap(f.clone()))?,
        }
        Ok(())
    }

    /// The kept frames, the mode's again by `unwrap`.
    fn into_frames<F>(self, unwrap: fn(Frame) -> Option<F>) -> Vec<F> {
        self.kept.into_iter().filter_map(unwrap).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::walk::pvs::PvsWalkReport;
    use crate::walk::review::WalkReport;
    use crate::walk::{Playback, WalkMode};

    #[test]
    fn frames_handed_on_are_the_frames_kept_and_a_report_is_only_its_modes() {
        let dir = tempfile::tempdir().unwrap();
        let (scene, file) = (dir.path().join("c.scene"), dir.path().join("c.flaneur"));
        let city = citygen::CityConfig {
            objects: 40,
            ..Default::default()
        };
        citygen::write_city(&city, &scene).unwrap();
        crate::build_from_scene(&scene, &file, &crate::BuildOptions::default()).unwrap();
        let db = Database::open(&file).unwrap();
        let path = crate::path::street_walk(&db.bounds(), 25, 5.0, 10, 7).unwrap();
        let cfg = WalkConfig::from(WalkMode::Box);
        let kept = run(&db, &cfg, &mut Playback::path(&path), Frames::Keep).unwrap();
        let mut handed = Vec::new();
        let mut each = |f: &Frame| {
            handed.push(f.clone());
            Ok(())
        };
        let streamed = run(
            &db,
            &cfg,
            &mut Playback::path(&path),
            Frames::Each(&mut each),
        );
        assert_eq!(streamed.unwrap().frames(), Vec::new());
        // Times aside, the frames are the same walk's.
        let untimed = |f: &Frame| match f {
            Frame::Review(f) => (f.frame, f.objects_drawn, f.index_pages, f.mesh_pages),
            other => panic!("a BOX walk gave {other:?}"),
        };
        let kept_frames: Vec<_> = kept.frames().iter().map(untimed).collect();
        assert_eq!(kept_frames, handed.iter().map(untimed).collect::<Vec<_>>());
        assert_eq!((kept.frames_walked(), kept_frames.len()), (25, 25));
        assert!(WalkReport::try_from(kept.clone()).is_ok());
        let err = PvsWalkReport::try_from(kept).unwrap_err().to_string();
        assert!(
            err.contains("REVIEW or BOX walk's report is not a PVS"),
            "{err}"
        );
    }
}
