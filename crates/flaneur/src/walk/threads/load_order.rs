//! The order a never-wait REVIEW walk loads a cell's objects in, and how the batches it
//! hands over before the whole result are taken: what is needed now comes first, as
//! Cesium orders the tiles it loads, and is drawn as it arrives.

use glam::Vec3;

use crate::geom::Aabb;
use crate::rtree::ObjectEntry;
use crate::walk::buffer::{Loaded, ObjectBuffer};

/// The order a never-wait walk loads a cell's objects in, as Cesium orders tiles: those
/// ahead of the viewer (within 60° of where it looks) before those behind, nearest
/// first within each. Smaller loads sooner.
pub(crate) fn load_order(e: &ObjectEntry, eye: Vec3, aim: Vec3) -> f32 {
    order_of(&e.bounds, eye, aim)
}

/// [`load_order`] of what lies in `bounds` (an object, or a group of objects).
pub(crate) fn order_of(bounds: &Aabb, eye: Vec3, aim: Vec3) -> f32 {
    let to = bounds.center() - eye;
    let distance = to.length();
    let ahead = distance < 1e-3 || to.dot(aim) >= 0.5 * distance;
    if ahead {
        distance
    } else {
        distance + LOAD_BEHIND_M
    }
}

/// How much further than it is an object behind the viewer counts when a never-wait
/// walk orders its loads: more than any frustum is deep, so every object ahead comes
/// first.
const LOAD_BEHIND_M: f32 = 1.0e6;

/// Puts a part of a loader's result into the buffer, as far as the budget allows and
/// without replacing what it holds (a finer level, perhaps); the whole result follows and
/// is adopted as usual.
pub(crate) fn take_part(objects: Vec<Loaded>, buffer: &mut ObjectBuffer) {
    for o in objects {
        if buffer.contains(o.entry.id) {
            continue;
        }
        if buffer.bytes() + o.bytes > buffer.budget() {
            break;
        }
        buffer.insert(o);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Aabb;
    use crate::scene::Mesh;
    use crate::store::Extent;

    fn at(id: u64, x: f32, z: f32) -> ObjectEntry {
        ObjectEntry {
            id,
            bounds: Aabb::new([x - 1.0, 0.0, z - 1.0], [x + 1.0, 10.0, z + 1.0]).unwrap(),
            mesh: Extent::default(),
            triangles: 1,
            kind: 0,
        }
    }

    #[test]
    fn ahead_comes_before_behind_and_near_before_far() {
        let (eye, aim) = (Vec3::new(0.0, 5.0, 0.0), Vec3::X);
        let mut objects = [
            at(1, -20.0, 0.0),  // behind, near
            at(2, 300.0, 10.0), // ahead, far
            at(3, 30.0, -5.0),  // ahead, near
            at(4, 5.0, 40.0),   // to the side, more than 60 degrees off
            at(5, 100.0, 90.0), // ahead, within 60 degrees
        ];
        objects.sort_by(|a, b| load_order(a, eye, aim).total_cmp(&load_order(b, eye, aim)));
        let ids: Vec<u64> = objects.iter().map(|o| o.id).collect();
        assert_eq!(ids, [3, 5, 2, 1, 4]);
    }

    #[test]
    fn a_part_fills_the_budget_and_replaces_nothing() {
        let mesh = |n: usize| Mesh {
            positions: vec![[0.0; 3]; 3 * n],
            normals: vec![[0.0, 1.0, 0.0]; 3 * n],
            indices: (0..3 * n as u32).collect(),
        };
        let coarse = Loaded::at_level(at(1, 0.0, 0.0), mesh(1), 2);
        let one = coarse.bytes;
        let mut buffer = ObjectBuffer::new(3 * one + one / 2);
        let full = Loaded::new(at(1, 0.0, 0.0), mesh(1));
        buffer.insert(full);
        let part = vec![
            coarse,
            Loaded::at_level(at(2, 1.0, 0.0), mesh(1), 1),
            Loaded::at_level(at(3, 2.0, 0.0), mesh(1), 1),
            Loaded::at_level(at(4, 3.0, 0.0), mesh(1), 1),
        ];
        take_part(part, &mut buffer);
        // Object 1 keeps its full mesh; 2 and 3 fit, 4 would pass the budget.
        assert_eq!(buffer.get(1).map(|o| o.level), Some(0));
        assert!(buffer.contains(2) && buffer.contains(3) && !buffer.contains(4));
        assert!(!buffer.over_budget());
    }
}
