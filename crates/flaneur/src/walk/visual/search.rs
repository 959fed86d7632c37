//! What every VISUAL walk searches with: the HDoV-tree searched from a viewcell (or a
//! disk cell queried outside cells), each find read at the level it deserves, and a
//! frame begun and finished around it; a next cell's prefetch answered the same way.

use crate::cache::BufferPool;
use crate::database::Database;
use crate::error::{Error, Result};
use crate::geom::Camera;
use crate::geom::DEFAULT_FOV;
use crate::hdov::{Found, Loader, NodeErrors, Scheme, ScreenRule, Selection};
use crate::prefetch::motion::MotionTrack;
use crate::rtree::ObjectEntry;
use crate::scene::Mesh;
use crate::store::{IoStats, PageKind};
use crate::walk::buffer::{Loaded, ObjectBuffer, GROUP_ID};
use crate::walk::cells::viewcell_holding;
use crate::walk::session::{Culled, FrameAt};
use crate::walk::threads::pace::wait_until_due;
use crate::walk::visual::{faint_tau_scale, screen_test, VisualConfig, VisualFrame};
use std::collections::HashMap;
use std::time::Instant;

/// One find of a search (or of the fallback's query), at the level it deserves.
#[derive(Clone, Debug)]
pub(super) struct Piece {
    /// Its id in the buffer: the object's, or the node's with [`GROUP_ID`].
    pub key: u64,
    pub level: usize,
    pub found: Found,
}

/// A prefetched cell's finds, and the meshes the thread read for them.
pub(super) struct Prefetched {
    pub(super) cell: u32,
    pub(super) pieces: Vec<Piece>,
    pub(super) loaded: Vec<Loaded>,
    /// Finds it could not read (a viewer that walks on), with why.
    pub(super) failed: Vec<(u64, Error)>,
}

/// What the prefetch thread is asked: a cell, and what the buffer held at which level.
pub(super) struct Request {
    pub(super) cell: u32,
    pub(super) held: HashMap<u64, usize>,
}

/// A cell's finds at their levels, those whose level could not be read (with why),
/// and the search's time, ms.
pub(super) struct Finds {
    pub pieces: Vec<Piece>,
    pub failed: Vec<(u64, Error)>,
    pub ms: f64,
}

/// What both threads search with.
pub(super) struct Searcher<'a> {
    pub db: &'a Database,
    pub eta: f32,
    pub scheme: Scheme,
    pub pool: Option<&'a BufferPool<'a>>,
    pub tolerant: bool,
    /// Whether objects carry their DoV to LOD selection.
    pub dov_tau: bool,
    /// Whether LOD selection draws objects at the finer of the level they were loaded
    /// at (eq. 5.6's) and the screen-space one.
    pub finer_of: bool,
    /// The rule that picks nodes' internal LODs, and the τ the screen rule holds them to.
    pub selection: Selection,
    pub tau: f32,
    /// τ's stretch for an object of DoV at most η under the screen rule.
    pub faint_tau: f32,
    /// The nodes' internal LODs' stored errors read so far (the screen rule's).
    pub errors: NodeErrors,
}

impl Searcher<'_> {
    /// The finds of `cell`, each at the level `loader` says it deserves (those whose
    /// level could not be read left apart when tolerant; otherwise the error).
    pub(super) fn finds(&self, loader: &mut Loader<'_>, cell: u32) -> Result<Finds> {
        let t = Instant::now();
        let screen = self.screen_rule(cell)?;
        let result = self.db.hdov_search_screened(
            cell,
            self.eta,
            Some(self.scheme),
            self.pool,
            screen.as_ref(),
        )?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        loader.learn(&result.found);
        let mut pieces = Vec::with_capacity(result.found.len());
        // A node whose errors could not be read was searched past (tolerant only): its
        // objects are found instead, and the damage told.
        let mut failed: Vec<(u64, Error)> = self
            .errors
            .take_damaged()
            .into_iter()
            .map(|(node, e)| (GROUP_ID | node as u64, e))
            .collect();
        for found in result.found {
            let key = key_of(&found)?;
            match loader.level(&found) {
                Ok(level) => {
                    let level = self.screened(&found, level, screen.as_ref());
                    pieces.push(Piece { key, level, found })
                }
                Err(e) if self.tolerant => failed.push((key, e)),
                Err(e) => return Err(e),
            }
        }
        Ok(Finds { pieces, failed, ms })
    }

    /// The screen rule from `cell`, under ours; `None` under the thesis's selection.
    fn screen_rule(&self, cell: u32) -> Result<Option<ScreenRule<'_>>> {
        Ok(match self.selection {
            Selection::Thesis => None,
            Selection::Screen => Some(ScreenRule {
                test: screen_test(self.db, cell, self.tau, DEFAULT_FOV)?,
                errors: &self.errors,
                tolerant: self.tolerant,
            }),
        })
    }

    /// The level a find is read at: the loader's (eqs. 5.5–5.6), or for a node under the
    /// screen rule the finer of that and the coarsest internal LOD whose error passes
    /// (the search stopped there because one does; levels count from 1).
    fn screened(&self, found: &Found, level: usize, screen: Option<&ScreenRule<'_>>) -> usize {
        let (Some(rule), Found::Node { node, mbr, .. }) = (screen, found) else {
            return level;
        };
        match self.errors.known(*node) {
            Some(errors) => match rule.test.coarsest_fit(&errors, mbr) {
                Some(fit) => level.min(fit + 1),
                None => level,
            },
            None => level,
        }
    }

    /// How many finds `cell` has, searched apart from the walk's figures (no node cache).
    pub(super) fn count(&self, cell: u32) -> Result<usize> {
        let screen = self.screen_rule(cell)?;
        let found = self.db.hdov_search_screened(
            cell,
            self.eta,
            Some(self.scheme),
            None,
            screen.as_ref(),
        )?;
        Ok(found.found.len())
    }

    /// The prefetch thread's work: `req`'s cell searched, and what the buffer did not
    /// hold at its level read.
    pub(super) fn prefetch(&self, loader: &mut Loader<'_>, req: &Request) -> Result<Prefetched> {
        let Finds {
            pieces, mut failed, ..
        } = self.finds(loader, req.cell)?;
        let mut loaded = Vec::new();
        for p in &pieces {
            if req.held.get(&p.key) == Some(&p.level) {
                continue;
            }
            match read(loader, p, self) {
                Ok(l) => loaded.push(l),
                Err(e) if self.tolerant => failed.push((p.key, e)),
                Err(e) => return Err(e),
            }
        }
        Ok(Prefetched {
            cell: req.cell,
            pieces,
            loaded,
            failed,
        })
    }
}

