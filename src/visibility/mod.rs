//! Precomputed from-region visibility (Shou 2002 §5.5): viewcells, occluders, the
//! conservative potentially visible set of each cell, and its degree of visibility.

mod cells;
mod conservative;
mod intersect;
mod occluder;
mod table;

pub use cells::{corners, Viewcell, ViewcellGrid, DEFAULT_CELL_SIZE, DEFAULT_EYE_RANGE};
pub use conservative::{hides, BeltOptions, CellVisibility, Scene};
pub use intersect::{ray_triangle_distance, segment_meets_box, triangle_meets_box};
pub use occluder::occluder_box;
pub use table::{
    CellEntry, CellPvs, TableHead, VisibilitySettings, VisibilityStats, VISIBILITY_SEGMENT,
};
