//! `flaneur build`: a database from a citygen scene file or OBJ, glTF and OpenStreetMap
//! files, and what went into it.

use crate::cli::args::{fill, finite_f32};
use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use super::bars::Bars;
use flaneur::lod::{LodOptions, LodReport};
use flaneur::progress::{Progress, Silent};
use flaneur::visibility::{DovMethod, SampleOptions, VisibilityOptions};
use flaneur::{BuildOptions, WriteOrder};

/// What `flaneur build` and `flaneur merge` share: the inputs, the file written, and
/// every setting of the database but its visibility's (a merge takes the shards').
#[derive(clap::Args)]
pub struct DatabaseArgs {
    /// A `.scene` file from citygen, or one or more `.obj`, `.gltf` and `.glb` files and
    /// at most one OpenStreetMap extract (`.osm.pbf`).
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// The database file to write.
    #[arg(long, short)]
    out: PathBuf,
    /// Bytes per page of the database file: a power of two from 1024 to 65536.
    #[arg(long, value_name = "BYTES", default_value_t = 4096)]
    page_size: usize,
    /// Share of each R-tree node that bulk loading fills, within [0.1, 1].
    #[arg(long, default_value_t = flaneur::rtree::DEFAULT_FILL, value_parser = fill, allow_negative_numbers = true)]
    fill: f32,
    /// Build the index by one-by-one insertion (linear split), as the thesis did.
    #[arg(long)]
    insertion: bool,
    /// Store no LODs: only each object's full mesh (faster, smaller).
    #[arg(long)]
    no_lod: bool,
    /// Objects with more triangles than this also store their progressive mesh and
    /// DAG, for view-dependent refinement.
    #[arg(long, value_name = "N", default_value_t = flaneur::lod::DEFAULT_PM_THRESHOLD)]
    pm_threshold: usize,
    /// Build the HDoV-tree over the objects, their LODs and the visibility (a build's
    /// --visibility, a merge's shards), storing its V-pages under these schemes: any of
    /// horizontal, vertical and indexed, comma-separated (default: none, no HDoV-tree).
    #[arg(long, value_name = "SCHEMES", value_delimiter = ',')]
    hdov: Option<Vec<flaneur::hdov::Scheme>>,
    /// Entries an HDoV-tree node holds (M, with --hdov): from 2 up to what a page holds
    /// (72 in a 4096-byte page, the default). Smaller nodes make a taller tree of which a
    /// viewcell sees a smaller share, and smaller V-pages.
    #[arg(long, value_name = "M", requires = "hdov")]
    hdov_fanout: Option<u32>,
    /// The order objects' meshes and LODs are written in: `hilbert`, along a Hilbert
    /// curve over their positions, so that the objects of one cell lie in a few byte
    /// runs (fewer requests over HTTP), or `input`, as the input lists them.
    #[arg(long, default_value_t = WriteOrder::default())]
    order: WriteOrder,
    /// What one object of a glTF input is: `node`, each node with a mesh, or `mesh`,
    /// each mesh with all the nodes that place it.
    #[arg(long, value_name = "node|mesh", default_value = "node")]
    gltf_objects: flaneur::scene::GltfObjects,
    /// The axis that points up in OBJ inputs: `y` (as flaneur), `z` (as GIS and many CAD
    /// exports: turned to y up), or `auto`, y unless the files' bounds plainly say z.
    #[arg(long, value_name = "y|z|auto", default_value = "auto")]
    up: flaneur::scene::Up,
    /// Metres per unit of OBJ inputs (0.01 for centimetres, 0.3048 for feet).
    #[arg(long, value_name = "METRES", default_value_t = 1.0, value_parser = finite_f32, allow_negative_numbers = true)]
    scale: f32,
    /// Metres per storey of OpenStreetMap buildings, for `building:levels`.
    #[arg(long, value_name = "METRES", default_value_t = flaneur::scene::OsmOptions::default().storey_height, value_parser = finite_f32, allow_negative_numbers = true)]
    storey_height: f32,
    /// Height of an OpenStreetMap building with neither `height` nor `building:levels`.
    #[arg(long, value_name = "METRES", default_value_t = flaneur::scene::OsmOptions::default().default_height, value_parser = finite_f32, allow_negative_numbers = true)]
    default_height: f32,
    /// OpenStreetMap heights above this are taken as mistakes (levels or the default
    /// are used instead).
    #[arg(long, value_name = "METRES", default_value_t = flaneur::scene::OsmOptions::default().max_height, value_parser = finite_f32, allow_negative_numbers = true)]
    max_height: f32,
    /// Store no build times in the file, so that it is a function of its inputs and
    /// options: two builds, or a build and a merge of shards, give the same bytes.
    #[arg(long)]
    reproducible: bool,
    /// How meshes are stored: `meshopt`, meshoptimizer's index and vertex codecs over
    /// 16-bit positions and 8-bit normals, zstd around them, meshes and LOD chains packed
    /// several to a page (format version 2); or `raw`, f32 floats, whole pages per mesh
    /// (format version 1).
    #[arg(long, value_name = "meshopt|raw", default_value = "meshopt")]
    codec: CodecName,
    /// zstd's level (1..=22) around each meshoptimizer buffer (`--codec meshopt`); 0 for
    /// none. Higher levels write slower and read as fast.
    #[arg(long, value_name = "LEVEL", default_value_t = flaneur::scene::DEFAULT_ZSTD_LEVEL, value_parser = clap::value_parser!(i32).range(0..=22))]
    zstd: i32,
    /// No progress bars: only the summary.
    #[arg(long, short)]
    quiet: bool,
}

