//! The `visual-vs-review` experiment (Shou 2002 §5.8.5, Table 5.3, Figs. 5.24–5.27):
//! VISUAL, the HDoV-tree walkthrough, against REVIEW, the spatial one, played along the
//! same recorded sessions: frame-preparation time (mean, variance, the longest), the
//! memory held, the pages read, and the visible objects each leaves out.
//!
//! - **Sessions** (Fig. 5.27): `normal`, a walk through the walkable viewcells at
//!   `speed` m/s; `turning`, the same walk looking left and right (±35°, a 4 s period);
//!   `back-forth`, the same walk played 3 s forward, 1.5 s back. Table 5.3 and
//!   Figs. 5.24–5.25 are the normal session.
//! - **Walks**: VISUAL at each η of Table 5.3, without prefetch as the thesis's; VISUAL
//!   at η = 0.001 with our next-cell prefetch (labelled `visual+prefetch`); REVIEW
//!   (CSearch, index cache and prefetching: the thesis's whole system) with each query
//!   box. A REVIEW box of b metres is a disk cell b deep: a frustum b/SF deep, the
//!   disk cell SF times its box (the thesis gives the box, not how it is cut).
//! - **Frame time** is the walk's own time for a frame (its retrieval, reading, culling),
//!   not drawing it: the thesis's frame times include rendering on its 2002 hardware,
//!   which is not ours to measure here. Frame 0, the cold load, is left out of both.
//!   Both walks are paced to the path's clock at `pace` times real time, so that
//!   REVIEW's prefetch thread gets a viewer's time.
//! - **Missed**: per frame, objects of the eye's viewcell's PVS (DoV > 0) within the
//!   full frustum (1 km) that the walk did not draw, neither as themselves nor inside
//!   the box of a group it drew (a node at an internal LOD): what REVIEW's box loses.
//!
//! Pages are exact counts; times are this machine's.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use crate::report::Report;
use crate::walk_setup::walk_path;
use flaneur::database::Database;
use flaneur::error::{Error, Result};
use flaneur::geom::{Aabb, Camera};
use flaneur::path::{cell_walk, CameraPath, Pose};
use flaneur::walk::review::{Preset, ReviewConfig, WalkReport};
use flaneur::walk::settings;
use flaneur::walk::visual::{VisualConfig, VisualReport};
use flaneur::walk::{FrameSink, ObjectBuffer, Selection};

/// The settings of the experiment.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VisualVsReviewConfig {
    /// Frames per session.
    pub frames: usize,
    /// Frames per second of the recorded sessions.
    pub fps: f32,
    /// The walker's speed, m/s.
    pub speed: f32,
    /// VISUAL's thresholds (Table 5.3's nine by default).
    pub etas: Vec<f32>,
    /// REVIEW's query boxes, metres (the thesis: 400 and 200).
    pub boxes: Vec<f32>,
    /// The sessions walked: `normal`, `turning`, `back-forth`.
    pub sessions: Vec<String>,
    /// Both walks play the path this many times faster than real time.
    pub pace: f32,
    /// Seed of the walk.
    pub seed: u64,
    /// VISUAL's selection rule: ours (screen, the default) or the thesis's (Table 5.3's
    /// own), under the thesis's τ.
    pub selection: flaneur::hdov::Selection,
}

impl Default for VisualVsReviewConfig {
    fn default() -> Self {
        VisualVsReviewConfig {
            frames: 1800,
            fps: 30.0,
            speed: 10.0,
            etas: vec![
                0.0, 0.00005, 0.0001, 0.0002, 0.0003, 0.0005, 0.001, 0.002, 0.004,
            ],
            boxes: vec![400.0, 200.0],
            sessions: SESSIONS.iter().map(|s| s.to_string()).collect(),
            pace: settings::DEFAULT_PACE,
            seed: 1,
            selection: flaneur::hdov::Selection::Screen,
        }
    }
}

/// The sessions of Fig. 5.27.
pub const SESSIONS: [&str; 3] = ["normal", "turning", "back-forth"];

