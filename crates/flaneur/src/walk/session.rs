//! One walk session: the frame loop every walk mode shares. A viewer (a window, a
//! recorded or generated path) supplies each frame's pose and receives the frame; a
//! [`Mode`] is the retrieval strategy between them: REVIEW's disk cells with BOX or
//! CSearch (Shou 2002 §4.1–4.4), or the PVS client with SNP or PBNP neighbour
//! prefetching (Zheng 2007 ch. 7).
//!
//! Each frame the session takes the pose, lets the mode retrieve for it (bring the
//! object buffer to what the mode holds: load, drop, evict), culls the objects the mode
//! offers for drawing against the frustum, lets the mode finish its figures, hands the
//! frame to the viewer, then the figures. A mode owns everything else: what it asks of
//! the store and when, on which thread, and what it counts.
//!
//! The HDoV modes fit the same seam: a mode that searches on a cell change does so in
//! [`Mode::retrieve`] when the cell changes, one that keeps a delta of what is buffered
//! applies it to the buffer there, and one that chooses each object's detail loads the
//! mesh of the level it chose as the object's [`Loaded`] and offers for drawing only
//! what it chose ([`Drawable::Only`]).

use std::time::Instant;

use super::buffer::{Loaded, ObjectBuffer};
use super::looked_at::looked_at;
use super::sink::{FrameFigures, Viewer};
use super::walk_lods::{LodWanted, WalkLods};
use crate::error::Result;
use crate::geom::Camera;
use crate::path::Pose;

/// A walk's retrieval strategy: what it does per frame, given the pose.
pub(crate) trait Mode {
    /// The mode's own figures of one frame.
    type Frame;

    /// The object buffer's budget, bytes.
    fn memory_budget(&self) -> usize;

    /// Retrieves for the frame `at`: brings `buffer` to what the mode holds for it. The
    /// camera to cull and draw the frame with, or `None` when the frame hands the viewer
    /// nothing (no culling, no [`FrameSink::frame`](super::FrameSink::frame) call).
    fn retrieve(&mut self, at: FrameAt<'_>, buffer: &mut ObjectBuffer) -> Result<Option<Camera>>;

    /// Which buffered objects the frame may draw, before frustum culling.
    fn drawable(&self) -> Drawable<'_> {
        Drawable::All
    }

    /// The frame's figures, once it is culled: `culled` is what it draws (empty when
    /// [`Mode::retrieve`] gave no camera).
    fn finish(&mut self, culled: &Culled<'_>, buffer: &ObjectBuffer) -> Result<Self::Frame>;

    /// What the frame cost, for a display beside the picture.
    fn figures(&mut self, frame: &Self::Frame, buffer: &ObjectBuffer) -> FrameFigures;
}

/// The frame a mode retrieves for.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FrameAt<'p> {
    pub index: usize,
    pub pose: &'p Pose,
    /// Whether the viewer draws ([`FrameSink::draws`](super::FrameSink::draws)): a mode
    /// that only counts loads no meshes otherwise.
    pub draws: bool,
    /// The viewer's picture's shape, when the view takes it
    /// ([`FrameSink::aspect`](super::FrameSink::aspect)).
    pub aspect: Option<f32>,
}

impl FrameAt<'_> {
    /// The camera at this frame's pose: the thesis's 45° × 45° frustum, its horizontal
    /// field of view fitted to the viewer's picture when it asks, with `far`.
    pub fn camera(&self, far: Option<f32>) -> Result<Camera> {
        let p = self.pose;
        let mut camera = Camera::new(p.position, p.yaw, p.pitch)?;
        if let Some(far) = far {
            camera.far = far;
        }
        match self.aspect {
            Some(a) => camera.fitted_to(a),
            None => Ok(camera),
        }
    }
}

/// The buffered objects a frame may draw.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Drawable<'a> {
    /// Every object in the buffer, in its order.
    All,
    /// These, in this order, those not in the buffer left out.
    Only(&'a [u64]),
}