/// `flaneur build`'s arguments: what it shares with `merge`, and the visibility's.
#[derive(clap::Args)]
pub struct BuildArgs {
    #[command(flatten)]
    db: DatabaseArgs,
    /// Precompute each viewcell's potentially visible set and its objects' degrees
    /// of visibility (the long step of a build; see --cell-size).
    #[arg(long)]
    visibility: bool,
    /// Side of a viewcell in metres (with --visibility).
    #[arg(long, value_name = "METRES", default_value_t = VisibilityOptions::default().cell_size, value_parser = finite_f32, allow_negative_numbers = true)]
    cell_size: f32,
    /// Pixels per side of each cube face the DoV is measured on (with --visibility).
    #[arg(long, value_name = "N", default_value_t = VisibilityOptions::default().resolution)]
    dov_resolution: u32,
    /// Widest patch of a viewcell the conservative test samples, in metres (with
    /// --visibility): smaller is a tighter PVS and a slower build.
    #[arg(long, value_name = "METRES", default_value_t = SampleOptions::default().spacing, value_parser = finite_f32, allow_negative_numbers = true)]
    sample_spacing: f32,
    /// Occluders further than this from a sample point are not used, in metres
    /// (with --visibility).
    #[arg(long, value_name = "METRES", default_value_t = SampleOptions::default().radius, value_parser = finite_f32, allow_negative_numbers = true)]
    occluder_radius: f32,
    /// How the DoV's item buffers are drawn (with --visibility): by the CPU rasteriser,
    /// or by one ray per pixel, the slower reference it is tested against.
    #[arg(long, value_enum, value_name = "METHOD", default_value_t = DovMethodArg::Raster)]
    dov_method: DovMethodArg,
    /// Compute only shard K of N of the visibility (K from 0), into the file --out
    /// names, for `flaneur merge` to join: each shard a process of its own, on any
    /// machine (with --visibility; default: none, the whole visibility).
    #[arg(long, value_name = "K/N")]
    shard: Option<flaneur::visibility::Shard>,
}

impl BuildArgs {
    /// Builds the database (or, with `--shard`, one shard of its visibility), with bars
    /// unless quiet, and prints its summary.
    pub fn run(self) -> Result<()> {
        let opts = self.options()?;
        let progress: &dyn Progress = if self.db.quiet {
            &Silent
        } else {
            &Bars::default()
        };
        if let Some(shard) = self.shard {
            let made = flaneur::build_visibility_shard(
                &self.db.inputs,
                &self.db.out,
                &opts,
                shard,
                progress,
            )?;
            let entries: usize = made.cells.iter().map(|(_, p)| p.ids.len()).sum();
            println!(
                "visibility shard {shard} written to {}: {} of {} walkable cells, {:.1} objects per PVS, {:.1} s (of which DoV {:.1} s); join the shards with flaneur merge",
                self.db.out.display(),
                made.cells.len(),
                made.walkable,
                entries as f64 / made.cells.len().max(1) as f64,
                made.seconds,
                made.dov_seconds
            );
            return Ok(());
        }
        let summary = build(&self.db.inputs, &self.db.out, &opts, progress)?;
        print_summary(&self.db.out, &summary, self.db.order);
        Ok(())
    }