/// The threshold VISUAL is compared at, and its prefetch's.
pub const COMPARED_ETA: f32 = 0.001;

impl VisualVsReviewConfig {
    /// Checks the settings, naming a bad one.
    pub fn validate(&self) -> Result<()> {
        if self.frames < 2 || !(self.fps > 0.0 && self.speed > 0.0) {
            return Err(Error::Invalid(format!(
                "visual-vs-review needs at least 2 frames and a positive fps and speed (got {}, {}, {})",
                self.frames, self.fps, self.speed
            )));
        }
        if self.etas.iter().any(|e| !(e.is_finite() && *e >= 0.0)) {
            return Err(Error::Invalid(format!(
                "visual-vs-review thresholds {:?}: give numbers ≥ 0",
                self.etas
            )));
        }
        if self.boxes.iter().any(|b| !(b.is_finite() && *b > 1.0)) {
            return Err(Error::Invalid(format!(
                "REVIEW's query boxes {:?}: give sizes of more than a metre",
                self.boxes
            )));
        }
        if let Some(s) = self
            .sessions
            .iter()
            .find(|s| !SESSIONS.contains(&s.as_str()))
        {
            return Err(Error::Invalid(format!(
                "unknown session '{s}' ({})",
                SESSIONS.join(", ")
            )));
        }
        settings::check_pace(self.pace)
    }
}

/// One walk of one session.
#[derive(Clone, Debug, serde::Serialize)]
pub struct WalkRow {
    pub session: String,
    /// `visual`, `visual+prefetch` or `review`.
    pub system: String,
    /// VISUAL's η, or REVIEW's box in metres.
    pub setting: f32,
    pub mean_frame_ms: f64,
    pub frame_ms_variance: f64,
    pub max_frame_ms: f64,
    pub frames_over_50ms: usize,
    /// Searches (VISUAL: the tree; REVIEW: its index) on either thread.
    pub queries: usize,
    /// Mean time of a search on the viewer's thread, ms (Fig. 5.27a).
    pub mean_query_ms: f64,
    /// Pages read over the walk (Fig. 5.27b).
    pub pages: u64,
    /// The most memory the walk held, MiB.
    pub peak_mib: f64,
    /// Objects (and groups) drawn per frame.
    pub mean_drawn: f64,
    /// Triangles drawn per frame.
    pub mean_triangles: f64,
    /// Visible objects within the frustum not drawn, per frame.
    pub mean_missed: f64,
    /// Frames outside every viewcell (VISUAL's fallback).
    pub frames_outside: usize,
}

/// What the experiment measured.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VisualVsReviewReport {
    pub config: VisualVsReviewConfig,
    pub objects: u64,
    pub rows: Vec<WalkRow>,
    /// Frame times of the normal session, per walk: (system label, ms per frame).
    pub series: Vec<(String, Vec<f64>)>,
}

/// Each frame's eye and drawn objects' ids and boxes, as the walk handed them over.
#[derive(Default)]
struct Drawn {
    frames: Vec<(Camera, Vec<(u64, Aabb)>)>,
}

impl FrameSink for Drawn {
    fn frame(
        &mut self,
        _: usize,
        camera: &Camera,
        _: &ObjectBuffer,
        s: &mut Selection<'_>,
    ) -> Result<()> {
        let drawn = s
            .culled
            .iter()
            .map(|o| (o.entry.id, o.entry.bounds))
            .collect();
        self.frames.push((*camera, drawn));
        Ok(())
    }
}

