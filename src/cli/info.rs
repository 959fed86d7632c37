//! `flaneur info`: what a database holds, as text or JSON.

use std::path::{Path, PathBuf};

use anyhow::Result;

use super::source::{remote_line, SourceArgs};
use flaneur::DatabaseInfo;

/// `flaneur info`'s arguments.
#[derive(clap::Args)]
pub struct InfoArgs {
    /// The database: a file, or a URL (http://… or https://…) on any HTTP server.
    db: PathBuf,
    /// Print the figures as JSON.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    source: SourceArgs,
}

impl InfoArgs {
    /// Prints the database's figures.
    pub fn run(self) -> Result<()> {
        info(&self.db, self.json, &self.source)
    }
}

fn info(path: &Path, json: bool, source: &SourceArgs) -> Result<()> {
    let db = source.open(path)?;
    let info = db.info()?;
    if json {
        println!("{}", serde_json::to_string_pretty(&info)?);
        return Ok(());
    }
    print_pages(path, &info);
    print_lods(&info);
    print_visibility(&info);
    print_hdov(&info);
    print_index(&info);
    if let Some(stats) = db.remote_stats() {
        println!("{}", remote_line(&stats));
    }
    Ok(())
}

/// Its size: objects, triangles, pages by kind, bytes per triangle, the codec.
fn print_pages(path: &Path, info: &DatabaseInfo) {
    let k = &info.pages_by_kind;
    println!("database    {}", path.display());
    println!("objects     {}", info.objects);
    println!("triangles   {}", info.triangles);
    println!(
        "pages       {} of {} bytes ({:.1} MiB)",
        info.pages,
        info.page_size,
        info.file_bytes as f64 / (1 << 20) as f64
    );
    if info.uncommitted_bytes > 0 {
        eprintln!(
            "warning: {} bytes past the database's last page are not part of it: what a \
             write interrupted before its commit leaves, or bytes appended by something \
             else (never read; the next writer cuts them off)",
            info.uncommitted_bytes
        );
    }
    println!(
        "  by kind   header 1, r-tree {}, mesh {}, meta {}, lod {}, visibility {}",
        k.rtree, k.mesh, k.meta, k.lod, k.visibility
    );
    let b = &info.bytes_per_triangle;
    println!(
        "bytes/tri   {:.2} in all: mesh {:.2}, lod {:.2}, r-tree {:.2}, visibility {:.2} (a page's bytes over the full-detail triangles)",
        b.whole, b.mesh, b.lod, b.rtree, b.visibility
    );
    let codec = match info.codec {
        flaneur::scene::MeshCodec::Raw => "raw floats".to_string(),
        flaneur::scene::MeshCodec::Meshopt { zstd: None } => "meshoptimizer's, no zstd".to_string(),
        flaneur::scene::MeshCodec::Meshopt { zstd: Some(l) } => {
            format!("meshoptimizer's, zstd level {l}")
        }
    };
    let dictionaries = match info.dictionary_bytes {
        0 => String::new(),
        n => format!(
            ", with dictionaries trained on the city ({} KiB)",
            n.div_ceil(1024)
        ),
    };
    println!(
        "codec       {codec}{dictionaries} (format version {})",
        info.format_version
    );
}

/// Its stored LODs and the settings they were made with.
fn print_lods(info: &DatabaseInfo) {
    match &info.lod {
        None => println!("lods        none (built with --no-lod, or before LODs were stored)"),
        Some(l) => {
            let bytes = l.pages * info.page_size as u64;
            println!(
                "lods        {} of {} objects, {} levels coarser than the full meshes, {} pages ({:.1} MiB, {:.1}% of the file)",
                l.with_levels,
                info.objects,
                l.levels,
                l.pages,
                bytes as f64 / (1 << 20) as f64,
                100.0 * bytes as f64 / info.file_bytes.max(1) as f64
            );
            println!(
                "  settings  ratio {}, down to {} triangles; PM + DAG above {} triangles: {} objects",
                l.ratio, l.min_triangles, l.pm_threshold, l.with_pm
            );
            if l.refused > 0 {
                println!(
                    "  refused   {} objects the simplifier refused have no LODs",
                    l.refused
                );
            }
        }
    }
}

/// Its viewcells, their PVS, and what computing them took.
fn print_visibility(info: &DatabaseInfo) {
    match &info.visibility {
        None => println!("visibility  none (built without --visibility)"),
        Some(v) => {
            println!(
                "visibility  {} walkable cells of {} × {} ({} m, eyes {}–{} m), {} pages",
                v.cells,
                v.rows,
                v.columns,
                v.cell_size,
                v.eye[0],
                v.eye[1],
                info.pages_by_kind.visibility
            );
            println!(
                "  PVS       {:.1} objects on average, {:.2}% of the scene (patches of {} m, occluders within {} m)",
                v.mean_pvs,
                100.0 * v.mean_share,
                v.sample_spacing,
                v.occluder_radius
            );
            if v.seconds > 0.0 {
                println!(
                    "  computed  in {:.1} s, {:.3} s per cell; DoV at N = {}: {:.3} s per cell, {} rays, {:.2} M rays/s",
                    v.seconds,
                    v.seconds_per_cell,
                    v.resolution,
                    v.dov_seconds_per_cell,
                    v.rays,
                    v.rays_per_second / 1e6
                );
            } else {
                println!(
                    "  computed  DoV at N = {}, {} rays (times not recorded: a reproducible build)",
                    v.resolution, v.rays
                );
            }
        }
    }
}

/// Its HDoV-tree and the bytes of each storage scheme.
fn print_hdov(info: &DatabaseInfo) {
    if let Some(h) = &info.hdov {
        println!(
            "hdov        {} nodes (fan-out {}, height {}), internal LODs {} pages; {} cells, {:.1} visible nodes per cell; built in {:.1} s",
            h.nodes,
            h.fanout,
            h.height,
            h.lod_pages,
            h.cells,
            h.visible_nodes as f64 / h.cells.max(1) as f64,
            h.seconds
        );
        for (scheme, bytes) in &h.schemes {
            println!(
                "  {:<10} {} bytes ({:.2} MiB)",
                scheme.name(),
                bytes,
                *bytes as f64 / (1 << 20) as f64
            );
        }
    }
}

/// Its names, bounds and R-tree.
fn print_index(info: &DatabaseInfo) {
    if info.named_objects > 0 {
        println!(
            "names       {} objects named by the file they came from (`query` shows them)",
            info.named_objects
        );
    }
    let b = info.bounds;
    println!(
        "bounds      x {:.1}..{:.1}  y {:.1}..{:.1}  z {:.1}..{:.1}",
        b[0], b[3], b[1], b[4], b[2], b[5]
    );
    println!(
        "r-tree      height {}, fan-out {} (leaf) / {} (internal), fill {:.1}%",
        info.tree.height,
        info.fanout_leaf,
        info.fanout_internal,
        info.tree.fill * 100.0
    );
    for (level, (n, e)) in info.tree.nodes.iter().zip(&info.tree.entries).enumerate() {
        println!("  level {level}   {n} nodes, {e} entries");
    }
}
