//! Ground truth for a REVIEW walk's visual misses: every object's box, held in memory
//! apart from the counted store reads, asked which boxes in the frustum the buffer lacks.

use glam::Vec3;
use rstar::{primitives::GeomWithData, primitives::Rectangle, RTree as RStar, RTreeObject, AABB};

use crate::database::Database;
use crate::error::Result;
use crate::geom::{Aabb, Frustum};
use crate::walk::buffer::ObjectBuffer;

/// Ground truth for visual misses: every object's box, in memory, outside the counted
/// store reads.
pub(super) struct Oracle {
    tree: RStar<GeomWithData<Rectangle<[f32; 3]>, u64>>,
}

impl Oracle {
    pub(super) fn new(db: &Database) -> Result<Oracle> {
        let all = db.range(&db.bounds())?.objects;
        Ok(Oracle {
            tree: RStar::bulk_load(
                all.iter()
                    .map(|o| {
                        GeomWithData::new(
                            Rectangle::from_corners(
                                o.bounds.min.to_array(),
                                o.bounds.max.to_array(),
                            ),
                            o.id,
                        )
                    })
                    .collect(),
            ),
        })
    }

    pub(super) fn misses(&self, frustum: &Frustum, fcell: &Aabb, buffer: &ObjectBuffer) -> usize {
        let q = AABB::from_corners(fcell.min.to_array(), fcell.max.to_array());
        self.tree
            .locate_in_envelope_intersecting(&q)
            .filter(|g| !buffer.contains(g.data))
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