/// Runs every session's walks over `db`; `tick(done, total)` after each walk.
pub fn run(
    db: &Database,
    cfg: &VisualVsReviewConfig,
    mut tick: impl FnMut(usize, usize),
) -> Result<VisualVsReviewReport> {
    cfg.validate()?;
    db.hdov_head()?;
    let base = cell_walk(db, cfg.frames, cfg.speed / cfg.fps, cfg.fps, cfg.seed)?;
    let entries: HashMap<u64, Aabb> = db
        .range(&db.bounds())?
        .objects
        .into_iter()
        .map(|o| (o.id, o.bounds))
        .collect();
    let mut truth = Truth {
        db,
        entries: &entries,
        pvs: HashMap::new(),
    };
    let per_session = cfg.etas.len() + 1 + cfg.boxes.len();
    let total = per_session * cfg.sessions.len();
    let mut rows = Vec::with_capacity(total);
    let mut series = Vec::new();
    for session in &cfg.sessions {
        let path = session_path(&base, session)?;
        let normal = session == "normal";
        for (system, vc) in visual_configs(cfg) {
            let mut drawn = Drawn::default();
            let r: VisualReport = walk_path(db, &path, vc.clone(), &mut drawn)?;
            let s = &r.summary;
            if normal {
                series.push((
                    format!("{system} η = {}", vc.eta),
                    r.frames.iter().map(|f| f.frame_ms).collect(),
                ));
            }
            rows.push(WalkRow {
                session: session.clone(),
                system,
                setting: vc.eta,
                mean_frame_ms: s.mean_frame_ms,
                frame_ms_variance: s.frame_ms_variance,
                max_frame_ms: s.max_frame_ms,
                frames_over_50ms: s.frames_over_50ms,
                queries: s.searches + s.prefetches + s.fallback_queries,
                mean_query_ms: s.mean_search_ms,
                pages: s.tree_pages + s.model_pages + s.other_pages,
                peak_mib: s.peak_buffer_bytes as f64 / 1048576.0,
                mean_drawn: s.mean_drawn,
                mean_triangles: s.mean_triangles,
                mean_missed: truth.missed(&drawn)?,
                frames_outside: s.frames_outside,
            });
            tick(rows.len(), total);
        }
        for &b in &cfg.boxes {
            let preset = ReviewConfig::preset(Preset::Optimal);
            let rc = ReviewConfig {
                far: b / preset.sf,
                pace: Some(cfg.pace),
                ..preset
            };
            let mut drawn = Drawn::default();
            let r: WalkReport = walk_path(db, &path, rc, &mut drawn)?;
            let s = &r.summary;
            let sync: Vec<f64> = r
                .frames
                .iter()
                .filter(|f| f.sync_query)
                .map(|f| f.query_ms)
                .collect();
            if normal {
                series.push((
                    format!("review {b} m"),
                    r.frames.iter().map(|f| f.frame_ms).collect(),
                ));
            }
            rows.push(WalkRow {
                session: session.clone(),
                system: "review".into(),
                setting: b,
                mean_frame_ms: s.mean_frame_ms,
                frame_ms_variance: s.frame_ms_variance,
                max_frame_ms: s.max_frame_ms,
                frames_over_50ms: s.frames_over_50ms,
                queries: s.queries,
                mean_query_ms: sync.iter().sum::<f64>() / sync.len().max(1) as f64,
                pages: s.index_pages + s.mesh_pages,
                peak_mib: s.peak_buffer_bytes as f64 / 1048576.0,
                mean_drawn: r.frames.iter().map(|f| f.objects_drawn as f64).sum::<f64>()
                    / r.frames.len().max(1) as f64,
                mean_triangles: r
                    .frames
                    .iter()
                    .map(|f| f.triangles_drawn as f64)
                    .sum::<f64>()
                    / r.frames.len().max(1) as f64,
                mean_missed: truth.missed(&drawn)?,
                frames_outside: 0,
            });
            tick(rows.len(), total);
        }
    }
    Ok(VisualVsReviewReport {
        config: cfg.clone(),
        objects: db.objects(),
        rows,
        series,
    })
}

