// The `citygen` command: parses arguments into a CityConfig, writes the scene (and
// optionally an OBJ of one region), and prints one summary line. Everything else is
// library code; this is the only place that prints or exits.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Parser;
use indicatif::{ProgressBar, ProgressStyle};

use citygen::CityConfig;

/// Generate a deterministic procedural city as a flaneur scene file.
#[derive(Parser, Debug)]
#[command(name = "citygen", version, about)]
struct Args {
    /// Number of objects (lots), 1..=10,000,000.
    #[arg(long, default_value_t = CityConfig::default().objects)]
    objects: u64,
    /// Random seed; the same seed and options give a byte-identical file.
    #[arg(long, default_value_t = CityConfig::default().seed)]
    seed: u64,
    /// Side of the square city in metres (default: just large enough).
    #[arg(long)]
    extent: Option<f32>,
    /// Share of objects that are high-detail landmarks, 0..=1.
    #[arg(long, default_value_t = CityConfig::default().landmarks)]
    landmarks: f32,
    /// Metres between neighbouring building lots, 10..=30.
    #[arg(long, default_value_t = CityConfig::default().spacing)]
    spacing: f32,
    /// Lots per block side.
    #[arg(long, default_value_t = CityConfig::default().block)]
    block: u32,
    /// Street width in metres.
    #[arg(long, default_value_t = CityConfig::default().street_width)]
    street_width: f32,
    /// The scene file to write.
    #[arg(long)]
    out: PathBuf,
    /// Also write the objects overlapping --region to this OBJ file.
    #[arg(long, requires = "region")]
    obj: Option<PathBuf>,
    /// The region for --obj: x0,z0,x1,z1 in metres.
    #[arg(long, requires = "obj", value_parser = parse_region, allow_hyphen_values = true)]
    region: Option<([f32; 2], [f32; 2])>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

/// `x0,z0,x1,z1` → ([x_min, z_min], [x_max, z_max]).
fn parse_region(s: &str) -> Result<([f32; 2], [f32; 2]), String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>().map_err(|e| format!("{p:?}: {e}")))
        .collect::<Result<_, _>>()?;
    let [x0, z0, x1, z1] = v[..] else {
        return Err(format!(
            "expected four numbers x0,z0,x1,z1, got {}",
            v.len()
        ));
    };
    if !v.iter().all(|c| c.is_finite()) {
        return Err("every coordinate must be a finite number".into());
    }
    Ok(([x0.min(x1), z0.min(z1)], [x0.max(x1), z0.max(z1)]))
}

fn main() -> Result<()> {
    let args = Args::parse();
    let config = CityConfig {
        objects: args.objects,
        seed: args.seed,
        extent: args.extent,
        landmarks: args.landmarks,
        spacing: args.spacing,
        block: args.block,
        street_width: args.street_width,
    };
    if let Err(e) = config.validate() {
        bail!("{e}");
    }
    let bar = if !args.quiet && std::io::stderr().is_terminal() {
        objects_bar(config.objects)
    } else {
        ProgressBar::hidden()
    };
    let started = Instant::now();
    let summary = citygen::write_city_with_progress(&config, &args.out, |n| bar.set_position(n))
        .with_context(|| format!("writing {}", args.out.display()))?;
    bar.finish_and_clear();
    let secs = started.elapsed().as_secs_f64();
    println!(
        "{}: {} objects, {} triangles, {} bytes in {:.2} s ({:.0} objects/s, {:.0} triangles/object, {:.0} bytes/object), city {:.0} m square",
        args.out.display(),
        summary.objects,
        summary.triangles,
        summary.bytes,
        secs,
        summary.objects as f64 / secs,
        summary.triangles as f64 / summary.objects as f64,
        summary.bytes as f64 / summary.objects as f64,
        config.extent(),
    );
    if let (Some(obj), Some(region)) = (args.obj, args.region) {
        let n = citygen::export_obj(&config, region, &obj)
            .with_context(|| format!("exporting {}", obj.display()))?;
        println!(
            "{}: {n} objects in region x {}..{} z {}..{}",
            obj.display(),
            region.0[0],
            region.1[0],
            region.0[1],
            region.1[1]
        );
    }
    Ok(())
}

/// The bar of objects written, on standard error.
fn objects_bar(objects: u64) -> ProgressBar {
    let bar = ProgressBar::new(objects);
    bar.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{wide_bar}] {pos}/{len} objects ({per_sec}, {eta} left)",
        )
        .expect("a valid template")
        .progress_chars("=> "),
    );
    bar
}
