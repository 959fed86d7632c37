//! A walk that hands each frame on and keeps none (`walk::run` with `Frames::Each`,
//! its poses generated as it goes by `Playback::poses`) reports what the same walk
//! keeping its frames (`Frames::Keep`, along a `Playback::path`) reports: every frame,
//! in order, and figures that are the sums, counts and extremes of those frames,
//! tallied a frame at a time; for the PVS, VISUAL and scene-tree walks.

mod common;

use flaneur::hdov::HdovOptions;
use flaneur::path::{cell_poses, cell_walk};
use flaneur::visibility::VisibilityOptions;
use flaneur::walk::pvs::{PvsFrame, PvsPrefetch, PvsWalkReport};
use flaneur::walk::scene::{SceneConfig, SceneFrame, SceneReport, SceneTree, Traversal};
use flaneur::walk::visual::{VisualConfig, VisualFrame, VisualReport};
use flaneur::walk::{self, Frame, Frames, Playback, WalkConfig, WalkState};
use flaneur::{BuildOptions, Database};

const FRAMES: usize = 600;
/// Metres a frame: a cell of 12 m every 48 frames.
const STEP: f32 = 0.25;

fn city() -> common::City {
    common::city(
        80,
        12,
        &BuildOptions {
            page_size: 1024,
            visibility: Some(VisibilityOptions {
                cell_size: 12.0,
                resolution: 16,
                ..Default::default()
            }),
            hdov: Some(HdovOptions::default()),
            ..Default::default()
        },
    )
}

/// `a` and `b` are the same frames as `key` sees them; the first that differs is named.
fn same_frames<F, K: PartialEq + std::fmt::Debug>(a: &[F], b: &[F], key: impl Fn(&F) -> K) {
    assert_eq!(a.len(), b.len(), "frames");
    if let Some(i) = (0..a.len()).find(|&i| key(&a[i]) != key(&b[i])) {
        panic!("frame {i} streamed {:?}, kept {:?}", key(&a[i]), key(&b[i]));
    }
}

/// Moves into a walkable cell other than the frame before's, as every walk counts them.
fn entered(cells: &[Option<u32>]) -> usize {
    cells
        .windows(2)
        .filter(|w| w[1].is_some() && w[1] != w[0])
        .count()
}

#[test]
fn a_streamed_pvs_walk_reports_its_frames_sums() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    let path = cell_walk(&db, FRAMES, STEP, 30.0, 5).unwrap();
    let rule = PvsPrefetch::Pbnp { border: 0.25 };
    let cfg = WalkConfig::from(rule);
    let kept: PvsWalkReport = walk::run(&db, &cfg, &mut Playback::path(&path), Frames::Keep)
        .unwrap()
        .try_into()
        .unwrap();
    let db = Database::open(&c.db).unwrap();
    let mut handed: Vec<(usize, PvsFrame)> = Vec::new();
    let poses = cell_poses(&db, FRAMES, STEP, 30.0, 5).unwrap();
    let r: PvsWalkReport = walk::run(
        &db,
        &cfg,
        &mut Playback::poses(poses),
        Frames::Each(&mut |f| {
            match f {
                Frame::Pvs(p) => handed.push((f.index(), *p)),
                other => panic!("a PVS walk handed on {other:?}"),
            }
            Ok(())
        }),
    )
    .unwrap()
    .try_into()
    .unwrap();
    assert!(r.frames.is_empty());
    assert_eq!(handed.len(), FRAMES);
    assert!(handed.iter().enumerate().all(|(i, (j, _))| i == *j));
    let frames: Vec<PvsFrame> = handed.into_iter().map(|(_, f)| f).collect();
    same_frames(&frames, &kept.frames, |f| *f);

    let cells: Vec<Option<u32>> = frames.iter().map(|f| f.cell).collect();
    assert!(entered(&cells) >= 5, "the walk crosses cells: {cells:?}");
    let inside: Vec<&PvsFrame> = frames.iter().filter(|f| f.cell.is_some()).collect();
    assert_eq!(r.walked, FRAMES);
    assert_eq!(r.cells_entered, entered(&cells));
    assert_eq!(r.frames_outside, FRAMES - inside.len());
    assert_eq!(
        r.transactions,
        frames.iter().filter(|f| f.transaction).count()
    );
    assert_eq!(r.swaps, frames.iter().map(|f| f.swaps).sum::<usize>());
    assert_eq!(r.objects_sent, frames.iter().map(|f| f.sent).sum::<usize>());
    assert_eq!(r.pages, frames.iter().map(|f| f.pages).sum::<u64>());
    assert_eq!(
        r.visual_misses,
        frames.iter().map(|f| f.visual_misses).sum::<usize>()
    );
    let drawn = inside.iter().map(|f| f.drawn as f64).sum::<f64>() / inside.len() as f64;
    assert!((r.mean_drawn - drawn).abs() < 1e-9);
    for k in [
        "cells_entered",
        "transactions",
        "pages",
        "objects_sent",
        "frames_outside",
    ] {
        let (a, b) = (
            serde_json::to_value(&r).unwrap()[k].clone(),
            serde_json::to_value(&kept).unwrap()[k].clone(),
        );
        assert_eq!(a, b, "{k}");
    }
}