/// The VISUAL walks of each session, each with the system its rows name: one per η of
/// `cfg`, then VISUAL with prefetching at [`COMPARED_ETA`]. A function of its own to
/// keep `run` short.
fn visual_configs(cfg: &VisualVsReviewConfig) -> Vec<(String, VisualConfig)> {
    let mut visuals: Vec<(String, VisualConfig)> = cfg
        .etas
        .iter()
        .map(|&eta| {
            (
                "visual".to_string(),
                VisualConfig {
                    eta,
                    pace: Some(cfg.pace),
                    selection: cfg.selection,
                    ..VisualConfig::default()
                },
            )
        })
        .collect();
    visuals.push((
        "visual+prefetch".into(),
        VisualConfig {
            eta: COMPARED_ETA,
            prefetch_k: Some(settings::DEFAULT_K),
            pace: Some(cfg.pace),
            selection: cfg.selection,
            ..VisualConfig::default()
        },
    ));
    visuals
}

/// `base` as session `name` plays it: the same walk, looking about or going back and
/// forth.
fn session_path(base: &CameraPath, name: &str) -> Result<CameraPath> {
    let poses = &base.poses;
    let out: Vec<Pose> = match name {
        "normal" => poses.clone(),
        "turning" => poses
            .iter()
            .map(|p| Pose {
                yaw: p.yaw
                    + 35f32.to_radians() * (p.time as f32 * std::f32::consts::TAU / 4.0).sin(),
                ..*p
            })
            .collect(),
        "back-forth" => {
            // 3 s forward, 1.5 s back: the path's index runs on, then back a half.
            let dt = poses.get(1).map_or(1.0, |p| p.time - poses[0].time);
            let (fwd, back) = ((3.0 / dt) as usize, (1.5 / dt) as usize);
            let mut index = 0usize;
            (0..poses.len())
                .map(|i| {
                    let phase = i % (fwd + back).max(1);
                    if phase < fwd {
                        index = (index + 1).min(poses.len() - 1);
                    } else {
                        index = index.saturating_sub(1);
                    }
                    // Going back, the walker still looks the way it was going.
                    Pose {
                        time: poses[i].time,
                        ..poses[index]
                    }
                })
                .collect()
        }
        other => return Err(Error::Invalid(format!("unknown session '{other}'"))),
    };
    CameraPath::new(out)
}

/// The visible objects of each frame: its viewcell's PVS within the frustum.
struct Truth<'a> {
    db: &'a Database,
    entries: &'a HashMap<u64, Aabb>,
    pvs: HashMap<u32, Vec<u64>>,
}

impl Truth<'_> {
    /// Visible objects within each frame's full frustum (1 km) that `drawn` did not
    /// draw, as themselves or inside a drawn group's box; per frame, over frames in a
    /// viewcell.
    fn missed(&mut self, drawn: &Drawn) -> Result<f64> {
        let (mut missed, mut frames) = (0usize, 0usize);
        for (camera, ids) in &drawn.frames {
            let Some(cell) = self.db.viewcell_at(camera.position)? else {
                continue;
            };
            if !self.pvs.contains_key(&cell) {
                let ids = self.db.pvs(cell)?.map(|p| p.ids).unwrap_or_default();
                self.pvs.insert(cell, ids);
            }
            let full = Camera {
                far: flaneur::geom::DEFAULT_FAR,
                ..*camera
            }
            .frustum();
            let seen: HashSet<u64> = ids.iter().map(|d| d.0).collect();
            let groups: Vec<&Aabb> = ids
                .iter()
                .filter(|d| d.0 & flaneur::walk::GROUP_ID != 0)
                .map(|d| &d.1)
                .collect();
            frames += 1;
            for id in &self.pvs[&cell] {
                let b = self.entries.get(id).ok_or_else(|| {
                    Error::Invalid(format!(
                        "object {id} of viewcell {cell}'s PVS is not in the database's index"
                    ))
                })?;
                if full.overlaps_aabb(b)
                    && !seen.contains(id)
                    && !groups.iter().any(|g| contains(g, b))
                {
                    missed += 1;
                }
            }
        }
        Ok(missed as f64 / frames.max(1) as f64)
    }
}

