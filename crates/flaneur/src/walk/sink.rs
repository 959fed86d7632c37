//! What a walk shows, frame by frame, for whoever draws it: the camera, the object
//! buffer, the objects in view (the buffer after frustum culling) and what to draw of
//! them, each at the level the walk's LOD selection chose for the τ the sink wants. The
//! renderer implements [`FrameSink`]; a walk that draws nothing passes [`NoSink`].

use super::buffer::{Loaded, ObjectBuffer};
use super::lod_select::{Drawn, LodCounts, Refinements};
use crate::error::Result;
use crate::geom::Camera;

/// Receives each frame of a walk as the engine selected it.
pub trait FrameSink {
    /// Frame `index`, seen by `camera`: `selection` is what to draw of the objects of
    /// `buffer` in view.
    fn frame(
        &mut self,
        index: usize,
        camera: &Camera,
        buffer: &ObjectBuffer,
        selection: &mut Selection<'_>,
    ) -> Result<()>;

    /// Whether it draws, so that a walk must load the objects' meshes for it (a walk
    /// that only counts, like the PVS walk, loads none otherwise).
    fn draws(&self) -> bool {
        true
    }

    /// The shape of the picture it draws (width / height), when the walk's view should
    /// take it: the camera keeps its vertical field of view and widens or narrows its
    /// horizontal one to fill the picture, and selects and culls for that view. `None`
    /// (the default, and every headless walk's): the thesis's 45° × 45°.
    fn aspect(&self) -> Option<f32> {
        None
    }

    /// The screen-space error the walk's LOD selection draws this frame under, a
    /// fraction of the viewport ([`lod_select`](super::lod_select)); `None`: every
    /// object at full detail.
    fn lod_tau(&self) -> Option<f32> {
        None
    }

    /// Whether LOD selection starts afresh this frame, forgetting the levels read so
    /// far (a window's key setting τ asks it even where τ stays the same).
    fn lod_restart(&mut self) -> bool {
        false
    }

    /// Whether LOD selection refines a large object from the frame it is first drawn,
    /// the frame waiting for its progressive mesh and DAG to decode, rather than drawing
    /// it at its discrete levels meanwhile
    /// ([`LodSelector::settling`](super::lod_select::LodSelector::settling)): for a
    /// viewer whose pictures must follow from the path alone (a comparison of pictures,
    /// a test); a person at a window would rather not wait.
    fn lod_settled(&self) -> bool {
        false
    }

    /// Whether objects refined view by view are refined on the thread pool for the
    /// next frame once a frame is drawn (Adapt and Display,
    /// [`LodSelector::adapting_ahead`](super::lod_select::LodSelector::adapting_ahead)):
    /// the traversal leaves the frame's thread, and each such object is drawn as
    /// refined for a view predicted one frame ahead.
    fn lod_adapt_ahead(&self) -> bool {
        false
    }

    /// Objects refined elsewhere that the walk is to draw from there (a stream
    /// server's landmarks, [`RemoteRefinements`](super::RemoteRefinements)); asked once,
    /// as the walk starts, and taken.
    fn lod_remote(&mut self) -> Option<Box<dyn super::RemoteRefinements>> {
        None
    }
}

/// What a frame draws: the objects in view, each at the level LOD selection chose.
pub struct Selection<'f> {
    /// The objects of the buffer in view, at full detail as the walk loaded them.
    pub culled: &'f [&'f Loaded],
    /// Each of them, in the same order, at its level (at full detail without LOD
    /// selection).
    pub drawn: Vec<Drawn>,
    /// Time LOD selection took, ms.
    pub select_ms: f64,
    /// The LOD pages selection read for this frame.
    pub pages: u64,
    /// What LOD selection read and chose over the walk so far; `None` without it.
    pub lod: Option<LodCounts>,
    /// Objects whose LOD data was found unreadable on this frame, drawn at full detail
    /// (or their discrete levels) from now on, each with why. Only for a viewer that
    /// [skips damaged objects](Viewer::skips_damaged); otherwise the frame fails.
    pub damaged: Vec<String>,
    /// Why selection failed, when it did and the frame is drawn at full detail instead
    /// (only for a viewer that [skips damaged objects](Viewer::skips_damaged), as
    /// [`Selection::damaged`]).
    pub failed: Option<String>,
    pub(crate) refinements: Option<&'f mut (dyn Refinements + 'f)>,
}

impl<'f> Selection<'f> {
    /// The renderer has uploaded this frame's refined meshes and will not read them
    /// again this frame: objects that [adapt ahead](FrameSink::lod_adapt_ahead) may be
    /// refined for the next frame while this one draws. Without it they are once the
    /// frame is done.
    pub fn uploaded(&mut self) -> Result<()> {
        match &mut self.refinements {
            Some(r) => r.uploaded(),
            None => Ok(()),
        }
    }