/// What a frame draws: the drawable objects within the frustum.
#[derive(Debug, Default)]
pub(crate) struct Culled<'b> {
    pub drawn: Vec<&'b Loaded>,
    /// Time taken to cull, ms.
    pub ms: f64,
}

/// Walks `mode` with `viewer` until it has no more poses. Each frame the viewer is handed is selected by `lods` under the τ
/// the viewer wants (its LOD pages counted apart from the mode's figures, which are
/// finished before). The mode's figures of every frame, in order.
pub(crate) fn run<M: Mode + ?Sized>(
    mode: &mut M,
    viewer: &mut dyn Viewer,
    lods: &mut WalkLods<'_>,
) -> Result<Vec<M::Frame>> {
    let mut frames = Vec::new();
    run_each(mode, viewer, lods, |f| {
        frames.push(f);
        Ok(())
    })?;
    Ok(frames)
}

/// [`run`], handing each frame's figures to `each` as the frame ends instead of keeping
/// them: a walk of any length in constant memory.
pub(crate) fn run_each<M: Mode + ?Sized>(
    mode: &mut M,
    viewer: &mut dyn Viewer,
    lods: &mut WalkLods<'_>,
    mut each: impl FnMut(M::Frame) -> Result<()>,
) -> Result<()> {
    let mut buffer = ObjectBuffer::new(mode.memory_budget());
    // The object last looked at, with its name: asked of the database once per object.
    let mut named: Option<(u64, Option<String>)> = None;
    if let Some(remote) = viewer.lod_remote() {
        lods.set_remote(remote);
    }
    for index in 0.. {
        let Some(pose) = viewer.next_pose(index)? else {
            break;
        };
        let at = FrameAt {
            index,
            pose: &pose,
            draws: viewer.draws(),
            aspect: viewer.aspect(),
        };
        let camera = mode.retrieve(at, &mut buffer)?;
        let culled = match &camera {
            Some(camera) => cull(&buffer, mode.drawable(), camera),
            None => Culled::default(),
        };
        let frame = mode.finish(&culled, &buffer)?;
        let mut lod_pages = 0;
        let mut looking_at = None;
        if let (Some(camera), true) = (&camera, at.draws) {
            looking_at = looked_at(camera, &culled.drawn).map(|(id, metres)| {
                if named.as_ref().is_none_or(|n| n.0 != id) {
                    named = Some((id, lods.object_name(id)));
                }
                match named.as_ref().and_then(|n| n.1.as_deref()) {
                    Some(name) => format!("{name} (object {id}), {metres:.0} m"),
                    None => format!("object {id}, {metres:.0} m"),
                }
            });
        }
        if let Some(camera) = &camera {
            let want = LodWanted {
                tau: viewer.lod_tau(),
                restart: viewer.lod_restart(),
                tolerant: viewer.skips_damaged(),
                settled: viewer.lod_settled(),
                ahead: viewer.lod_adapt_ahead(),
            };
            let mut selection = lods.select(want, camera, &buffer, &culled.drawn)?;
            lod_pages = selection.pages;
            viewer.frame(index, camera, &buffer, &mut selection)?;
            lods.frame_drawn()?;
        }
        viewer.figures(&FrameFigures {
            lod_pages,
            remote: lods.remote_stats(),
            streamed: lods.remote_status(),
            looking_at,
            ..mode.figures(&frame, &buffer)
        });
        each(frame)?;
    }
    Ok(())
}

