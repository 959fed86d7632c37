//! The demo's four retrieval modes side by side on one walk through the city's viewcells:
//! REVIEW and BOX over the R-tree, PVS over the precomputed visibility, VISUAL over the
//! HDoV-tree. Each is walked headless, loading what it would draw and selecting its
//! levels of detail, for its frame times, pages, visual misses and triangles; where a
//! GPU adapter is found, its first frames are drawn twice (the mode's selection, and
//! every object in view at full detail) for its PSNR.

use anyhow::Result;
use flaneur::path::{cell_walk, CameraPath};
use flaneur::walk::lod_select::DEFAULT_TAU;
use flaneur::walk::pvs::PvsPrefetch;
use flaneur::walk::review::{Preset, ReviewConfig};
use flaneur::walk::visual::VisualConfig;
use flaneur::walk::{
    self, FrameSink, Frames, ObjectBuffer, Playback, Report, Selection, WalkConfig,
};
use flaneur::Database;
use flaneur_bench::fidelity::{self, Drawing};
use flaneur_render::Gpu;

/// Frames of each mode drawn against full detail, and their size.
const DRAWN_FRAMES: usize = 60;
const DRAWN_SIZE: (u32, u32) = (320, 180);
/// VISUAL's DoV threshold η: groups of objects seen under 0.1 % of the view sphere may
/// be drawn as their node's internal LOD.
pub const DEMO_ETA: f32 = 0.001;
/// A frame identical to its reference counts as this PSNR in a mean.
const IDENTICAL_DB: f64 = 60.0;

/// One mode's line of the table.
struct ModeRow {
    name: &'static str,
    frames: usize,
    over_50ms: usize,
    pages: u64,
    misses: u64,
    /// Triangles a frame, on average, at the levels LOD selection chose.
    triangles: f64,
    /// Mean PSNR of the frames drawn.
    psnr: Option<f64>,
}

/// A viewer that draws nothing but has the walk load, cull and select levels as for
/// drawing, and counts the triangles selected.
struct Counting {
    frames: usize,
    triangles: u64,
}

impl FrameSink for Counting {
    fn frame(
        &mut self,
        _: usize,
        _: &flaneur::geom::Camera,
        _: &ObjectBuffer,
        selection: &mut Selection<'_>,
    ) -> flaneur::Result<()> {
        self.frames += 1;
        self.triangles += selection
            .drawn
            .iter()
            .map(|d| d.triangles as u64)
            .sum::<u64>();
        Ok(())
    }

    fn draws(&self) -> bool {
        true
    }

    fn lod_tau(&self) -> Option<f32> {
        Some(DEFAULT_TAU)
    }
}

/// Walks the four modes along one walk of `frames` frames through the walkable cells and
/// prints their table. `gpu`: where frames can be drawn.
pub fn walk_modes(db: &Database, frames: usize, gpu: Option<&Gpu>) -> Result<()> {
    let path = cell_walk(db, frames, 1.4 / 30.0, 30.0, 1)?;
    println!(
        "walking the four modes along one walk of {frames} frames through the viewcells{}",
        match gpu {
            Some(_) => format!(
                ", then drawing the first {} of each at {} × {} against full detail",
                DRAWN_FRAMES.min(frames),
                DRAWN_SIZE.0,
                DRAWN_SIZE.1
            ),
            None => String::new(),
        }
    );
    let review_cfg = ReviewConfig::preset(Preset::Optimal);
    let box_cfg = ReviewConfig::preset(Preset::Box);
    let prefetch = PvsPrefetch::Pbnp {
        border: flaneur::prefetch::pvs::DEFAULT_BORDER,
    };
    let visual_cfg = VisualConfig {
        eta: DEMO_ETA,
        ..VisualConfig::default()
    };
    let mut rows = Vec::new();
    for (name, walk) in [
        ("REVIEW", WalkConfig::Review(review_cfg)),
        ("BOX", WalkConfig::Review(box_cfg)),
        ("PVS", WalkConfig::from(prefetch)),
        ("VISUAL (η 0.001)", WalkConfig::Visual(visual_cfg)),
    ] {
        let bar = indicatif::ProgressBar::new(frames as u64);
        let mut row = walk_one(db, &path, name, &walk, &mut |_| bar.inc(1))?;
        bar.finish_and_clear();
        if let Some(gpu) = gpu {
            row.psnr = Some(psnr(db, gpu, &path, name, &walk)?);
        }
        rows.push(row);
    }
    print_table(&rows);
    Ok(())
}

