//! Every object's box in memory (an rstar tree), apart from the counted page reads: the
//! ground truth a walk's visual misses are counted against. A database builds it once a
//! handle, from one range query over the whole city, the first time a walk asks
//! (`Database::box_index`), so that walks one after another (a live window's) do not
//! each read the whole R-tree again.

use glam::Vec3;
use rstar::{primitives::GeomWithData, primitives::Rectangle, RTree as RStar, RTreeObject, AABB};

use super::ObjectEntry;
use crate::geom::{Aabb, Frustum};

/// Every object's box with its id, in memory.
pub(crate) struct BoxIndex {
    tree: RStar<GeomWithData<Rectangle<[f32; 3]>, u64>>,
}

impl BoxIndex {
    /// The index of `objects`' boxes.
    pub(crate) fn new(objects: &[ObjectEntry]) -> BoxIndex {
        let boxes = objects
            .iter()
            .map(|o| {
                let corners = (o.bounds.min.to_array(), o.bounds.max.to_array());
                GeomWithData::new(Rectangle::from_corners(corners.0, corners.1), o.id)
            })
            .collect();
        BoxIndex {
            tree: RStar::bulk_load(boxes),
        }
    }

    /// How many objects whose boxes meet `region` and `frustum` are not `held`.
    pub(crate) fn missing(
        &self,
        frustum: &Frustum,
        region: &Aabb,
        held: impl Fn(u64) -> bool,
    ) -> usize {
        let q = AABB::from_corners(region.min.to_array(), region.max.to_array());
        self.tree
            .locate_in_envelope_intersecting(&q)
            .filter(|g| !held(g.data))
            .filter(|g| {
                let e = g.geom().envelope();
                frustum.overlaps_aabb(&Aabb {
                    min: Vec3::from(e.lower()),
                    max: Vec3::from(e.upper()),
                })
            })
            .count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Camera;

    #[test]
    fn counts_the_boxes_in_view_that_are_not_held() {
        let entry = |id: u64, x: f32| ObjectEntry {
            id,
            bounds: Aabb {
                min: Vec3::new(x, 0.0, -1.0),
                max: Vec3::new(x + 1.0, 1.0, 1.0),
            },
            mesh: crate::store::Extent::default(),
            triangles: 12,
            kind: 0,
        };
        let index = BoxIndex::new(&[entry(1, 5.0), entry(2, 10.0), entry(3, -50.0)]);
        // Looking along +x, from the origin.
        let camera = Camera::new(Vec3::new(0.0, 0.5, 0.0), 0.0, 0.0).unwrap();
        let frustum = camera.frustum();
        let region = frustum.aabb();
        let seen = |held: &[u64]| index.missing(&frustum, &region, |id| held.contains(&id));
        assert_eq!(seen(&[]), 2, "objects 1 and 2 lie ahead, 3 behind");
        assert_eq!(seen(&[1]), 1);
        assert_eq!(seen(&[1, 2, 3]), 0);
    }
}
