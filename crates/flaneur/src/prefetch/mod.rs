//! Prefetching: fetching what the viewer will need before it needs it.
//!
//! `motion` predicts where the viewer's frustum will be from its motion so far (Shou
//! 2002 §4.2.5); `pvs` prefetches the precomputed potentially visible sets of the
//! viewcells around the viewer (Zheng 2007, chapter 7).

pub mod motion;
pub mod pvs;
