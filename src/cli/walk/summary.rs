//! What a walk prints when it ends: the summary of each mode's report, and what the
//! network cost when the database was read over HTTP.

use flaneur::walk::pvs::PvsWalkReport;
use flaneur::walk::review::WalkReport;
use flaneur::walk::scene::SceneReport;
use flaneur::walk::scene::Traversal;
use flaneur::walk::visual::VisualReport;
use flaneur::walk::Report;
use flaneur::Database;

use super::gaps;

/// Any walk's summary, as its mode prints it (`page_size` for REVIEW's bytes).
pub(super) fn print_report(report: &Report, page_size: usize) {
    match report {
        Report::Review(r) => print_walk(r, page_size),
        Report::Pvs(r) => print_pvs(r),
        Report::Visual(r) => print_visual(r),
        Report::Scene(r) => print_scene(r),
    }
}

/// A PVS walk's summary: its prefetching, transactions, misses and frame times.
fn print_pvs(r: &PvsWalkReport) {
    println!(
        "pvs walk, {} prefetch: {} frames ({} outside any walkable cell), {} cells entered",
        r.prefetch.name(),
        r.walked,
        r.frames_outside,
        r.cells_entered
    );
    println!(
        "  {} prefetch transactions, {} cache swaps, {:.1} objects per transaction, {} visual misses",
        r.transactions,
        r.swaps,
        r.objects_per_transaction(),
        r.visual_misses
    );
    println!(
        "  {:.1} objects drawn per frame (the current cell's PVS), {} pages read",
        r.mean_drawn, r.pages
    );
    println!(
        "  frame time on the viewer's thread: mean {:.2} ms   max {:.2} ms   over 50 ms: {}",
        r.mean_frame_ms, r.max_frame_ms, r.frames_over_50ms
    );
    if r.never_wait {
        println!(
            "  never waits on a read (ours): round trip measured up to {} frames   first complete frame {}   visual misses after it {}",
            r.round_trip_frames,
            r.first_complete_frame
                .map_or("none".to_string(), |f| f.to_string()),
            r.visual_misses_after_start
        );
    }
    if r.failed_loads > 0 {
        println!(
            "  {} loads failed on the network and were asked for again; the last: {}",
            r.failed_loads,
            r.last_load_error.as_deref().unwrap_or("")
        );
    }
    gaps::print_damaged(&r.damaged);
}

/// A scene-tree walk's summary.
fn print_scene(r: &SceneReport) {
    let s = &r.summary;
    println!(
        "scene tree walk, {} ({} selection): frames {}   mean {:.3} ms   max {:.2} ms   variance {:.4}   traversal {:.3} ms",
        r.config.traversal.label(),
        r.config.selection.name(),
        s.frames,
        s.mean_frame_ms,
        s.max_frame_ms,
        s.frame_ms_variance,
        s.mean_traverse_ms
    );
    println!(
        "  per frame: {:.0} triangles (most {}), {:.1} nodes visited, {:.1} drawn   cells entered {}, {} frames outside every cell, {} drawn by CONV before the first",
        s.mean_triangles, s.max_triangles, s.mean_visited, s.mean_drawn, s.cells_entered, s.frames_outside, s.frames_conv
    );
    if let Traversal::Pb { budget } = r.config.traversal {
        println!(
            "  within the budget of {budget} triangles on {:.1} % of frames",
            r.within_budget() * 100.0
        );
    }
    if let Some(t) = r.too_big() {
        println!("  {t}");
    }
}

/// A VISUAL walk's summary: its settings, frames, searches, pages and memory.
fn print_visual(r: &VisualReport) {
    let (s, c) = (&r.summary, &r.config);
    let cache = c
        .node_cache
        .as_ref()
        .map_or("none".to_string(), |(p, b)| format!("{p}, {} KiB", b >> 10));
    let prefetch = c.prefetch_k.map_or("off".to_string(), |k| {
        format!(
            "k = {k} s (ours){}",
            c.pace
                .map_or(", unpaced".into(), |p| format!(", played {p}x real time"))
        )
    });
    println!(
        "visual walk: η = {}, {} selection, {} scheme, node cache {cache}, next-cell prefetch {prefetch}, frustum {} m",
        c.eta,
        c.selection.name(),
        c.scheme.map_or("smallest", |s| s.name()),
        c.far
    );
    println!(
        "  frames {}   first (cold) load {:.1} ms   then mean {:.2} ms   max {:.2} ms   variance {:.3}   over 50 ms: {}",
        s.frames, s.initial_load_ms, s.mean_frame_ms, s.max_frame_ms, s.frame_ms_variance, s.frames_over_50ms
    );
    println!(
        "  cells entered {}   searches {} on the viewer's thread ({:.2} ms each), {} prefetched ({} used)   outside every cell: {} frames, {} REVIEW box queries",
        s.cells_entered, s.searches, s.mean_search_ms, s.prefetches, s.prefetches_used, s.frames_outside, s.fallback_queries
    );
    println!(
        "  pages read: {} tree (nodes and V-pages) + {} models + {} other   finds loaded {}, reused {} (delta), left out {}",
        s.tree_pages, s.model_pages, s.other_pages, s.loaded, s.reused, s.left_out
    );
    println!(
        "  drawn per frame {:.1} objects and nodes, {:.0} triangles   peak memory {:.1} MiB",
        s.mean_drawn,
        s.mean_triangles,
        s.peak_buffer_bytes as f64 / (1 << 20) as f64
    );
    if c.never_wait {
        println!(
            "  never waits on a read (ours): first complete frame {}   visual misses {} ({} after it)   finds drawn coarser than they deserve {} (summed over frames)",
            s.first_complete_frame
                .map_or("none".to_string(), |f| f.to_string()),
            s.visual_misses,
            s.visual_misses_after_start,
            s.coarse_draws
        );
    }
    if s.failed_loads > 0 {
        println!(
            "  {} reads failed on the network and were asked for again; the last: {}",
            s.failed_loads,
            s.last_load_error.as_deref().unwrap_or("")
        );
    }
    if let Some(cs) = &s.node_cache {
        println!(
            "  node cache: {} hits, {} misses, hit rate {:.1}%",
            cs.hits,
            cs.misses,
            cs.hit_rate() * 100.0
        );
    }
}

