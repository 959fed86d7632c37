//! LOD selection as a walk runs it for its viewer ([`WalkLods`]): the selector under the
//! τ the viewer wants, made again when it wants another, and the objects refined
//! elsewhere that it draws from there; what the walk session hands each frame's
//! viewer as its [`Selection`](super::Selection).

use super::buffer::{Loaded, ObjectBuffer};
use super::lod_select::{Drawn, LodCounts, LodSelector, RefinedView, Refinements, REFINED};
use super::remote::RemoteRefinements;
use crate::database::Database;
use crate::error::Result;
use crate::geom::Camera;

/// LOD selection as a walk runs it for its viewer: a selector under the τ the viewer
/// [wants](super::FrameSink::lod_tau), made again when it wants another (or
/// [asks](super::FrameSink::lod_restart) to start afresh). A session of several walks
/// at one window hands the same one from walk to walk, so that the levels read and the
/// objects refined so far stay so when a walk restarts.
///
/// Made [`Default`], it has no database to read levels from: every frame at full detail.
#[derive(Default)]
pub(crate) struct WalkLods<'db> {
    db: Option<&'db Database>,
    selector: Option<LodSelector<'db>>,
    /// Objects refined elsewhere (a stream server's landmarks), drawn from there, and
    /// how many draws so far.
    remote: Option<Box<dyn RemoteRefinements>>,
    streamed_draws: u64,
}

/// What a viewer wants of LOD selection on a frame.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LodWanted {
    pub tau: Option<f32>,
    pub restart: bool,
    /// Whether an object whose LOD data cannot be read is drawn at full detail, told
    /// of, rather than the frame failing ([`LodSelector::tolerating_damage`]).
    pub tolerant: bool,
    /// Whether a large object is refined from the frame it is first drawn
    /// ([`LodSelector::settling`]).
    pub settled: bool,
    /// Whether refined objects adapt ahead ([`LodSelector::adapting_ahead`]).
    pub ahead: bool,
}

impl<'db> WalkLods<'db> {
    /// Object `id`'s name in the database walked, where it keeps one; a names table that
    /// cannot be read names nothing (the walk goes on).
    pub(crate) fn object_name(&self, id: u64) -> Option<String> {
        self.db?.object_name(id).ok().flatten()
    }

    /// LOD selection over `db`, before any frame.
    pub(crate) fn new(db: &'db Database) -> WalkLods<'db> {
        WalkLods {
            db: Some(db),
            selector: None,
            remote: None,
            streamed_draws: 0,
        }
    }

    /// Draws the objects `remote` refines from it from now on (in place of any before).
    pub(crate) fn set_remote(&mut self, remote: Box<dyn RemoteRefinements>) {
        self.remote = Some(remote);
    }

    /// What the objects refined elsewhere did lately, in words.
    pub(crate) fn remote_status(&self) -> Option<String> {
        self.remote.as_ref().and_then(|r| r.status())
    }

    /// The frame is drawn: what adapts ahead starts for the next, if the viewer did
    /// not start it when it uploaded.
    pub(crate) fn frame_drawn(&mut self) -> Result<()> {
        self.uploaded()
    }

    /// What reading the database over HTTP has cost so far; `None` for a local file.
    pub(crate) fn remote_stats(&self) -> Option<crate::store::RemoteStats> {
        self.db.and_then(Database::remote_stats)
    }

    /// The frame's selection of `culled` (the objects of `buffer` in view of `camera`)
    /// as `want` says.
    pub(crate) fn select<'f>(
        &'f mut self,
        want: LodWanted,
        camera: &Camera,
        buffer: &ObjectBuffer,
        culled: &'f [&'f Loaded],
    ) -> Result<super::Selection<'f>> {
        if want.restart || self.selector.as_ref().map(LodSelector::tau) != want.tau {
            self.selector = match (want.tau, self.db) {
                (Some(tau), Some(db)) => {
                    let mut s = LodSelector::new(db, tau)?;
                    if want.tolerant {
                        s = s.tolerating_damage();
                    }
                    if want.settled {
                        s = s.settling();
                    }
                    if want.ahead {
                        s = s.adapting_ahead();
                    }
                    Some(s)
                }
                _ => None,
            };
        }
        let full = || culled.iter().map(|o| Drawn::full(o)).collect();
        let pages_before = self.selector.as_ref().map_or(0, |s| s.counts.pages);
        let started = std::time::Instant::now();
        // Objects refined elsewhere are drawn from there, with LOD selection only.
        let remote = match (&mut self.remote, &self.selector) {
            (Some(r), Some(_)) => {
                r.frame(camera)?;
                Some(&**r)
            }
            _ => None,
        };
        let from_remote =
            |o: &Loaded| remote.is_some_and(|r| !o.is_group() && r.refines(o.entry.id));
        let local: Vec<&Loaded> = match remote {
            Some(_) => culled.iter().copied().filter(|o| !from_remote(o)).collect(),
            None => Vec::new(),
        };
        let (drawn, damaged, failed) = match &mut self.selector {
            None => (full(), Vec::new(), None),
            Some(s) => {
                let chosen = s.select(
                    camera,
                    buffer,
                    if remote.is_some() { &local } else { culled },
                );
                let damaged = s.take_damaged();
                match chosen {
                    Ok(d) => (d, damaged, None),
                    Err(e) if want.tolerant => (full(), damaged, Some(e.to_string())),
                    Err(e) => return Err(e),
                }
            }
        };
        // In the culled order: each object from elsewhere where it stands.
        let drawn = match remote {
            Some(r) if failed.is_none() => {
                let mut chosen = drawn.into_iter();
                self.streamed_draws += (culled.len() - local.len()) as u64;
                culled
                    .iter()
                    .map(|o| match from_remote(o) {
                        true => Some(Drawn {
                            id: o.entry.id,
                            bounds: o.entry.bounds,
                            level: REFINED,
                            mesh: o.mesh.clone(),
                            triangles: r.triangles(o.entry.id),
                        }),
                        false => chosen.next(),
                    })
                    .collect::<Option<Vec<_>>>()
                    .expect("one choice for each object drawn here")
            }
            _ => drawn,
        };
        let select_ms = started.elapsed().as_secs_f64() * 1e3;
        Ok(super::Selection {
            culled,
            drawn,
            select_ms,
            pages: self.selector.as_ref().map_or(0, |s| s.counts.pages) - pages_before,
            lod: self.selector.as_ref().map(|s| LodCounts {
                streamed_draws: self.streamed_draws,
                ..s.counts
            }),
            damaged,
            failed,
            refinements: Some(self as &mut dyn Refinements),
        })
    }
}

/// A renderer finds an object refined elsewhere there, and the rest with the selector.
impl Refinements for WalkLods<'_> {
    fn refined(&mut self, id: u64) -> Option<RefinedView<'_>> {
        match (&mut self.remote, &mut self.selector) {
            (Some(r), Some(_)) if r.refines(id) => r.refined(id),
            (_, Some(s)) => Refinements::refined(s, id),
            (_, None) => None,
        }
    }

    fn uploaded(&mut self) -> Result<()> {
        match &mut self.selector {
            Some(s) => s.launch_ahead(),
            None => Ok(()),
        }
    }
}
