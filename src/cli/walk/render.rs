//! `flaneur walk --render`: the frames a walk draws headless (landmarks refined ahead
//! or streamed, as asked), and what drawing them cost.

use std::path::PathBuf;

use anyhow::Result;

use super::super::write_file;
use flaneur::Database;

/// A bar counting the walk's `frames`, hidden when quiet.
fn frame_bar(frames: usize, quiet: bool) -> indicatif::ProgressBar {
    if quiet {
        indicatif::ProgressBar::hidden()
    } else {
        indicatif::ProgressBar::new(frames as u64)
    }
}

/// Runs `walk` over `frames` poses under a bar of its frames (hidden when `quiet`), with a frame
/// writer when `render` asks for one (frames drawn with a ground reaching `far` past the
/// city), else with no sink; and what drawing cost. `walk` is handed the sink and what
/// to tell of each frame.
pub(super) fn rendered<R>(
    db: &Database,
    (frames, quiet): (usize, bool),
    render: Option<&RenderOpts>,
    far: f32,
    walk: impl FnOnce(&mut dyn flaneur::walk::FrameSink, &mut dyn FnMut(usize)) -> flaneur::Result<R>,
) -> Result<(R, Option<Drawn>)> {
    let bar = frame_bar(frames, quiet);
    let mut tick = |_: usize| bar.inc(1);
    let Some(r) = render else {
        let result = walk(&mut flaneur::walk::NoSink, &mut tick)?;
        bar.finish_and_clear();
        return Ok((result, None));
    };
    let gpu = flaneur_render::Gpu::headless()?;
    let mut writer =
        flaneur_render::FrameWriter::new(&gpu, r.size, (&db.bounds(), far), &r.dir, r.every)?;
    if let Some(tau) = r.lod_tau {
        writer = writer.with_lod_tau(tau)?;
    }
    if r.adapt_ahead {
        writer = writer.adapting_ahead();
    }
    let mut streamed = None;
    if let (Some(addr), Some(tau)) = (&r.stream, r.lod_tau) {
        let (landmarks, figures) = super::super::stream_client::stream_landmarks(addr, tau)?;
        streamed = Some((addr.as_str(), figures));
        writer = writer.with_remote(Box::new(landmarks));
    }
    let result = walk(&mut writer, &mut tick)?;
    bar.finish_and_clear();
    if let Some((addr, figures)) = streamed {
        let f = figures.lock().unwrap_or_else(|p| p.into_inner());
        println!(
            "streamed landmarks from {addr}: {} of {} frames applied a batch, {} views sent, \
             {:.1} KiB of batches (largest {:.1} KiB), round trip {}, prediction span {} frames",
            f.modified,
            f.frames,
            f.views,
            f.bytes as f64 / 1024.0,
            f.largest_batch as f64 / 1024.0,
            f.round_trip.map_or("not measured".into(), |t| format!(
                "{:.1} ms",
                t.as_secs_f64() * 1e3
            )),
            f.span
        );
        if f.broken_frames > 0 {
            println!(
                "  the session broke: {} frames drawn with the landmarks as they stood, {} \
                 reconnections; the last failure: {}",
                f.broken_frames,
                f.reconnects,
                f.last_failure.as_deref().unwrap_or("?")
            );
        }
    }
    Ok((
        result,
        Some(Drawn {
            adapter: gpu.adapter.clone(),
            times: writer.times,
        }),
    ))
}

/// What drew a walk, and what it cost.
pub(super) struct Drawn {
    adapter: flaneur_render::AdapterInfo,
    times: flaneur_render::FrameTimes,
}

/// What drawing a walk's frames cost, printed and written to `render.csv` beside them
/// (nothing when the walk was not drawn).
pub(super) fn print_render(drawn: Option<Drawn>, r: Option<&RenderOpts>) -> Result<()> {
    let (Some(drawn), Some(r)) = (drawn, r) else {
        return Ok(());
    };
    let (adapter, t) = (&drawn.adapter, &drawn.times);
    let csv = r.dir.join("render.csv");
    write_file(&csv, &t.to_csv())?;
    let stats = |v: &[f64]| {
        let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
        (mean, v.iter().copied().fold(0.0, f64::max))
    };
    let ((select, select_max), (up, up_max), (draw, draw_max)) =
        (stats(&t.select_ms), stats(&t.upload_ms), stats(&t.draw_ms));
    println!(
        "rendered {} frames of {} × {} on {} ({:?}), {} written to {}: LOD selection {:.1} ms a \
             frame (most {:.1}), uploads {:.1} ms (most {:.1}), drawing and reading back {:.1} ms \
             (most {:.1}); {} uploads, {} frees, at most {:.1} MiB of meshes on the GPU",
        t.frames,
        r.size.0,
        r.size.1,
        adapter.name,
        adapter.backend,
        t.written,
        r.dir.display(),
        select,
        select_max,
        up,
        up_max,
        draw,
        draw_max,
        t.uploads,
        t.evictions,
        t.peak_gpu_bytes as f64 / 1048576.0
    );
    if let Some(c) = t.lod {
        println!(
            "  LOD selection: {} draws coarser than full detail, {} levels read; {} draws refined view by view ({} vertex splits and edge collapses), {} progressive meshes decoded off the frame's thread ({} draws at discrete levels meanwhile); {} pages",
            c.coarse_draws, c.levels_read, c.refined_draws, c.refine_ops, c.decoded, c.drawn_while_decoding, c.pages
        );
        if r.stream.is_some() {
            println!("  {} draws of landmarks from the stream", c.streamed_draws);
        }
    }
    println!("  per-frame times in {}", csv.display());
    Ok(())
}

/// Where and how `walk --render` draws its frames.
pub(super) struct RenderOpts {
    pub dir: PathBuf,
    pub size: (u32, u32),
    pub every: usize,
    pub lod_tau: Option<f32>,
    pub adapt_ahead: bool,
    pub stream: Option<String>,
}