/// The viewcell of the HDoV-tree whose box holds `p` ([`viewcell_holding`]).
pub(super) fn cell_at(db: &Database, p: glam::Vec3) -> Result<Option<u32>> {
    Ok(match viewcell_holding(db, p)? {
        Some(c) if db.hdov_head()?.slot(c).is_some() => Some(c),
        _ => None,
    })
}

/// The id a find has in the buffer.
pub(super) fn key_of(found: &Found) -> Result<u64> {
    match found {
        Found::Object { entry, .. } if entry.id & GROUP_ID != 0 => Err(Error::Invalid(format!(
            "object {} has an id with its top bit set, which VISUAL keeps for HDoV nodes",
            entry.id
        ))),
        Found::Object { entry, .. } => Ok(entry.id),
        Found::Node { node, .. } => Ok(GROUP_ID | *node as u64),
    }
}

/// `piece` read at its level, as the buffer holds it, with what LOD selection is to
/// know of it as `search` says (its DoV, how fine it may be drawn).
pub(super) fn read(
    loader: &mut Loader<'_>,
    piece: &Piece,
    search: &Searcher<'_>,
) -> Result<Loaded> {
    let mesh = loader.mesh(&piece.found, piece.level)?;
    Ok(loaded(piece, mesh, piece.level, search))
}

/// `piece` as the buffer holds it with `mesh`, its level `level`, and what LOD
/// selection is to know of it as `search` says.
pub(super) fn loaded(piece: &Piece, mesh: Mesh, level: usize, search: &Searcher<'_>) -> Loaded {
    let entry = match &piece.found {
        Found::Object { entry, .. } => *entry,
        Found::Node { mbr, lods, .. } => ObjectEntry {
            id: piece.key,
            bounds: *mbr,
            mesh: *lods,
            triangles: mesh.triangle_count() as u32,
            kind: 0,
        },
    };
    let mut loaded = Loaded::at_level(entry, mesh, level);
    if let Found::Object { dov, .. } = &piece.found {
        // The fallback's objects (DoV 0) have no DoV to hand on.
        if search.dov_tau && *dov > 0.0 {
            loaded.dov = Some(*dov);
        }
        if search.finer_of {
            loaded.finest = 0;
            loaded.finer_of = true;
        }
        if search.selection == Selection::Screen {
            loaded.tau_scale = faint_tau_scale(*dov, search.eta, search.faint_tau);
        }
    }
    loaded
}

/// A frame's start, in either VISUAL mode: its pose taken into `track`, the path's clock
/// waited for under the walk's pace, its camera, and its figures begun. Pages are
/// counted from before the wait: what another thread reads meanwhile is this frame's.
/// The camera, the figures, the pages read so far and when the frame's own work began.
pub(super) fn begin_frame(
    db: &Database,
    cfg: &VisualConfig,
    track: &mut MotionTrack,
    clock: Instant,
    at: FrameAt<'_>,
) -> Result<(Camera, VisualFrame, IoStats, Instant)> {
    let pose = at.pose;
    track.push(at.index, *pose)?;
    let io_before = db.io();
    if let (Some(speed), Some(start)) = (cfg.pace, track.start()) {
        wait_until_due(pose.time, start, speed, clock);
    }
    let camera = at.camera(Some(cfg.far))?;
    let frame = VisualFrame {
        frame: at.index,
        time: pose.time,
        ..Default::default()
    };
    Ok((camera, frame, io_before, Instant::now()))
}

/// A frame's figures once it is culled, from what its retrieval left `pending`: what
/// it draws, its time, and the pages read since its retrieval began, on every thread.
pub(super) fn finish_frame(
    db: &Database,
    pending: Option<(VisualFrame, IoStats, Instant)>,
    culled: &Culled<'_>,
    buffer: &ObjectBuffer,
) -> Result<VisualFrame> {
    let (mut frame, io_before, start) =
        pending.ok_or_else(|| Error::Invalid("a frame finished before it was retrieved".into()))?;
    frame.cull_ms = culled.ms;
    frame.drawn = culled.drawn.len();
    frame.triangles_drawn = culled
        .drawn
        .iter()
        .map(|o| o.mesh.triangle_count() as u64)
        .sum();
    frame.frame_ms = start.elapsed().as_secs_f64() * 1e3;
    let io = db.io().since(&io_before);
    let of = |kinds: &[PageKind]| kinds.iter().map(|k| io.reads_of(*k)).sum::<u64>();
    frame.tree_pages = of(&[PageKind::HdovNode, PageKind::VPage]);
    frame.model_pages = of(&[PageKind::Mesh, PageKind::Lod]);
    frame.other_pages = io.page_reads - frame.tree_pages - frame.model_pages;
    frame.buffer_bytes = buffer.bytes();
    Ok(frame)
}
