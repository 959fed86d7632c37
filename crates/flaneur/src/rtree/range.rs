//! BOX, the plain range query of the thesis (Shou 2002 §4.2.1): enter every subtree
//! whose MBR overlaps the query, return every object whose box does.

use super::search::Selection;
use crate::geom::Aabb;

pub struct Range {
    pub query: Aabb,
}

impl Selection for Range {
    #[inline]
    fn descend(&self, mbr: &Aabb) -> bool {
        self.query.overlaps(mbr)
    }

    #[inline]
    fn select(&self, bounds: &Aabb) -> bool {
        self.query.overlaps(bounds)
    }
}