/// The objects of `drawable` in `buffer` that `camera` sees (ViewCulling, Shou 2002
/// Fig. 4.15: a box test against the frustum).
fn cull<'b>(buffer: &'b ObjectBuffer, drawable: Drawable<'_>, camera: &Camera) -> Culled<'b> {
    let frustum = camera.frustum();
    let t = Instant::now();
    let drawn = match drawable {
        Drawable::All => buffer
            .iter()
            .filter(|o| frustum.overlaps_aabb(&o.entry.bounds))
            .collect(),
        Drawable::Only(ids) => ids
            .iter()
            .filter_map(|id| buffer.get(*id))
            .filter(|o| frustum.overlaps_aabb(&o.entry.bounds))
            .collect(),
    };
    Culled {
        drawn,
        ms: t.elapsed().as_secs_f64() * 1e3,
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::path::CameraPath;
    use crate::walk::buffer::tests::loaded;
    use crate::walk::playback::Playback;
    use crate::walk::FrameSink;

    /// Loads an object in front of the eye (+x) and one behind it each frame, offers
    /// frame 1 only some objects, and hands the viewer nothing on frame 2.
    #[derive(Default)]
    struct Probe {
        frame: usize,
        log: Vec<String>,
    }

    impl Mode for Probe {
        type Frame = usize;

        fn memory_budget(&self) -> usize {
            usize::MAX
        }

        fn retrieve(
            &mut self,
            at: FrameAt<'_>,
            buffer: &mut ObjectBuffer,
        ) -> Result<Option<Camera>> {
            self.frame = at.index;
            self.log.push(format!("retrieve {}", at.index));
            let id = at.index as u64;
            buffer.insert(loaded(10 + id, 5.0, 1));
            buffer.insert(loaded(20 + id, -50.0, 1));
            (at.index != 2).then(|| at.pose.camera()).transpose()
        }

        fn drawable(&self) -> Drawable<'_> {
            if self.frame == 1 {
                Drawable::Only(&[21, 11, 10, 99])
            } else {
                Drawable::All
            }
        }

        fn finish(&mut self, culled: &Culled<'_>, buffer: &ObjectBuffer) -> Result<usize> {
            let ids: Vec<u64> = culled.drawn.iter().map(|o| o.entry.id).collect();
            self.log.push(format!("finish {ids:?} of {}", buffer.len()));
            Ok(culled.drawn.len())
        }

        fn figures(&mut self, frame: &usize, _: &ObjectBuffer) -> FrameFigures {
            self.log.push("figures".into());
            FrameFigures {
                objects_drawn: *frame,
                ..Default::default()
            }
        }
    }

    struct Sink<'l>(&'l std::cell::RefCell<Vec<String>>);

    impl FrameSink for Sink<'_> {
        fn frame(
            &mut self,
            i: usize,
            _: &Camera,
            _: &ObjectBuffer,
            d: &mut crate::walk::Selection<'_>,
        ) -> Result<()> {
            self.0
                .borrow_mut()
                .push(format!("frame {i}: {}", d.culled.len()));
            Ok(())
        }
    }

    #[test]
    fn one_loop_retrieves_culls_finishes_then_hands_over_the_frame() {
        let pose = |i: usize| Pose {
            time: i as f64,
            position: Vec3::ZERO,
            yaw: 0.0,
            pitch: 0.0,
        };
        let path = CameraPath::new((0..3).map(pose).collect()).unwrap();
        let drawn = std::cell::RefCell::new(Vec::new());
        let mut sink = Sink(&drawn);
        let mut mode = Probe::default();
        let mut ticks = Vec::new();
        let mut tick = |i| ticks.push(i);
        let frames = run(
            &mut mode,
            &mut Playback::path(&path)
                .drawn_by(&mut sink)
                .with_progress(&mut tick),
            &mut WalkLods::default(),
        )
        .unwrap();
        // Frame 0 draws all in view; frame 1 only those offered, in their order; frame 2
        // hands the viewer nothing and culls nothing.
        assert_eq!(frames, vec![1, 2, 0]);
        assert_eq!(ticks, vec![0, 1, 2]);
        assert_eq!(
            mode.log,
            [
                "retrieve 0",
                "finish [10] of 2",
                "figures",
                "retrieve 1",
                "finish [11, 10] of 4",
                "figures",
                "retrieve 2",
                "finish [] of 6",
                "figures",
            ]
        );
        assert_eq!(*drawn.borrow(), ["frame 0: 1", "frame 1: 2"]);
    }
}