#[test]
fn a_streamed_visual_walk_reports_its_frames_sums() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    let path = cell_walk(&db, FRAMES, STEP, 30.0, 6).unwrap();
    let cfg = VisualConfig::default();
    let kept: VisualReport = walk::run(
        &db,
        &cfg.clone().into(),
        &mut Playback::path(&path),
        Frames::Keep,
    )
    .unwrap()
    .try_into()
    .unwrap();
    // A handle of its own, as the first walk's: the HDoV-tree's head is read once a
    // handle.
    let db = Database::open(&c.db).unwrap();
    let mut frames: Vec<VisualFrame> = Vec::new();
    let poses = cell_poses(&db, FRAMES, STEP, 30.0, 6).unwrap();
    let r: VisualReport = walk::run(
        &db,
        &cfg.into(),
        &mut Playback::poses(poses),
        Frames::Each(&mut |f| {
            match f {
                Frame::Visual(v) => frames.push(v.clone()),
                other => panic!("a VISUAL walk handed on {other:?}"),
            }
            Ok(())
        }),
    )
    .unwrap()
    .try_into()
    .unwrap();
    assert!(r.frames.is_empty());
    let s = &r.summary;
    assert_eq!(s.frames, FRAMES);
    assert!(frames.iter().enumerate().all(|(i, f)| f.frame == i));
    // Times differ run to run; what was read and drawn does not.
    let same = |f: &VisualFrame| {
        (
            f.cell,
            f.objects_found,
            f.loaded,
            f.tree_pages,
            f.model_pages,
        )
    };
    same_frames(&frames, &kept.frames, same);
    let cells: Vec<Option<u32>> = frames.iter().map(|f| f.cell).collect();
    assert!(entered(&cells) >= 5, "the walk crosses cells: {cells:?}");
    assert_eq!(s.cells_entered, entered(&cells));
    assert_eq!(s.searches, frames.iter().filter(|f| f.searched).count());
    assert_eq!(
        s.tree_pages,
        frames.iter().map(|f| f.tree_pages).sum::<u64>()
    );
    assert_eq!(
        s.model_pages,
        frames.iter().map(|f| f.model_pages).sum::<u64>()
    );
    assert_eq!(s.loaded, frames.iter().map(|f| f.loaded).sum::<usize>());
    assert_eq!(s.reused, frames.iter().map(|f| f.reused).sum::<usize>());
    assert_eq!(
        s.peak_buffer_bytes,
        frames.iter().map(|f| f.buffer_bytes).max().unwrap()
    );
    assert_eq!(s.initial_load_ms, frames[0].frame_ms);
    let max = frames[1..].iter().map(|f| f.frame_ms).fold(0.0, f64::max);
    assert_eq!(s.max_frame_ms, max);
    let mean = frames[1..].iter().map(|f| f.frame_ms).sum::<f64>() / (FRAMES - 1) as f64;
    assert!((s.mean_frame_ms - mean).abs() < 1e-9 * mean.max(1.0));
    assert_eq!(
        (s.tree_pages, s.model_pages, s.cells_entered),
        (
            kept.summary.tree_pages,
            kept.summary.model_pages,
            kept.summary.cells_entered
        )
    );
}

#[test]
fn a_streamed_scene_walk_reports_its_frames_sums() {
    let c = city();
    let db = Database::open(&c.db).unwrap();
    let tree = SceneTree::load(&db, &flaneur::progress::Silent).unwrap();
    let budget = 4000;
    let cfg = WalkConfig::from(SceneConfig::new(Traversal::Pb { budget }));
    let path = cell_walk(&db, FRAMES, STEP, 30.0, 7).unwrap();
    let kept: SceneReport = WalkState::new(&db)
        .with_scene_tree(tree)
        .run(&cfg, &mut Playback::path(&path), Frames::Keep)
        .unwrap()
        .try_into()
        .unwrap();
    let db = Database::open(&c.db).unwrap();
    let tree = SceneTree::load(&db, &flaneur::progress::Silent).unwrap();
    let mut frames: Vec<SceneFrame> = Vec::new();
    let poses = cell_poses(&db, FRAMES, STEP, 30.0, 7).unwrap();
    let r: SceneReport = WalkState::new(&db)
        .with_scene_tree(tree)
        .run(
            &cfg,
            &mut Playback::poses(poses),
            Frames::Each(&mut |f| {
                match f {
                    Frame::Scene(s) => frames.push(s.clone()),
                    other => panic!("a scene-tree walk handed on {other:?}"),
                }
                Ok(())
            }),
        )
        .unwrap()
        .try_into()
        .unwrap();
    assert!(r.frames.is_empty());
    let s = &r.summary;
    let same = |f: &SceneFrame| (f.cell, f.visited, f.drawn, f.triangles, f.pages);
    same_frames(&frames, &kept.frames, same);
    let cells: Vec<Option<u32>> = frames.iter().map(|f| f.cell).collect();
    assert!(entered(&cells) >= 5, "the walk crosses cells: {cells:?}");
    assert_eq!(s.frames, FRAMES);
    assert_eq!(s.cells_entered, entered(&cells));
    assert_eq!(
        s.max_triangles,
        frames.iter().map(|f| f.triangles).max().unwrap()
    );
    assert_eq!(
        s.frames_over_budget,
        frames.iter().filter(|f| f.triangles > budget).count()
    );
    let mean = frames.iter().map(|f| f.triangles as f64).sum::<f64>() / FRAMES as f64;
    assert!((s.mean_triangles - mean).abs() < 1e-9 * mean);
    assert_eq!(s.frames_ended, frames.iter().filter(|f| f.ended).count());
    let first = frames
        .iter()
        .find_map(|f| f.too_big.map(|(id, t)| (f.frame, id, t)));
    assert_eq!(s.first_too_big, first);
    assert_eq!(r.too_big(), kept.too_big());
    assert_eq!(r.within_budget(), kept.within_budget());
}
