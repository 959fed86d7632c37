//! `flaneur bench`: the papers' experiments, one file each. Every experiment builds its
//! configuration from the arguments, runs it in `flaneur_bench`, and hands the report to
//! [`report::write_report`].

mod crowd;
mod csearch;
mod dov_accuracy;
mod fidelity;
mod hdov_cache;
mod hdov_scaling;
mod hdov_search;
mod hdov_storage;
mod http;
mod index_cache;
mod layout;
mod lod_dag;
mod lod_parallel;
mod lod_refine;
mod patterns;
mod prefetch_k;
mod pvs_http;
mod pvs_prefetch;
mod pvs_tightness;
mod report;
mod scene_tree;
mod soak;
mod stream;
mod stream_blocks;
mod stream_bytes;
mod stream_crowd;
mod view_culling;
mod visual_http;
mod visual_vs_review;
mod walk_setup;

use anyhow::Result;
use clap::Subcommand;

/// `flaneur bench`'s arguments: the experiment to run.
#[derive(clap::Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    experiment: Experiment,
}

#[derive(Subcommand)]
enum Experiment {
    /// Each frame of a walk drawn twice, with the mode's selection and at full detail,
    /// and compared: PSNR and the share of differing pixels beside triangles drawn
    /// (the thesis's Figs. 5.26 and 6.6 as numbers). Renders headless.
    Fidelity(fidelity::FidelityArgs),
    /// Hit rate of a cache of HDoV-tree nodes against its size, LRU, DoV and DoV-Time
    /// beside Belady, for continuous and random viewcell queries (Figs. 5.15–5.20).
    /// Needs a database built with --visibility --hdov.
    HdovCache(hdov_cache::HdovCacheArgs),
    /// What each storage scheme of the HDoV-tree takes, against eqs. 5.7–5.9 and the
    /// thesis's Table 5.2. Needs a database built with --visibility --hdov.
    HdovStorage(hdov_storage::HdovStorageArgs),
    /// HDoV-tree searches from random viewcells under DoV thresholds η from 0 to 0.008:
    /// search and total I/O per storage scheme against the naive PVS list (Figs.
    /// 5.21–5.22). Needs a database built with --visibility --hdov.
    HdovSearch(hdov_search::HdovSearchArgs),
    /// HDoV-tree search and total I/O against the naive method on generated cities of
    /// growing size, built once with LODs, visibility and the tree (Fig. 5.23).
    HdovScaling(hdov_scaling::HdovScalingArgs),
    /// VISUAL, the HDoV-tree walkthrough, against REVIEW with 400 m and 200 m query
    /// boxes along the same sessions: frame time and its variance, memory, pages and the
    /// visible objects each misses, VISUAL at Table 5.3's nine η (Table 5.3, Figs.
    /// 5.24–5.27). Needs a database built with --visibility --hdov.
    VisualVsReview(visual_vs_review::VisualVsReviewArgs),
    /// The memory HDoV scene tree walked by CONV, VSC(η) and PB(n): frame time,
    /// triangles, nodes visited, frames within budget (Table 6.1, Figs. 6.4–6.7). Needs
    /// a database built with --visibility.
    SceneTree(scene_tree::SceneTreeArgs),
    /// Ours: an hour of walking (108,000 frames, unpaced) with the resident set sampled:
    /// flat after the warm-up, within the buffer's budget and a fixed overhead.
    Soak(soak::SoakArgs),
    /// Frame and query time against the prefetch factor k, per motion pattern (Fig. 4.17).
    PrefetchK(prefetch_k::PrefetchKArgs),
    /// Objects and time removed by frustum culling against the disk cell's scale factor (Table 4.2).
    ViewCulling(view_culling::ViewCullingArgs),
    /// Disk I/Os per query, Optimal against BOX, on the five motion patterns (Table 4.1).
    Patterns(patterns::PatternsArgs),
    /// Index cache hit rate against cache size: LRU, DPLRU, the path policy and Belady (Fig. 4.18).
    IndexCache(index_cache::IndexCacheArgs),
    /// The normal and fast walks over HTTP through a loopback link of set round trip
    /// and bandwidth, never waiting on a read, beside the local walks: frames over 50
    /// ms, visual misses, time to the first complete frame, requests and bytes per
    /// second, bytes moved over bytes used, cache hit rate (ours).
    Http(http::HttpArgs),
    /// The PVS walk's prefetchers, SNP, PBNP and LANP, never waiting on a read, over
    /// HTTP through a loopback link of set round trips, beside the local walks: visual
    /// misses, frames over 50 ms, swaps, objects sent, the measured round trip (ours).
    /// Needs a database built with --visibility.
    PvsHttp(pvs_http::PvsHttpArgs),
    /// The VISUAL walk over the HDoV-tree never waiting on a read, over HTTP through a
    /// loopback link of set round trips, beside the local walks waiting and never
    /// waiting: visual misses, frames over 50 ms, coarse draws (ours). Needs a database
    /// built with --visibility --hdov.
    VisualHttp(visual_http::VisualHttpArgs),
    /// Each sampled viewcell's conservative PVS against what a dense sampling of the
    /// cell sees (32 viewpoints, 256 × 256 rays a cube face): the ratio per cell, and
    /// every seen object missing from a PVS, which fails the command (ours). Needs a
    /// database built with --visibility.
    PvsTightness(pvs_tightness::PvsTightnessArgs),
    /// The DoVs a build stores (the CPU rasteriser's item buffers) against the ray-cast
    /// reference on the database's own meshes, cell by cell: the sum of absolute
    /// differences a cell, which fails the command over --limit, and each one's time a
    /// corner (ours). Needs a database built with --visibility.
    DovAccuracy(dov_accuracy::DovAccuracyArgs),
    /// The same city in files of different object orders (`build --order`), served over
    /// HTTP and asked the same range queries from cold clients: pages, requests, round
    /// trips and bytes per query for the query, the coarse levels and the full meshes
    /// (ours).
    Layout(layout::LayoutArgs),
    /// Many walkers at once (32 by default) against one nginx on loopback, or any URL:
    /// errors, bytes per walker, p50/p99 request time, and the server's CPU (ours).
    Crowd(crowd::CrowdArgs),
    /// Pages read by BOX against CSearch along a walk of overlapping disk cells; then
    /// REVIEW walks: frame time and variance against cell size, Optimal / NC / NP / BOX
    /// (Fig. 4.19, 4.20), time per frame, Optimal against BOX (Fig. 4.21), and search
    /// time against database size on generated cities (Fig. 4.22).
    Csearch(csearch::CsearchArgs),
    /// DAG edges, build time and bytes per vertex: full-, non- and mini-redundant, on the
    /// bunny and bumpy tori of the thesis's sizes (Zheng Tables 3.1–3.3). No database.
    LodDag(lod_dag::LodDagArgs),
    /// One large mesh's progressive mesh built on 1 and on all threads: time, speed-up and
    /// load balance (El-Sana & Varshney Tables 1–2), beside the serial build; and the
    /// throughput of building many city objects' progressive meshes. No database.
    LodParallel(lod_parallel::LodParallelArgs),
    /// Traversal and update time, accuracy and fronts per frame along a scripted orbit:
    /// priority, linear and constant-time traversals (Zheng Tables 4.1, 4.3, Fig. 4.11,
    /// 4.12). No database.
    LodRefine(lod_refine::LodRefineArgs),
    /// SNP against PBNP neighbour PVS prefetching on the thesis's synthetic city and its
    /// two routes: transactions, cache swaps, objects sent, visual misses (Zheng Table
    /// 7.2, Figs. 7.6–7.8), and PBNP against its region size. No database.
    PvsPrefetch(pvs_prefetch::PvsPrefetchArgs),
    /// A landmark streamed from the stream server through a loopback link at set round
    /// trips, the client sequential or predicting f frames ahead: frame time, prediction
    /// span, accuracy against the traversal at the actual view (Zheng Tables 5.1, 6.1,
    /// Fig. 6.6). No database.
    Stream(stream::StreamArgs),
    /// Many predictive clients on one stream server at once, each walking its own orbit
    /// at 30 Hz: the server's CPU, memory per session, answer time and round trip
    /// (p50, p99), unmodified frames of the worst-served client (ours). No database.
    StreamCrowd(stream_crowd::StreamCrowdArgs),
    /// One view's stream to convergence, view-dependent against view-independent: bytes,
    /// frames and triangles, and what a byte cap buys (Kim–Lee–Kobbelt Figs. 8–9). No
    /// database.
    StreamBytes(stream_bytes::StreamBytesArgs),
    /// A walk past a landmark by each stream scheme (Zheng's DAG, Kim–Lee–Kobbelt's
    /// truly selective, El-Sana's blocks with and without prediction and a bounded
    /// cache): triangles, split/merge operations, bytes and time per frame (El-Sana
    /// Table 1). No database.
    StreamBlocks(stream_blocks::StreamBlocksArgs),
}