/// Whether `outer` holds `inner`.
fn contains(outer: &Aabb, inner: &Aabb) -> bool {
    outer.min.cmple(inner.min).all() && inner.max.cmple(outer.max).all()
}

/// The plots' file names.
pub const PLOT_FRAMES: &str = "visual-vs-review-frames.png";
pub const PLOT_ETA: &str = "visual-vs-review-eta.png";

impl VisualVsReviewReport {
    /// The row of `system` at `setting` in `session`.
    pub fn row(&self, session: &str, system: &str, setting: f32) -> Option<&WalkRow> {
        self.rows
            .iter()
            .find(|r| r.session == session && r.system == system && r.setting == setting)
    }
}

impl Report for VisualVsReviewReport {
    fn name(&self) -> &'static str {
        "visual-vs-review"
    }

    fn to_csv(&self) -> String {
        let mut s = String::from(
            "session,system,setting,mean_frame_ms,frame_ms_variance,max_frame_ms,frames_over_50ms,queries,mean_query_ms,pages,peak_mib,mean_drawn,mean_triangles,mean_missed,frames_outside\n",
        );
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{},{:.4},{:.4},{:.3},{},{},{:.3},{},{:.2},{:.1},{:.0},{:.2},{}\n",
                r.session,
                r.system,
                r.setting,
                r.mean_frame_ms,
                r.frame_ms_variance,
                r.max_frame_ms,
                r.frames_over_50ms,
                r.queries,
                r.mean_query_ms,
                r.pages,
                r.peak_mib,
                r.mean_drawn,
                r.mean_triangles,
                r.mean_missed,
                r.frames_outside
            ));
        }
        s
    }

    fn extra_csvs(&self) -> Vec<(&'static str, String)> {
        let mut s = String::from("walk,frame,frame_ms\n");
        for (name, ms) in &self.series {
            for (i, m) in ms.iter().enumerate() {
                s.push_str(&format!("{name},{i},{m:.4}\n"));
            }
        }
        vec![("visual-vs-review-frames.csv", s)]
    }

    fn markdown(&self) -> String {
        let c = &self.config;
        let mut s = format!(
            "# VISUAL against REVIEW (Shou 2002 §5.8.5, Table 5.3, Figs. 5.24–5.27)\n\n\
             Sessions of {} frames at {} fps through the walkable viewcells of a city of {} \
             objects at {} m/s (seed {}), played {}× real time; VISUAL under the {} selection. \
             Frame time is the walk's own \
             (retrieval, reading, culling), frame 0 left out; the thesis's includes rendering. \
             Missed: visible objects within the frustum that the walk did not draw, per frame.\n\n",
            c.frames,
            c.fps,
            self.objects,
            c.speed,
            c.seed,
            c.pace,
            c.selection.name()
        );
        for session in &c.sessions {
            s.push_str(&format!(
                "## Session {session}\n\n| walk | mean frame ms | variance | max ms | over 50 ms | queries | ms a query | pages | peak MiB | drawn | triangles | missed | outside |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
            ));
            for r in self.rows.iter().filter(|r| &r.session == session) {
                let label = match r.system.as_str() {
                    "review" => format!("REVIEW, {} m box", r.setting),
                    sys => format!("{} (η = {})", sys.to_uppercase(), r.setting),
                };
                s.push_str(&format!(
                    "| {label} | {:.3} | {:.3} | {:.1} | {} | {} | {:.2} | {} | {:.1} | {:.1} | {:.0} | {:.2} | {} |\n",
                    r.mean_frame_ms,
                    r.frame_ms_variance,
                    r.max_frame_ms,
                    r.frames_over_50ms,
                    r.queries,
                    r.mean_query_ms,
                    r.pages,
                    r.peak_mib,
                    r.mean_drawn,
                    r.mean_triangles,
                    r.mean_missed,
                    r.frames_outside
                ));
            }
            s.push('\n');
        }
        if let (Some(v), Some(r)) = (
            self.row("normal", "visual", COMPARED_ETA),
            c.boxes
                .first()
                .and_then(|b| self.row("normal", "review", *b)),
        ) {
            s.push_str(&format!(
                "Normal session, VISUAL (η = {COMPARED_ETA}) against REVIEW ({} m box): mean frame \
                 time {:.3} ms against {:.3} ms ({:.1}× lower), variance {:.3} against {:.3}, \
                 memory {:.1} MiB against {:.1} MiB, {:.2} visible objects missed a frame against \
                 {:.2}. The thesis: 12.78 ms against 57.84 ms (4.5×), variance 4.35 against \
                 16.46, 28 MB against 62 MB.\n",
                r.setting,
                v.mean_frame_ms,
                r.mean_frame_ms,
                r.mean_frame_ms / v.mean_frame_ms.max(1e-9),
                v.frame_ms_variance,
                r.frame_ms_variance,
                v.peak_mib,
                r.peak_mib,
                v.mean_missed,
                r.mean_missed
            ));
        }
        s
    }

    fn plot(&self, dir: &Path) -> Result<()> {
        use crate::plot::{line_plot, LinePlot, Series};
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let wanted = |name: &str| {
            name.starts_with("review")
                || name == format!("visual η = {COMPARED_ETA}")
                || name == "visual η = 0.0003"
        };
        line_plot(
            &dir.join(PLOT_FRAMES),
            &LinePlot {
                title: "Frame time along the normal session (Figs. 5.24–5.25)".into(),
                x_label: "frame".into(),
                y_label: "ms".into(),
                series: self
                    .series
                    .iter()
                    .filter(|(n, _)| wanted(n))
                    .map(|(n, ms)| Series {
                        name: n.clone(),
                        points: ms
                            .iter()
                            .enumerate()
                            .skip(1)
                            .map(|(i, m)| (i as f64, *m))
                            .collect(),
                    })
                    .collect(),
            },
        )?;
        line_plot(
            &dir.join(PLOT_ETA),
            &LinePlot {
                title: "VISUAL's mean frame time against η, normal session (Table 5.3)".into(),
                x_label: "DoV threshold η".into(),
                y_label: "ms".into(),
                series: vec![Series {
                    name: "VISUAL".into(),
                    points: self
                        .rows
                        .iter()
                        .filter(|r| r.session == "normal" && r.system == "visual")
                        .map(|r| (r.setting as f64, r.mean_frame_ms))
                        .collect(),
                }],
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn base() -> CameraPath {
        CameraPath::new(
            (0..100)
                .map(|i| Pose {
                    time: i as f64 * 0.1,
                    position: Vec3::new(i as f32, 1.7, 0.0),
                    yaw: 0.0,
                    pitch: 0.0,
                })
                .collect(),
        )
        .unwrap()
    }

    #[test]
    fn sessions_keep_the_clock_and_vary_the_view_or_the_way() {
        let b = base();
        let turning = session_path(&b, "turning").unwrap();
        assert!(turning.poses.iter().any(|p| p.yaw.abs() > 0.3));
        let bf = session_path(&b, "back-forth").unwrap();
        assert_eq!(bf.poses.len(), b.poses.len());
        assert!(bf.poses.iter().zip(&b.poses).all(|(a, b)| a.time == b.time));
        // It goes back at times, and gets less far than the walk.
        assert!(bf
            .poses
            .windows(2)
            .any(|w| w[1].position.x < w[0].position.x));
        assert!(bf.poses.last().unwrap().position.x < b.poses.last().unwrap().position.x);
        assert!(session_path(&b, "flying").is_err());
    }

    #[test]
    fn bad_settings_are_named() {
        let bad = VisualVsReviewConfig {
            sessions: vec!["flying".into()],
            ..Default::default()
        };
        assert!(bad.validate().unwrap_err().to_string().contains("flying"));
        let bad = VisualVsReviewConfig {
            boxes: vec![0.0],
            ..Default::default()
        };
        assert!(bad.validate().is_err());
    }
}