    /// The build's options from the arguments, checked.
    fn options(&self) -> Result<BuildOptions> {
        let a = self;
        if a.db.hdov.is_some() && !a.visibility {
            bail!("--hdov needs --visibility: the HDoV-tree is built from the viewcells' DoVs");
        }
        if a.shard.is_some() && !a.visibility {
            bail!("--shard computes a shard of the visibility: give --visibility too");
        }
        a.db.options(a.visibility.then(|| VisibilityOptions {
            cell_size: a.cell_size,
            resolution: a.dov_resolution,
            samples: SampleOptions {
                spacing: a.sample_spacing,
                radius: a.occluder_radius,
            },
            dov: match a.dov_method {
                DovMethodArg::Raster => DovMethod::Raster,
                DovMethodArg::RayCast => DovMethod::RayCast,
            },
            ..VisibilityOptions::default()
        }))
    }
}

/// `--dov-method`'s values: the engine's [`DovMethod`], named for the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum DovMethodArg {
    /// Item buffers drawn by the CPU rasteriser, front to back with hierarchical depth.
    Raster,
    /// One ray per pixel into a BVH of every triangle: the reference, several times slower.
    RayCast,
}

impl DatabaseArgs {
    /// The inputs to build from.
    pub fn inputs(&self) -> &[PathBuf] {
        &self.inputs
    }

    /// The file to write.
    pub fn out(&self) -> &Path {
        &self.out
    }

    /// Whether bars are left out.
    pub fn quiet(&self) -> bool {
        self.quiet
    }

    /// The build's options from the arguments, checked, with `visibility`'s settings
    /// (none for a merge, which takes the shards').
    pub fn options(&self, visibility: Option<VisibilityOptions>) -> Result<BuildOptions> {
        let a = self;
        if let Ok(target) = std::fs::canonicalize(&a.out) {
            for input in &a.inputs {
                if std::fs::canonicalize(input).is_ok_and(|i| i == target) {
                    bail!(
                        "--out {} is an input of the build: give the database another path",
                        a.out.display()
                    );
                }
            }
        }
        Ok(BuildOptions {
            visibility,
            page_size: a.page_size,
            fill: a.fill,
            insertion: a.insertion,
            lod: (!a.no_lod).then(|| LodOptions {
                pm_threshold: a.pm_threshold,
                ..LodOptions::default()
            }),
            hdov: a.hdov.clone().map(|schemes| flaneur::hdov::HdovOptions {
                schemes,
                fanout: a.hdov_fanout,
                ..Default::default()
            }),
            order: a.order,
            gltf_objects: a.gltf_objects,
            obj_axes: flaneur::scene::ObjAxes {
                up: a.up,
                scale: a.scale,
            },
            osm: flaneur::scene::OsmOptions {
                storey_height: a.storey_height,
                default_height: a.default_height,
                max_height: a.max_height,
            },
            reproducible: a.reproducible,
            codec: match a.codec {
                CodecName::Raw => flaneur::scene::MeshCodec::Raw,
                CodecName::Meshopt => flaneur::scene::MeshCodec::Meshopt {
                    zstd: (a.zstd > 0).then_some(a.zstd),
                },
            },
        })
    }
}

/// `--codec`'s values.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum CodecName {
    Meshopt,
    Raw,
}

/// A build's summary: what was written, how the inputs were placed or imported, the
/// LODs, the visibility and the HDoV-tree.
pub fn print_summary(out: &Path, summary: &flaneur::BuildSummary, order: WriteOrder) {
    println!(
        "built {}: {} objects, {} triangles, {} pages ({:.1} MiB), tree height {}, written in {} order, {:.1} s",
        out.display(),
        summary.objects,
        summary.triangles,
        summary.pages,
        summary.bytes as f64 / (1 << 20) as f64,
        summary.height,
        order,
        summary.seconds
    );
    if let Some(p) = &summary.obj_placed {
        print_placed(p);
    }
    if let Some(r) = &summary.osm {
        print_osm(r);
    }
    print_lod_report(summary.lod.as_ref(), summary.bytes);
    if let Some(v) = &summary.visibility {
        println!(
            "  visibility: {} walkable cells of {} × {}, {:.1} objects per PVS, {} occluders; \
             {:.1} s ({:.3} s per cell, of which DoV {:.3} s at {:.2} M rays/s)",
            v.cells,
            v.rows,
            v.columns,
            v.entries as f64 / v.cells.max(1) as f64,
            v.occluders,
            v.seconds,
            v.seconds / v.cells.max(1) as f64,
            v.dov_seconds / v.cells.max(1) as f64,
            v.rays as f64 / v.dov_seconds.max(1e-9) / 1e6
        );
    }
    if let Some(h) = &summary.hdov {
        print_hdov_report(h);
    }
}