/// `walk` along `path`, counted: its frame times, pages, misses and triangles.
fn walk_one(
    db: &Database,
    path: &CameraPath,
    name: &'static str,
    walk: &WalkConfig,
    tick: &mut dyn FnMut(usize),
) -> Result<ModeRow> {
    // Pages from the store's own counters, so that every mode counts alike: index,
    // meshes, levels, PVS rows, HDoV nodes and V-pages. (REVIEW and VISUAL set them
    // back to zero as they start, too.)
    db.reset_io();
    let mut sink = Counting {
        frames: 0,
        triangles: 0,
    };
    let mut viewer = Playback::path(path).drawn_by(&mut sink).with_progress(tick);
    let report = walk::run(db, walk, &mut viewer, Frames::Each(&mut |_| Ok(())))?;
    drop(viewer);
    // Each walk's own frames, frames over 50 ms and visual misses.
    let (frames, over_50ms, misses) = match &report {
        Report::Review(r) => (
            r.summary.frames,
            r.summary.frames_over_50ms,
            r.summary.visual_misses,
        ),
        Report::Pvs(r) => (r.walked, r.frames_over_50ms, r.visual_misses as u64),
        Report::Visual(r) => {
            let s = &r.summary;
            (s.frames, s.frames_over_50ms, s.visual_misses as u64)
        }
        Report::Scene(_) => anyhow::bail!("the demo walks no memory scene tree ({name})"),
    };
    Ok(ModeRow {
        name,
        frames,
        over_50ms,
        pages: db.io().page_reads,
        misses,
        triangles: sink.triangles as f64 / sink.frames.max(1) as f64,
        psnr: None,
    })
}

/// The first frames of `path` drawn by `walk` and at full detail: their mean PSNR (an
/// identical frame counted as 60 dB).
fn psnr(db: &Database, gpu: &Gpu, path: &CameraPath, name: &str, walk: &WalkConfig) -> Result<f64> {
    let first = CameraPath::new(path.poses.iter().take(DRAWN_FRAMES).cloned().collect())?;
    let drawing = Drawing {
        width: DRAWN_SIZE.0,
        height: DRAWN_SIZE.1,
        lod_tau: Some(DEFAULT_TAU),
    };
    let r = fidelity::run(db, gpu, &first, walk, name, &drawing, |_| {})?;
    let n = r.rows.len().max(1) as f64;
    Ok(r.rows.iter().map(|x| x.psnr.min(IDENTICAL_DB)).sum::<f64>() / n)
}

fn print_table(rows: &[ModeRow]) {
    println!(
        "  {:<18} {:>7} {:>15} {:>10} {:>14} {:>15} {:>10}",
        "mode", "frames", "over 50 ms", "pages", "visual misses", "triangles/frame", "PSNR dB"
    );
    for r in rows {
        let psnr = r.psnr.map_or("-".into(), |p| format!("{p:.1}"));
        println!(
            "  {:<18} {:>7} {:>15} {:>10} {:>14} {:>15.0} {:>10}",
            r.name, r.frames, r.over_50ms, r.pages, r.misses, r.triangles, psnr
        );
    }
    println!(
        "  (pages: every page the walk read, index, meshes, levels, PVS rows, HDoV nodes and V-pages; \
         PSNR against every object in view at full detail, τ = {DEFAULT_TAU} of the viewport)"
    );
}