    /// What to draw, and where the objects drawn refined find their selective mesh and
    /// its changed ranges (to upload them); apart so that both are borrowed at once.
    pub fn parts(&mut self) -> (&[Drawn], Option<&mut dyn Refinements>) {
        (
            &self.drawn,
            self.refinements
                .as_mut()
                .map(|r| &mut **r as &mut dyn Refinements),
        )
    }
}

/// A sink that draws nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoSink;

impl FrameSink for NoSink {
    fn frame(
        &mut self,
        _: usize,
        _: &Camera,
        _: &ObjectBuffer,
        _: &mut Selection<'_>,
    ) -> Result<()> {
        Ok(())
    }

    fn draws(&self) -> bool {
        false
    }
}

/// A walk's viewer: where each frame's pose comes from (a person at a window, a
/// recorded path), and what draws the frame the walk selects for it.
pub trait Viewer: FrameSink {
    /// The pose of frame `frame`, or `None` when the walk ends.
    fn next_pose(&mut self, frame: usize) -> Result<Option<crate::path::Pose>>;

    /// What the frame just drawn cost the walk, for a display beside the picture.
    fn figures(&mut self, _figures: &FrameFigures) {}

    /// Whether the walk should go on without an object whose mesh cannot be read (a
    /// damaged page, a failing disk), telling of it in [`FrameFigures::damaged`],
    /// rather than stop with the error. A person at a window would rather walk on; an
    /// experiment would rather stop than measure something else than it says.
    fn skips_damaged(&self) -> bool {
        false
    }
}

/// What one frame of a walk did, for a live display beside the picture.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameFigures {
    /// Pages the walk read on this frame (index and meshes, prefetches included).
    pub pages: u64,
    /// Pages its LOD selection read on this frame (levels, progressive meshes).
    pub lod_pages: u64,
    /// Objects in the object buffer.
    pub objects_buffered: usize,
    /// Objects the frame draws.
    pub objects_drawn: usize,
    /// Triangles of the objects drawn, at full detail.
    pub triangles: u64,
    /// Objects the viewer should see that the walk did not hold, as its mode counts
    /// them (REVIEW and BOX: in the frustum, not in memory; PVS: on entering a cell, in
    /// its PVS, not held by the client).
    pub visual_misses: usize,
    /// Searches running ahead of the viewer (prefetches in flight).
    pub prefetch_queue: usize,
    /// The index cache's hit rate so far, when the walk has one.
    pub cache_hit_rate: Option<f64>,
    /// Where the walk stands (its disk cell, or its viewcell), in words.
    pub cell: String,
    /// The walk's own time for the frame (retrieval, loading, culling), ms.
    pub walk_ms: f64,
    /// Objects found unreadable on this frame and left out, each with why (only when
    /// the viewer [skips damaged ones](Viewer::skips_damaged)).
    pub damaged: Vec<String>,
    /// What reading the database over HTTP has cost so far (its client cache's hit rate
    /// among it); `None` for a local file.
    pub remote: Option<crate::store::RemoteStats>,
    /// What the objects refined elsewhere did lately, in words (a stream session's
    /// round trip, prediction span, batches); `None` without them
    /// ([`RemoteRefinements::status`](super::RemoteRefinements::status)).
    pub streamed: Option<String>,
    /// The object straight ahead, for a viewer that draws: its name where the database
    /// keeps one (an OpenStreetMap building's `way/…`), its id and distance, in words.
    pub looking_at: Option<String>,
}

/// Objects whose meshes could not be read, left out of a walk whose viewer
/// [skips damaged ones](Viewer::skips_damaged): never read again, and told of once in
/// [`FrameFigures::damaged`].
#[derive(Debug, Default)]
pub(crate) struct LeftOut {
    ids: std::collections::HashSet<u64>,
    /// Those not yet told of, each with why.
    untold: Vec<String>,
}

impl LeftOut {
    pub fn contains(&self, id: u64) -> bool {
        self.ids.contains(&id)
    }

    /// Object `id` left out, reading its mesh having failed with `e`.
    pub fn leave_out(&mut self, id: u64, e: &crate::Error) {
        self.ids.insert(id);
        self.untold.push(if id & super::GROUP_ID != 0 {
            format!("HDoV node {} left out: {e}", id & !super::GROUP_ID)
        } else {
            format!("object {id} left out: {e}")
        });
    }

    /// Those left out since the last call, each with why.
    pub fn take_untold(&mut self) -> Vec<String> {
        std::mem::take(&mut self.untold)
    }
}