/// The HDoV-tree's lines of a build's summary.
fn print_hdov_report(h: &flaneur::hdov::HdovReport) {
    println!(
        "  HDoV-tree: {} nodes (fan-out {}, height {}), {} with internal LODs ({} levels, {} triangles, \
         {} pages); {} cells, {:.1} visible nodes per cell; {:.1} s (internal LODs {:.1} s)",
        h.nodes,
        h.fanout,
        h.height,
        h.nodes_with_lods,
        h.lod_levels,
        h.lod_triangles,
        h.lod_pages,
        h.cells,
        h.visible_nodes as f64 / h.cells.max(1) as f64,
        h.seconds,
        h.lod_seconds
    );
    for s in &h.schemes {
        println!(
            "    {:<10} {:>10} bytes ({} pages, {} V-pages); eqs. 5.7–5.9 estimate {} bytes",
            s.scheme.name(),
            s.bytes,
            s.pages,
            s.vpages,
            s.estimate_bytes
        );
    }
}

fn build(
    inputs: &[PathBuf],
    out: &Path,
    opts: &BuildOptions,
    progress: &dyn Progress,
) -> Result<flaneur::BuildSummary> {
    let is_model = |p: &PathBuf| flaneur::model_format(p).is_some();
    if inputs.iter().all(is_model) {
        Ok(flaneur::build_from_obj_with_progress(
            inputs, out, opts, progress,
        )?)
    } else if inputs.len() == 1 {
        Ok(flaneur::build_from_scene_with_progress(
            &inputs[0], out, opts, progress,
        )?)
    } else {
        bail!("give one scene file, or OBJ, glTF and OpenStreetMap files only")
    }
}

/// How the OBJ inputs were placed: the up axis taken and why, and the scale.
pub fn print_placed(p: &flaneur::scene::Placed) {
    let [x, y, z] = p.extent;
    let axes = match (p.turned, p.detected) {
        (true, true) => format!(
            "z up, turned to y up: they are plainly z-up, {x:.0} × {y:.0} wide and {z:.0} tall (--up y keeps them as they are)"
        ),
        (true, false) => "z up (--up z), turned to y up".to_string(),
        (false, _) => format!("y up, as flaneur ({x:.0} × {z:.0} wide, {y:.0} tall; --up z turns them)"),
    };
    println!("  OBJ inputs: {axes}; {} m a unit", p.scale);
}

/// What the OpenStreetMap import made of its extract: buildings, then every repair and
/// every skip with its count.
fn print_osm(r: &flaneur::scene::OsmReport) {
    println!(
        "  OpenStreetMap buildings: {} ({} ways, {} multipolygons), {} skipped; projected about {:.5}° N, {:.5}° E (equirectangular, metres)",
        r.buildings(),
        r.from_ways,
        r.from_relations,
        r.skipped_total(),
        r.centre[0],
        r.centre[1]
    );
    for (repair, n) in &r.repaired {
        println!("    repaired {n:>6}: {}", repair.describe());
    }
    for (skip, n) in &r.skipped {
        println!("    skipped  {n:>6}: {}", skip.describe());
    }
}

/// The LOD lines of a build's summary.
pub fn print_lod_report(lod: Option<&LodReport>, file_bytes: u64) {
    let Some(r) = lod else {
        println!("  LODs: none (--no-lod)");
        return;
    };
    let s = &r.stats;
    println!(
        "  LODs: {} objects simplified, {} with coarse levels ({} levels), {} with PM + DAG (over {} triangles); \
         {} pages ({:.1} MiB, {:.1}% of the file); {:.1} s of the build ({:.1} s of simplifying tasks on {} threads)",
        s.objects,
        s.with_levels,
        s.levels,
        s.with_pm,
        s.pm_threshold,
        s.pages,
        r.bytes as f64 / (1 << 20) as f64,
        100.0 * r.bytes as f64 / file_bytes.max(1) as f64,
        r.seconds,
        r.task_seconds,
        r.threads
    );
    if s.refused > 0 {
        println!(
            "  LODs: {} objects refused by the simplifier have none (first: {})",
            s.refused,
            r.first_refusal.as_deref().unwrap_or("?")
        );
    }
}