impl BenchArgs {
    /// Runs the experiment, writes its report and prints its summary.
    pub fn run(self) -> Result<()> {
        match self.experiment {
            Experiment::Fidelity(a) => a.run(),
            Experiment::HdovCache(a) => a.run(),
            Experiment::HdovSearch(a) => a.run(),
            Experiment::HdovScaling(a) => a.run(),
            Experiment::VisualVsReview(a) => a.run(),
            Experiment::SceneTree(a) => a.run(),
            Experiment::Soak(a) => a.run(),
            Experiment::HdovStorage(a) => a.run(),
            Experiment::PrefetchK(a) => a.run(),
            Experiment::ViewCulling(a) => a.run(),
            Experiment::Patterns(a) => a.run(),
            Experiment::IndexCache(a) => a.run(),
            Experiment::Http(a) => a.run(),
            Experiment::PvsHttp(a) => a.run(),
            Experiment::VisualHttp(a) => a.run(),
            Experiment::PvsTightness(a) => a.run(),
            Experiment::DovAccuracy(a) => a.run(),
            Experiment::Layout(a) => a.run(),
            Experiment::Crowd(a) => a.run(),
            Experiment::Csearch(a) => a.run(),
            Experiment::LodDag(a) => a.run(),
            Experiment::LodParallel(a) => a.run(),
            Experiment::LodRefine(a) => a.run(),
            Experiment::PvsPrefetch(a) => a.run(),
            Experiment::Stream(a) => a.run(),
            Experiment::StreamCrowd(a) => a.run(),
            Experiment::StreamBytes(a) => a.run(),
            Experiment::StreamBlocks(a) => a.run(),
        }
    }
}