/// A walk's summary: its settings, then its frames, queries, pages and their bytes
/// (pages of `page_size` bytes), misses and index cache.
pub fn print_walk(r: &WalkReport, page_size: usize) {
    let s = &r.summary;
    let c = &r.config;
    let cache = c
        .index_cache
        .as_ref()
        .map_or("none".to_string(), |(p, b)| format!("{p}, {} KiB", b >> 10));
    let k = c
        .prefetch_k
        .map_or("off".to_string(), |k| format!("k = {k}"));
    let pace = match (c.prefetch_k, c.pace) {
        (Some(_), Some(p)) => format!(", played {p}x real time"),
        (Some(_), None) => ", unpaced".to_string(),
        _ => String::new(),
    };
    let waits = if c.never_wait {
        ", never waits on a read (ours)"
    } else {
        ""
    };
    println!("walk: {:?} retrieval, index cache {cache}, prefetch {k}{pace}{waits}, SF {}, frustum {} m, budget {} MiB", c.retrieval, c.sf, c.far, c.memory_budget >> 20);
    println!(
        "  frames {}   first (cold) load {:.1} ms   then mean {:.2} ms   max {:.2} ms   variance {:.3}   over 50 ms: {}",
        s.frames, s.initial_load_ms, s.mean_frame_ms, s.max_frame_ms, s.frame_ms_variance, s.frames_over_50ms
    );
    println!(
        "  queries {} ({} on the viewer's thread, {} prefetched, {} prefetches dropped)   cells entered {} ({} prefetched)",
        s.queries, s.sync_queries, s.prefetches_adopted, s.prefetches_stale, s.cell_changes, s.prefetches_used
    );
    println!(
        "  pages read: {} index + {} mesh, {:.1} per query ({:.1} index)",
        s.index_pages, s.mesh_pages, s.io_per_query, s.index_pages_per_query
    );
    // Pages are the exact count; their bytes are what a disk or a link moved for them.
    let bytes = (s.index_pages + s.mesh_pages + s.lod_pages) as f64 * page_size as f64;
    println!(
        "  bytes read: {:.1} MiB (index, mesh and LOD pages of {page_size} B), {:.1} KiB a frame, {:.1} KiB a query",
        bytes / (1 << 20) as f64,
        bytes / 1024.0 / s.frames.max(1) as f64,
        bytes / 1024.0 / s.queries.max(1) as f64
    );
    println!(
        "  visual misses {}   peak buffer {:.1} MiB   frames over budget {}",
        s.visual_misses,
        s.peak_buffer_bytes as f64 / (1 << 20) as f64,
        s.overflow_frames
    );
    if let Some(cs) = &s.index_cache {
        println!(
            "  index cache: {} hits, {} misses, hit rate {:.1}%",
            cs.hits,
            cs.misses,
            cs.hit_rate() * 100.0
        );
    }
    if c.never_wait {
        println!(
            "  searches queued by the viewer {}   frames outside every loaded cell {}   first complete frame {}",
            s.queued_queries,
            s.frames_outran,
            s.first_complete_frame
                .map_or("none".to_string(), |f| f.to_string())
        );
    }
    if s.coarse_draws > 0 || s.refined > 0 {
        println!(
            "  objects drawn coarse while their full mesh came {} (objects × frames)   full meshes put in place {}   LOD pages read {}",
            s.coarse_draws, s.refined, s.lod_pages
        );
    }
    if s.failed_loads > 0 {
        println!(
            "  {} loads failed and the walk went on without them; the last: {}",
            s.failed_loads,
            s.last_load_error.as_deref().unwrap_or("")
        );
    }
    gaps::print_damaged(&s.damaged);
}

/// For a database read over HTTP: what the network cost.
pub(super) fn print_remote(db: &Database) {
    if let Some(stats) = db.remote_stats() {
        println!("{}", crate::cli::source::remote_line(&stats));
    }
}
