//! Adapt and Display (El-Sana–Varshney §4) for the objects a walk refines view by view:
//! once the renderer has uploaded a frame's changes, each refined object's traversal
//! for the next frame runs on the thread pool (Adapt) while the frame's thread draws it
//! and goes on to the next frame's retrieval and culling (Display); the next selection
//! takes the adapted meshes rather than refining on its own thread. A viewer that does
//! not say when it has uploaded has them adapted once its frame is done.
//!
//! The next view is not known when the frame ends, so it is predicted one frame ahead
//! from the last two, to first order (Zheng 2007 §6.3: E' = E_c + f·(E_c − E_p), here
//! with f = 1, for the eye and for the heading and elevation). An object is then drawn
//! as refined for the predicted view, not the actual one: the price of taking the
//! traversal off the frame's thread. An object not drawn refined on the frame before
//! (just decoded, or back in view) is refined on the frame's thread as without it.
//!
//! The paper's Adapt runs on its own processor and hands Display its changes through
//! an auxiliary buffer under a lock; here the refiner itself goes to the pool once the
//! renderer no longer reads its mesh (the draw reads the GPU's copy) and comes back with
//! its changes, and the next selection waits for what has not come back yet, so that no
//! upload reads a mesh being changed.

use std::collections::{HashMap, HashSet};
use std::sync::mpsc::{channel, Receiver, Sender};

use crate::error::{Error, Result};
use crate::geom::Camera;
use crate::lod::{RefineParams, View};

use super::RefinedObject;

/// A refined object back from the pool: its refiner after the traversal, and the
/// operators that traversal applied (or why it failed; the refiner is then as it was).
type Adapted = (u64, Box<RefinedObject>, Result<usize>);

/// The refined objects' traversals run ahead of the frames.
pub(super) struct AdaptAhead {
    /// Each object drawn refined on this frame, with the parameters it was refined
    /// under: what the next traversal runs with.
    drawn: Vec<(u64, RefineParams)>,
    /// The camera of the frame before, to predict the next from.
    previous: Option<Camera>,
    /// Whether this frame's traversals have started.
    launched: bool,
    in_flight: HashSet<u64>,
    /// Objects back from the pool since the last selection, refined for this frame.
    ready: HashSet<u64>,
    back: (Sender<Adapted>, Receiver<Adapted>),
}

impl AdaptAhead {
    pub(super) fn new() -> AdaptAhead {
        AdaptAhead {
            drawn: Vec::new(),
            previous: None,
            launched: false,
            in_flight: HashSet::new(),
            ready: HashSet::new(),
            back: channel(),
        }
    }

    /// Takes back every object whose traversal is running, waiting for those not back
    /// yet, into `refined`; adds the operators they applied to `ops`. The first
    /// traversal that failed is the error (its object is back as it was).
    pub(super) fn collect(
        &mut self,
        refined: &mut HashMap<u64, RefinedObject>,
        ops: &mut u64,
    ) -> Result<()> {
        let mut failed = None;
        while !self.in_flight.is_empty() {
            let (id, object, applied) = self
                .back
                .1
                .recv()
                .map_err(|_| Error::Invalid("the LOD adapting threads stopped".into()))?;
            self.in_flight.remove(&id);
            refined.insert(id, *object);
            match applied {
                Ok(n) => {
                    *ops += n as u64;
                    self.ready.insert(id);
                }
                Err(e) => {
                    failed.get_or_insert(e);
                }
            }
        }
        self.drawn.clear();
        self.launched = false;
        failed.map_or(Ok(()), Err)
    }

    /// Whether object `id` came back refined for this frame (and so needs no
    /// traversal on the frame's thread); asked once a frame.
    pub(super) fn take_ready(&mut self, id: u64) -> bool {
        self.ready.remove(&id)
    }

    /// Object `id` was drawn refined on this frame under `params`.
    pub(super) fn drawn(&mut self, id: u64, params: RefineParams) {
        self.drawn.push((id, params));
    }

    /// The frame seen by `camera` has been uploaded: sends each object it drew refined
    /// to the pool, to be refined for the view predicted for the next frame. Once a
    /// frame; a second call does nothing.
    pub(super) fn launch(
        &mut self,
        refined: &mut HashMap<u64, RefinedObject>,
        camera: &Camera,
    ) -> Result<()> {
        if std::mem::replace(&mut self.launched, true) {
            return Ok(());
        }
        let next = predict(self.previous.as_ref(), camera);
        self.previous = Some(*camera);
        let view = View::new(next.position, next.forward(), next.fov_x.max(next.fov_y))?;
        // Objects not taken as ready were not drawn again: they are refined afresh
        // when next drawn.
        self.ready.clear();
        for (id, params) in self.drawn.drain(..) {
            let Some(mut object) = refined.remove(&id).map(Box::new) else {
                continue;
            };
            let to = self.back.0.clone();
            self.in_flight.insert(id);
            rayon::spawn(move || {
                let applied = object.refiner.refine(&view, &params).map(|frame| {
                    let (ops, c) = (frame.stats.updates(), frame.changes);
                    let pending = &mut object.pending;
                    pending.vertices.extend(c.vertices);
                    pending.indices.extend(c.indices);
                    pending.vertex_len = c.vertex_len;
                    pending.index_len = c.index_len;
                    ops
                });
                // The selector may be gone by now: nobody wants the object then.
                let _ = to.send((id, object, applied));
            });
        }
        Ok(())
    }
}

/// The camera one frame after `camera`, the one before it being `previous`: each of
/// the eye, the heading and the elevation moved on by its last step (the heading's
/// step taken the short way round, the elevation kept inside its range).
fn predict(previous: Option<&Camera>, camera: &Camera) -> Camera {
    let Some(p) = previous else {
        return *camera;
    };
    let turn = (camera.yaw - p.yaw + std::f32::consts::PI).rem_euclid(std::f32::consts::TAU)
        - std::f32::consts::PI;
    let limit = std::f32::consts::FRAC_PI_2 - 1e-3;
    Camera {
        position: camera.position + (camera.position - p.position),
        yaw: camera.yaw + turn,
        pitch: (2.0 * camera.pitch - p.pitch).clamp(-limit, limit),
        ..*camera
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn the_next_camera_moves_on_by_the_last_step() {
        let a = Camera::new(Vec3::ZERO, 3.1, 0.1).unwrap();
        let b = Camera::new(Vec3::new(1.0, 0.0, 2.0), -3.1, 0.2).unwrap();
        let next = predict(Some(&a), &b);
        assert_eq!(next.position, Vec3::new(2.0, 0.0, 4.0));
        // From 3.1 to -3.1 is a step of about 0.083 across ±π, not -6.2.
        let step = std::f32::consts::TAU - 6.2;
        assert!((next.yaw - (-3.1 + step)).abs() < 1e-4, "{}", next.yaw);
        assert!((next.pitch - 0.3).abs() < 1e-6);
        // No camera before: the same one.
        assert_eq!(predict(None, &b).position, b.position);
        // The elevation stays inside its range.
        let up = Camera::new(Vec3::ZERO, 0.0, 1.5).unwrap();
        let down = Camera::new(Vec3::ZERO, 0.0, 0.0).unwrap();
        assert!(predict(Some(&down), &up).pitch < std::f32::consts::FRAC_PI_2);
    }
}
