//! Prefetching: fetching what the viewer will need before it needs it.
//!
//! `pvs` prefetches the precomputed potentially visible sets of the viewcells around
//! the viewer (Zheng 2007, chapter 7).

pub mod pvs;
