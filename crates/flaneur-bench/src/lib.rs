//! The papers' experiments as library code: `flaneur bench` and the criterion benches
//! call these and only print or plot what they return.
//!
//! `walk_setup` is the walk every walking experiment takes; `city_series` the generated
//! cities of growing size that `db_size` walks; `plot` draws every experiment's PNGs;
//! `report` is what every experiment's report gives the command that writes it.
//! `lod_dag`, `lod_parallel` and `lod_refine` measure the LOD core (`flaneur::lod`) on
//! procedural models, no database needed, with `lod_dag_stats` (the three DAG
//! constructions compared) and `lod_orbit` (a scripted orbit refined frame by frame)
//! beneath them. `pvs_prefetch` runs the neighbour
//! PVS prefetchers (`flaneur::prefetch::pvs`) on the thesis's synthetic city and PVS
//! table, which it draws itself, no database either, and
//! `pvs_stats` measures the PVS tables it runs on. `link` is a network you can set: a
//! loopback relay with a chosen round trip and bandwidth, which `http_walk` walks a
//! database over HTTP through (`through_link` opens one by URL through a link of its own), `pvs_http` the PVS walk's prefetchers, and `visual_http` the VISUAL walk never waiting; `layout` counts what the file's order costs a reader
//! over HTTP; `crowd` runs many walkers at once against one server, which `nginx`
//! starts; `stream` streams a landmark from `flaneur_stream`'s server through the link,
//! `stream_crowd` many clients from one server at once, `stream_bytes` what one view
//! costs view-dependent against view-independent (Kim–Lee–Kobbelt Figs. 8–9), and
//! `stream_blocks` what a walk's frame costs by each scheme (El-Sana's Table 1).

pub mod cell_size;
pub mod city_series;
pub mod crowd;
pub mod csearch;
pub mod dov_accuracy;
pub mod db_size;
pub mod fidelity;
pub mod frame_time;
pub mod hdov_cache;
pub mod hdov_scaling;
pub mod hdov_search;
pub mod hdov_storage;
pub mod http_walk;
pub mod index_cache;
pub mod layout;
pub mod link;
pub mod lod_dag;
pub mod lod_dag_stats;
pub mod lod_orbit;
pub mod lod_parallel;
pub mod lod_refine;
pub mod nginx;
pub mod patterns;
pub mod plot;
pub mod prefetch_k;
pub mod pvs_http;
pub mod pvs_prefetch;
pub mod pvs_stats;
pub mod pvs_tightness;
pub mod report;
pub mod scene_tree;
pub mod soak;
pub mod stream;
pub mod stream_blocks;
pub mod stream_bytes;
pub mod stream_crowd;
pub mod through_link;
pub mod view_culling;
pub mod visual_http;
pub mod visual_vs_review;
pub mod walk_setup;
