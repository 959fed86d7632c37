//! What the window's HUD says: its lines of figures, from the walk's, LOD selection's
//! and the GPU meshes', and the page reads per second they quote. Apart from drawing
//! the HUD (`crate::hud`) and the frame: this is wording and arithmetic, no GPU.

use std::collections::VecDeque;

use super::{WalkMode, WalkWindow};
use crate::hud::HudContent;
use crate::meshes::GpuMeshes;
use flaneur::walk::lod_select::{Drawn, REFINED};
use flaneur::walk::FrameFigures;

/// Frame times the HUD's graph shows.
pub(super) const GRAPH_FRAMES: usize = 120;

impl WalkWindow {
    pub(super) fn pages_per_second(&self) -> f64 {
        match (self.pages.front(), self.pages.back()) {
            (Some(a), Some(b)) if b.0 > a.0 => (b.1 - a.1) as f64 / (b.0 - a.0).as_secs_f64(),
            _ => 0.0,
        }
    }
}

/// The HUD's line about the network, for a database read over HTTP: the client page
/// cache's hit rate and what the walk has fetched so far.
fn network_line(f: &FrameFigures) -> Option<String> {
    let r = f.remote.as_ref()?;
    Some(format!(
        "HTTP client cache hits {:.0}%, {} requests, {:.1} MiB, {} retries",
        100.0 * r.hit_rate(),
        r.requests,
        r.bytes as f64 / 1048576.0,
        r.retries
    ))
}

/// The HUD's lines.
#[allow(clippy::too_many_arguments)]
pub(super) fn hud_content(
    f: &FrameFigures,
    mode: WalkMode,
    tau: Option<f32>,
    (selected, gpu): (&[Drawn], &GpuMeshes),
    (flying, p, pages_per_s): (bool, glam::Vec3, f64),
    message: Option<&str>,
    frame_ms: &VecDeque<f32>,
    wireframe: bool,
) -> HudContent {
    let last = frame_ms.back().copied().unwrap_or(0.0);
    let worst = frame_ms.iter().copied().fold(0.0, f32::max);
    let triangles: usize = selected.iter().map(|d| d.triangles).sum();
    let coarse = selected.iter().filter(|d| d.is_coarse()).count();
    let refined = selected.iter().filter(|d| d.level == REFINED).count();
    let mut lines = vec![
        format!(
            "frame {last:5.1} ms (worst {worst:.1} of the last {})",
            frame_ms.len()
        ),
        format!(
            "mode {} ({}), LOD tau {}",
            mode.name(),
            if flying { "flying" } else { "walking" },
            tau.map_or("off (full detail)".into(), |t| format!("{t}"))
        ),
        format!(
            "triangles {triangles}, objects drawn {} ({coarse} coarse, {refined} refined)",
            selected.len()
        ),
        format!(
            "objects resident {} (GPU {}, {:.1} MiB{}), misses {}",
            f.objects_buffered,
            gpu.len(),
            gpu.bytes() as f64 / 1048576.0,
            gpu.budget().map_or(String::new(), |b| format!(
                " of {:.0}",
                b as f64 / 1048576.0
            )),
            f.visual_misses
        ),
        format!(
            "pages {:.0}/s, index cache hits {}, prefetch queue {}",
            pages_per_s,
            f.cache_hit_rate
                .map_or("-".into(), |h| format!("{:.0}%", 100.0 * h)),
            f.prefetch_queue
        ),
        format!("{} at {:.0}, {:.1}, {:.0}", f.cell, p.x, p.y, p.z),
    ];
    lines.extend(f.looking_at.as_ref().map(|l| format!("looking at {l}")));
    lines.extend(network_line(f));
    lines.extend(f.streamed.as_ref().map(|s| format!("stream: {s}")));
    lines.push(format!(
            "WASD shift F fly  1 review 2 box 3 pvs 4 visual 5 vsc 6 pb 7 conv  [ ] tau  - = budget  H hud  B boxes  T top{}  Q quit",
            if wireframe { "  G lines" } else { "" }
    ));
    if let Some(m) = message {
        lines.push(m.to_string());
    }
    HudContent {
        lines,
        frame_ms: frame_ms.iter().copied().collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_network_line_gives_the_client_cache_hit_rate() {
        let mut f = FrameFigures::default();
        assert_eq!(network_line(&f), None, "a local file has no network line");
        // The renderer never names the store: the figures come filled in by the walk.
        let r = f.remote.insert(Default::default());
        (r.requests, r.bytes, r.page_reads, r.pages_fetched) = (12, 3 << 20, 200, 50);
        assert_eq!(
            network_line(&f).as_deref(),
            Some("HTTP client cache hits 75%, 12 requests, 3.0 MiB, 0 retries")
        );
    }

    #[test]
    fn a_walk_with_streamed_landmarks_shows_the_stream_line() {
        let mut f = FrameFigures::default();
        let lines = |f: &FrameFigures| {
            let gpu = GpuMeshes::default();
            hud_content(
                f,
                WalkMode::Review,
                Some(0.001),
                (&[], &gpu),
                (false, glam::Vec3::ZERO, 0.0),
                None,
                &VecDeque::new(),
                false,
            )
            .lines
        };
        assert!(!lines(&f).iter().any(|l| l.starts_with("stream:")));
        f.streamed = Some("round trip 80.0 ms, span 3".into());
        assert!(lines(&f)
            .iter()
            .any(|l| l == "stream: round trip 80.0 ms, span 3"));
    }
}
