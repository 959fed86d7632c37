//! The walk modes: the retrieval strategies the walk session (`walk::session`) plays,
//! one file each, each implementing [`Mode`](super::session::Mode). `review`: REVIEW
//! and BOX (Shou 2002 §4.1–4.4); `pvs`: the PVS client with SNP, PBNP or LANP (Zheng
//! 2007 ch. 7), and `pvs_never_wait` with its `pvs_loader` the same walk never waiting
//! on a read; `visual`: VISUAL over the HDoV-tree (Shou 2002 §5.8.5); `scene`: VSC, PB and
//! CONV over the memory scene tree (Shou 2002 ch. 6). `receive` takes a prefetch thread's
//! answer for REVIEW and VISUAL; `refining` is a never-wait REVIEW walk's lane that reads
//! the full meshes of the objects it drew coarse, `loader` what its loader threads are asked and
//! hand back, and `load_order` the order their loads come in (the ground truth of its
//! visual misses is the database's, `rtree::BoxIndex`, read once a handle); `pace` plays a paced walk's poses at their times; `damage` what
//! a never-wait walk's loaders could not read for damage, named for its summary.

mod damage;
mod load_failures;
mod load_order;
mod loader;
mod mailbox;
mod mesh_batch;
mod pace;
pub(crate) mod pvs;
mod pvs_loader;
mod pvs_never_wait;
mod receive;
mod refining;
pub(crate) mod review;
pub(crate) mod scene;
pub(crate) mod visual;
mod visual_loader;
mod visual_never_wait;
