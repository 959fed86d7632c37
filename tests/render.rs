//! The renderer headless: a small generated city drawn offscreen from a known
//! viewpoint. The id target must show, pixel for pixel, the object a ray through the
//! pixel's centre meets first (the CPU ray caster of `visibility` is the judge), and the
//! colour image must match a stored reference within a tolerance. It needs a GPU
//! adapter: CI installs Mesa's software one (lavapipe).

mod common;

use std::collections::HashMap;

use flaneur::geom::fov_x_for;
use flaneur::geom::Camera;
use flaneur::path::motion::{self, Motion};
use flaneur::visibility::RayScene;
use flaneur::walk::review::{self, Preset, ReviewConfig};
use flaneur::walk::{self, FrameSink, Frames, NoSink, ObjectBuffer, Playback, WalkConfig};
use flaneur::{BuildOptions, Database};
use flaneur_bench::report::Report;
use flaneur_render::{shot, FrameWriter, Gpu, Shot};
use glam::Vec3;

const WIDTH: u32 = 192;
const HEIGHT: u32 = 128;
const REFERENCE: &str = "tests/data/render-reference.png";

/// The test city (60 objects) built with `opts` into `dir`.
fn build(dir: &std::path::Path, opts: &BuildOptions) -> Database {
    let scene = dir.join("c.scene");
    let config = citygen::CityConfig {
        objects: 60,
        seed: 3,
        landmarks: 0.0,
        ..Default::default()
    };
    citygen::write_city(&config, &scene).unwrap();
    let db_path = dir.join("c.flaneur");
    flaneur::build_from_scene(&scene, &db_path, opts).unwrap();
    Database::open(&db_path).unwrap()
}

/// The test city, its database, and a camera above its south-west looking across it.
fn city(dir: &std::path::Path) -> (Database, Camera) {
    let db = build(
        dir,
        &BuildOptions {
            lod: None,
            ..Default::default()
        },
    );
    let b = db.bounds();
    let (centre, extent) = (b.center(), b.extent());
    let eye = Vec3::new(b.min.x - 0.1 * extent.x, 45.0, b.min.z - 0.1 * extent.z);
    let to = centre - eye;
    let yaw = to.z.atan2(to.x);
    let camera = Camera::new(eye, yaw, -0.35)
        .unwrap()
        .with_fov(50f32.to_radians(), 50f32.to_radians())
        .unwrap();
    (db, camera)
}

/// `db` as `camera` sees it at full detail, `camera` fitted to the picture: what
/// `flaneur shot` draws.
fn full_detail(db: &Database, gpu: &Gpu, camera: &Camera) -> Shot {
    let camera = camera.fitted_to(WIDTH as f32 / HEIGHT as f32).unwrap();
    let meshes: Vec<_> = (db.in_view(&camera).unwrap().iter())
        .map(|o| (o.id, db.mesh(o).unwrap()))
        .collect();
    shot(gpu, &camera, &db.bounds(), &meshes, WIDTH, HEIGHT).unwrap()
}

/// The fidelity experiment over `path` with `walk` (named `mode`), square pictures of
/// `size` pixels drawn under `lod_tau`.
fn fidelity(
    db: &Database,
    gpu: &Gpu,
    path: &flaneur::path::CameraPath,
    walk: impl Into<WalkConfig>,
    mode: &str,
    (size, lod_tau): (u32, Option<f32>),
) -> flaneur_bench::fidelity::FidelityReport {
    let drawing = flaneur_bench::fidelity::Drawing {
        width: size,
        height: size,
        lod_tau,
    };
    flaneur_bench::fidelity::run(db, gpu, path, &walk.into(), mode, &drawing, |_| {}).unwrap()
}

/// Walks `path` through `db` under `cfg`, handing each frame to `sink`, its frames kept.
fn review_walk_sink(
    db: &Database,
    path: &flaneur::path::CameraPath,
    cfg: &ReviewConfig,
    sink: &mut dyn FrameSink,
) -> flaneur::Result<review::WalkReport> {
    walk::run(
        db,
        &cfg.clone().into(),
        &mut Playback::path(path).drawn_by(sink),
        Frames::Keep,
    )?
    .try_into()
}

/// Walks `path` over `db`'s visibility with the PVS client prefetching by `rule`, handing
/// each frame to `sink`, its frames kept.
fn pvs_walk_sink(
    db: &Database,
    path: &flaneur::path::CameraPath,
    rule: flaneur::walk::pvs::PvsPrefetch,
    sink: &mut dyn FrameSink,
) -> flaneur::Result<flaneur::walk::pvs::PvsWalkReport> {
    walk::run(
        db,
        &rule.into(),
        &mut Playback::path(path).drawn_by(sink),
        Frames::Keep,
    )?
    .try_into()
}

fn gpu() -> Gpu {
    Gpu::headless().unwrap_or_else(|e| {
        panic!("{e}\nthe render tests need a GPU adapter; .ci/run installs Mesa's software one")
    })
}

#[test]
fn the_id_target_shows_what_rays_meet_and_the_image_matches_its_reference() {
    let dir = tempfile::tempdir().unwrap();
    let (db, camera) = city(dir.path());
    let gpu = gpu();
    let picture = full_detail(&db, &gpu, &camera);
    let frame = &picture.frame;
    assert_eq!(frame.objects.len(), (WIDTH * HEIGHT) as usize);
    assert!(picture.objects > 10 && picture.gpu_bytes > 0, "{picture:?}");

    // The judge: every object's mesh in one ray scene, a ray through each pixel centre.
    let all = db.range(&db.bounds()).unwrap();
    let meshes: Vec<(u64, flaneur::scene::Mesh)> = all
        .objects
        .iter()
        .map(|o| (o.id, db.mesh(o).unwrap()))
        .collect();
    let rays = RayScene::new(meshes.iter().map(|(id, m)| (*id, m))).unwrap();
    let aspect = WIDTH as f32 / HEIGHT as f32;
    let tan_x = (fov_x_for(camera.fov_y, aspect) * 0.5).tan();
    let tan_y = (camera.fov_y * 0.5).tan();
    let (f, r, u) = (camera.forward(), camera.right(), camera.up());
    let (mut agree, mut sky, mut seen) = (0usize, 0usize, HashMap::new());
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let sx = (x as f32 + 0.5) / WIDTH as f32 * 2.0 - 1.0;
            let sy = 1.0 - (y as f32 + 0.5) / HEIGHT as f32 * 2.0;
            let dir = f + r * (sx * tan_x) + u * (sy * tan_y);
            let hit = rays
                .first_hit(camera.position.to_array(), dir.to_array())
                .unwrap()
                .and_then(|h| rays.object_id(h.object));
            let drawn = frame.objects[(y * WIDTH + x) as usize];
            if drawn == hit {
                agree += 1;
            }
            match hit {
                None => sky += 1,
                Some(id) => *seen.entry(id).or_insert(0usize) += 1,
            }
        }
    }
    let pixels = (WIDTH * HEIGHT) as usize;
    let share = agree as f64 / pixels as f64;
    assert!(
        share > 0.99,
        "the id target agrees with the rays on {:.2} % of pixels",
        100.0 * share
    );
    assert!(
        sky > pixels / 20 && sky < pixels * 19 / 20,
        "{sky} sky pixels"
    );
    assert!(seen.len() >= 10, "rays meet {} objects", seen.len());
    // Every object rays see on a dozen pixels or more is drawn on most of them.
    for (id, n) in seen.iter().filter(|(_, &n)| n >= 12) {
        let drawn = frame.objects.iter().filter(|o| **o == Some(*id)).count();
        assert!(
            drawn * 10 >= n * 9,
            "object {id}: {drawn} pixels drawn, {n} by rays"
        );
    }

    // The colour image against the stored reference (FLANEUR_BLESS=1 rewrites it).
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(REFERENCE);
    if std::env::var_os("FLANEUR_BLESS").is_some() {
        frame.save_png(&path).unwrap();
    }
    let reference = image::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (FLANEUR_BLESS=1 writes it)", path.display()))
        .to_rgba8();
    assert_eq!(reference.dimensions(), (WIDTH, HEIGHT));
    let (mut total, mut far_off) = (0u64, 0usize);
    for (a, b) in reference
        .as_raw()
        .chunks_exact(4)
        .zip(frame.rgba.chunks_exact(4))
    {
        let d: Vec<u32> = (0..3).map(|k| a[k].abs_diff(b[k]) as u32).collect();
        total += d.iter().sum::<u32>() as u64;
        if d.iter().any(|&c| c > 24) {
            far_off += 1;
        }
    }
    let mean = total as f64 / (3 * pixels) as f64;
    assert!(
        mean < 2.0,
        "mean difference from the reference {mean:.2} of 255"
    );
    assert!(
        far_off * 100 < pixels,
        "{far_off} pixels differ from the reference by more than 24"
    );
}

#[test]
fn bad_sizes_and_unknown_objects_are_errors() {
    let gpu = gpu();
    for (w, h) in [(0, 10), (10, 0), (u32::MAX, 4)] {
        let err = flaneur_render::Offscreen::new(&gpu, w, h).err().unwrap();
        assert!(err.to_string().contains("pixels"), "{err}");
    }
    let target = flaneur_render::Offscreen::new(&gpu, 8, 8).unwrap();
    let meshes = flaneur_render::GpuMeshes::default();
    let err = target
        .render(&gpu, glam::Mat4::IDENTITY, &meshes, &[(7, 0)])
        .unwrap_err();
    assert!(err.to_string().contains("object 7"), "{err}");
    // A mesh whose indices run past its vertices is refused, naming the object.
    let mut meshes = flaneur_render::GpuMeshes::default();
    let bad = flaneur::scene::Mesh {
        positions: vec![[0.0; 3]; 3],
        normals: vec![[0.0, 1.0, 0.0]; 3],
        indices: vec![0, 1, 5],
    };
    let err = meshes.upload(&gpu, (9, 0), &bad).unwrap_err();
    assert!(err.to_string().contains("object 9"), "{err}");
    assert!(meshes.is_empty() && meshes.bytes() == 0);
}

#[test]
fn meshes_come_and_go_and_their_bytes_are_counted() {
    let gpu = gpu();
    let mut meshes = flaneur_render::GpuMeshes::default();
    let quad = |z: f32| flaneur::scene::Mesh {
        positions: vec![
            [-1.0, -1.0, z],
            [1.0, -1.0, z],
            [1.0, 1.0, z],
            [-1.0, 1.0, z],
        ],
        normals: vec![[0.0, 0.0, 1.0]; 4],
        indices: vec![0, 1, 2, 0, 2, 3],
    };
    meshes.upload(&gpu, (1, 0), &quad(-5.0)).unwrap();
    meshes.upload(&gpu, (2, 0), &quad(-3.0)).unwrap();
    let one = meshes.get((1, 0)).unwrap().bytes;
    assert_eq!(meshes.bytes(), 2 * one);
    // Drawn: the nearer quad hides the farther one in the middle of the image.
    let target = flaneur_render::Offscreen::new(&gpu, 32, 32).unwrap();
    let view_proj = glam::camera::rh::proj::directx::perspective(1.0, 1.0, 0.5, 100.0);
    let frame = target
        .render(&gpu, view_proj, &meshes, &[(1, 0), (2, 0)])
        .unwrap();
    assert_eq!(frame.objects[16 * 32 + 16], Some(2));
    assert_eq!(frame.objects[0], None);
    assert!(meshes.evict((2, 0)) && !meshes.evict((2, 0)));
    assert_eq!(meshes.bytes(), one);
    let frame = target.render(&gpu, view_proj, &meshes, &[(1, 0)]).unwrap();
    assert_eq!(frame.objects[16 * 32 + 16], Some(1));
    // A freed slot is reused, and shows its new object.
    meshes.upload(&gpu, (3, 0), &quad(-4.0)).unwrap();
    let frame = target
        .render(&gpu, view_proj, &meshes, &[(1, 0), (3, 0)])
        .unwrap();
    assert_eq!(frame.objects[16 * 32 + 16], Some(3));
}

/// A sink that renders through a [`FrameWriter`] and checks, frame by frame, that the
/// GPU holds exactly what the object buffer holds of what has been drawn, and that the
/// frame drew every object the walk selected.
struct Checked<'a> {
    writer: FrameWriter<'a>,
    frames: usize,
}

impl FrameSink for Checked<'_> {
    fn frame(
        &mut self,
        index: usize,
        camera: &Camera,
        buffer: &ObjectBuffer,
        selection: &mut flaneur::walk::Selection<'_>,
    ) -> flaneur::Result<()> {
        self.writer.frame(index, camera, buffer, selection)?;
        let drawn = selection.culled;
        let gpu = self.writer.resident();
        assert!(
            drawn.iter().all(|o| gpu.get((o.entry.id, 0)).is_some()),
            "frame {index}"
        );
        assert!(
            gpu.keys().all(|(id, _)| buffer.contains(id)),
            "frame {index}: a freed object"
        );
        self.frames += 1;
        Ok(())
    }

    fn lod_tau(&self) -> Option<f32> {
        self.writer.lod_tau()
    }

    fn lod_settled(&self) -> bool {
        self.writer.lod_settled()
    }
}

#[test]
fn a_walk_is_drawn_as_it_selects_and_the_gpu_follows_its_buffer() {
    let dir = tempfile::tempdir().unwrap();
    let (db, _) = city(dir.path());
    let gpu = gpu();
    // A small object buffer, so objects are evicted along the way and freed on the GPU.
    let cfg = ReviewConfig {
        memory_budget: 2 << 20,
        prefetch_k: None,
        pace: None,
        ..ReviewConfig::preset(Preset::Box)
    };
    let path = motion::generate(&db.bounds(), Motion::Fast, 600, 30.0, 2).unwrap();
    let frames = dir.path().join("frames");
    let writer = FrameWriter::new(&gpu, (64, 64), (&db.bounds(), cfg.far), &frames, 200).unwrap();
    let mut sink = Checked { writer, frames: 0 };
    let report = review_walk_sink(&db, &path, &cfg, &mut sink).unwrap();
    assert_eq!(sink.frames, path.poses.len());
    let t = &sink.writer.times;
    assert_eq!((t.frames, t.written), (600, 3));
    assert_eq!(t.draw_ms.len(), 600);
    let csv = t.to_csv();
    assert_eq!(csv.lines().count(), 601);
    assert!(csv.starts_with("frame,select_ms,upload_ms,draw_ms,triangles,coarse_objects\n0,"));
    let drawn: u64 = report.frames.iter().map(|f| f.triangles_drawn).sum();
    assert_eq!(
        t.triangles.iter().sum::<u64>(),
        drawn,
        "the walk's triangles, drawn"
    );
    assert!(
        t.uploads > 0 && t.evictions > 0 && t.peak_gpu_bytes > 0,
        "{} uploads, {} frees, {} bytes",
        t.uploads,
        t.evictions,
        t.peak_gpu_bytes
    );
    for k in [0, 200, 400] {
        assert!(frames.join(format!("frame-{k:05}.png")).exists());
    }
    assert!(FrameWriter::new(&gpu, (64, 64), (&db.bounds(), 10.0), &frames, 0).is_err());
}

/// The GPU in steady state: a viewer standing still is drawn from what the first frame
/// uploaded, with no upload or free after it (at the levels LOD selection chose).
#[test]
fn a_viewer_standing_still_allocates_nothing_after_the_first_frame() {
    let dir = tempfile::tempdir().unwrap();
    let db = build(dir.path(), &BuildOptions::default());
    let gpu = gpu();
    let cfg = ReviewConfig {
        pace: None,
        ..ReviewConfig::preset(Preset::Optimal)
    };
    let walked = motion::generate(&db.bounds(), Motion::Normal, 30, 30.0, 2).unwrap();
    let standing = |frames: usize| flaneur::path::CameraPath {
        poses: (0..frames)
            .map(|i| flaneur::path::Pose {
                time: i as f64 / 30.0,
                ..walked.poses[15]
            })
            .collect(),
    };
    let counts = |frames: usize| {
        let mut writer = FrameWriter::drawing(&gpu, (64, 64), (&db.bounds(), cfg.far))
            .unwrap()
            .with_lod_tau(0.001)
            .unwrap();
        review_walk_sink(&db, &standing(frames), &cfg, &mut writer).unwrap();
        let t = writer.times;
        assert!(t.triangles.iter().all(|&n| n == t.triangles[0]));
        (
            t.uploads,
            t.evictions,
            t.peak_gpu_bytes,
            t.lod.unwrap().levels_read,
        )
    };
    let first = counts(1);
    assert!(first.0 > 0, "the first frame uploads");
    assert_eq!(counts(60), first, "uploads, frees, GPU bytes, levels read");
}

/// BOX draws what it loaded at full detail, and loads a whole cell before drawing: its
/// frames must be the full-detail reference's, pixel for pixel, whatever slots the two
/// renders gave the objects.
#[test]
fn fidelity_of_a_full_detail_walk_is_exact() {
    let dir = tempfile::tempdir().unwrap();
    let (db, _) = city(dir.path());
    let gpu = gpu();
    let cfg = ReviewConfig {
        pace: None,
        ..ReviewConfig::preset(Preset::Box)
    };
    let path = motion::generate(&db.bounds(), Motion::Turning, 60, 30.0, 4).unwrap();
    let r = fidelity(&db, &gpu, &path, cfg.clone(), "box", (96, None));
    assert_eq!(r.rows.len(), 60);
    assert!(r.rows.iter().any(|row| row.triangles > 0));
    for row in &r.rows {
        assert_eq!(
            row.triangles, row.reference_triangles,
            "frame {}",
            row.frame
        );
        assert!(row.psnr.is_infinite() && row.differ == 0.0, "{row:?}");
    }
    assert!(r.to_csv().lines().count() == 61 && r.markdown().contains("60 (100.0 %)"));
}

/// The test city with small viewcells' visibility and no LODs, built into `dir`.
fn with_visibility(dir: &std::path::Path) -> Database {
    build(dir, &common::with_visibility())
}

/// The PVS walk drawn: every frame rendered from the objects the client holds, and the
/// walk's own figures (transactions, misses, pages) the same as when nothing is drawn.
#[test]
fn a_pvs_walk_is_drawn_without_changing_what_it_measures() {
    let dir = tempfile::tempdir().unwrap();
    let db = with_visibility(dir.path());
    let path = flaneur::path::cell_walk(&db, 240, 0.5, 30.0, 1).unwrap();
    let rule = flaneur::walk::pvs::PvsPrefetch::Pbnp { border: 0.25 };
    let plain = pvs_walk_sink(&db, &path, rule, &mut NoSink).unwrap();
    let gpu = gpu();
    let frames = dir.path().join("frames");
    let mut writer =
        FrameWriter::new(&gpu, (48, 48), (&db.bounds(), 1000.0), &frames, 100).unwrap();
    let drawn = pvs_walk_sink(&db, &path, rule, &mut writer).unwrap();
    assert_eq!(
        drawn.frames, plain.frames,
        "drawing changed the walk's figures"
    );
    assert!(
        plain.cells_entered >= 2,
        "{} cells entered",
        plain.cells_entered
    );
    let t = &writer.times;
    assert_eq!((t.frames, t.written), (240, 3));
    assert!(t.uploads > 0 && t.triangles.iter().any(|&n| n > 0));
}

/// The PVS walk's fidelity: it draws its viewcell's PVS of what the client holds, a
/// subset of the objects in view, so never more triangles than the reference; it leaves
/// out hidden objects, and the pictures stay close (the precomputation misses little).
#[test]
fn fidelity_of_the_pvs_walk() {
    let dir = tempfile::tempdir().unwrap();
    let db = with_visibility(dir.path());
    let path = flaneur::path::cell_walk(&db, 120, 0.5, 30.0, 2).unwrap();
    let gpu = gpu();
    let rule = flaneur::walk::pvs::PvsPrefetch::Pbnp { border: 0.25 };
    let r = fidelity(&db, &gpu, &path, rule, "pvs", (96, None));
    assert_eq!(r.rows.len(), 120);
    for row in &r.rows {
        assert!(row.triangles <= row.reference_triangles, "{row:?}");
        if row.triangles == row.reference_triangles {
            assert!(row.psnr.is_infinite() && row.differ == 0.0, "{row:?}");
        }
    }
    // Hidden objects left out: fewer triangles than the reference, the same picture
    // nearly everywhere.
    let drawn: u64 = r.rows.iter().map(|row| row.triangles).sum();
    let reference: u64 = r.rows.iter().map(|row| row.reference_triangles).sum();
    assert!(drawn < reference, "{drawn} triangles against {reference}");
    let same = r.rows.iter().filter(|row| row.differ == 0.0).count();
    let mean_differ = r.mean_differ();
    assert!(
        same > 0 && mean_differ < 0.05,
        "{same} frames the same, {:.2} % of pixels differ",
        100.0 * mean_differ
    );
}

/// A sink that draws at the levels LOD selection chooses and checks each frame: every
/// object drawn is resident at the level chosen, and no object has two levels on the
/// GPU.
struct AtLevels<'a> {
    writer: FrameWriter<'a>,
    /// Per frame: the triangles of the objects drawn at full detail.
    full: Vec<u64>,
    /// The selective mesh of each object drawn refined, as last drawn.
    refined: HashMap<u64, flaneur::lod::CompactMesh>,
}

impl FrameSink for AtLevels<'_> {
    fn frame(
        &mut self,
        index: usize,
        camera: &Camera,
        buffer: &ObjectBuffer,
        selection: &mut flaneur::walk::Selection<'_>,
    ) -> flaneur::Result<()> {
        self.writer.draw(camera, buffer, selection)?;
        let (selected, mut refinements) = selection.parts();
        for d in selected {
            if d.level == flaneur::walk::lod_select::REFINED {
                let r = refinements.as_mut().and_then(|r| r.refined(d.id));
                self.refined.extend(r.map(|r| (d.id, r.mesh.clone())));
            }
        }
        let (selected, drawn) = (&selection.drawn, selection.culled);
        assert_eq!(selected.len(), drawn.len(), "frame {index}");
        let gpu = self.writer.resident();
        for (d, o) in selected.iter().zip(drawn) {
            assert_eq!(d.id, o.entry.id);
            assert!(gpu.get((d.id, d.level)).is_some(), "frame {index}");
            match d.level {
                0 => assert_eq!(d.triangles, o.mesh.triangle_count()),
                // Refined view by view: at most the full mesh.
                flaneur::walk::lod_select::REFINED => {
                    assert!(d.triangles <= o.mesh.triangle_count())
                }
                _ => assert!(d.triangles < o.mesh.triangle_count()),
            }
        }
        let mut ids: Vec<u64> = gpu.keys().map(|(id, _)| id).collect();
        let n = ids.len();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), n, "frame {index}: an object at two levels");
        self.full
            .push(drawn.iter().map(|o| o.mesh.triangle_count() as u64).sum());
        Ok(())
    }

    fn lod_tau(&self) -> Option<f32> {
        self.writer.lod_tau()
    }

    fn lod_settled(&self) -> bool {
        self.writer.lod_settled()
    }
}

/// Drawn with LOD selection, a walk's far objects come from the database's coarse
/// levels: fewer triangles than full detail, the same where nothing is coarse, and
/// pictures close to the full-detail reference.
#[test]
fn a_walk_drawn_at_its_levels_of_detail() {
    let dir = tempfile::tempdir().unwrap();
    let db = build(dir.path(), &BuildOptions::default());
    assert!(db.has_lods());
    let gpu = gpu();
    let cfg = ReviewConfig {
        pace: None,
        ..ReviewConfig::preset(Preset::Box)
    };
    let path = motion::generate(&db.bounds(), Motion::Normal, 120, 30.0, 5).unwrap();
    // A coarse threshold (5 % of the viewport), so that a small city has far objects.
    let tau = 0.05;
    let writer = FrameWriter::drawing(&gpu, (64, 64), (&db.bounds(), cfg.far))
        .unwrap()
        .with_lod_tau(tau)
        .unwrap();
    let mut sink = AtLevels {
        writer,
        full: Vec::new(),
        refined: HashMap::new(),
    };
    review_walk_sink(&db, &path, &cfg, &mut sink).unwrap();
    let t = &sink.writer.times;
    let lod = t.lod.unwrap();
    assert!(
        lod.coarse_draws > 0 && lod.levels_read > 0 && lod.pages > 0,
        "{lod:?}"
    );
    for (i, ((&drawn, &full), &coarse)) in t
        .triangles
        .iter()
        .zip(&sink.full)
        .zip(&t.coarse)
        .enumerate()
    {
        if coarse == 0 {
            assert_eq!(drawn, full, "frame {i}");
        } else {
            assert!(drawn < full, "frame {i}: {drawn} of {full}");
        }
    }
    // The same walk through the fidelity experiment: coarse, yet close to full detail.
    let r = fidelity(&db, &gpu, &path, cfg.clone(), "box", (64, Some(tau)));
    assert!(r.rows.iter().any(|row| row.coarse > 0));
    assert!(r
        .rows
        .iter()
        .all(|row| row.triangles <= row.reference_triangles));
    let mean_differ = r.mean_differ();
    assert!(
        mean_differ < 0.05,
        "{:.1} % of pixels differ",
        100.0 * mean_differ
    );
    assert!(r.markdown().contains("τ = 0.05"));
    assert!(FrameWriter::drawing(&gpu, (8, 8), (&db.bounds(), 10.0))
        .unwrap()
        .with_lod_tau(0.0)
        .is_err());
}

/// Under a GPU budget, meshes a frame does not draw make room for those it does; a frame
/// whose own meshes do not fit is drawn anyway and says so.
#[test]
fn the_gpu_budget_frees_what_a_frame_does_not_draw() {
    use flaneur::walk::lod_select::Drawn;
    use std::sync::Arc;
    let gpu = gpu();
    let quad = |id: u64| Drawn {
        id,
        bounds: flaneur::geom::Aabb::new([0.0; 3], [1.0; 3]).unwrap(),
        level: 0,
        triangles: 2,
        mesh: Arc::new(flaneur::scene::Mesh {
            positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
            normals: vec![[0.0, 0.0, 1.0]; 4],
            indices: vec![0, 1, 2, 0, 2, 3],
        }),
    };
    let one = flaneur_render::gpu_bytes(&quad(0).mesh);
    let mut meshes = flaneur_render::GpuMeshes::default();
    meshes.set_budget(Some(2 * one));
    let all = |_| true;
    let f = meshes.follow(&gpu, all, &[quad(1), quad(2)], None).unwrap();
    assert_eq!((f.uploads, f.freed, f.over_budget), (2, 0, false));
    let f = meshes.follow(&gpu, all, &[quad(3)], None).unwrap();
    assert_eq!((f.uploads, f.freed, f.over_budget), (1, 1, false));
    assert!(meshes.bytes() <= 2 * one && meshes.get((3, 0)).is_some());
    let f = meshes
        .follow(&gpu, all, &[quad(1), quad(2), quad(3)], None)
        .unwrap();
    assert!(f.over_budget);
    assert!((1..=3).all(|id| meshes.get((id, 0)).is_some()));
    // Without a budget nothing is freed but what the buffer dropped.
    meshes.set_budget(None);
    let f = meshes.follow(&gpu, |id| id != 2, &[quad(1)], None).unwrap();
    assert_eq!((f.freed, f.over_budget), (1, false));
}

/// Boxes drawn over a frame in their Fig. 6.3 colours: a culled box in front of the
/// camera shows green lines, the frustum white ones, and nothing else changes.
#[test]
fn boxes_are_drawn_in_their_colours() {
    use flaneur_render::boxes::{lines, Boxes, CULLED};
    let gpu = gpu();
    let target = flaneur_render::Offscreen::new(&gpu, 64, 64).unwrap();
    let meshes = flaneur_render::GpuMeshes::default();
    let camera = Camera::new(Vec3::ZERO, 0.0, 0.0).unwrap();
    let view_proj = camera.view_proj(1.0).unwrap();
    let held = [flaneur::geom::Aabb::new([8.0, -2.0, -2.0], [12.0, 2.0, 2.0]).unwrap()];
    let plain = target.render(&gpu, view_proj, &meshes, &[]).unwrap();
    let mut boxes = Boxes::new(&gpu, target.colour_format());
    let l = lines(&camera.frustum(), &[], &held);
    let drawn = target
        .render_then(&gpu, view_proj, &meshes, &[], |enc, view| {
            boxes.draw(&gpu, enc, view, view_proj, None, &l)
        })
        .unwrap();
    let green = |p: &[u8]| p[1] > 150 && p[0] < 120 && p[2] < 140;
    let changed: Vec<&[u8]> = drawn
        .rgba
        .chunks_exact(4)
        .zip(plain.rgba.chunks_exact(4))
        .filter(|(a, b)| a != b)
        .map(|(a, _)| a)
        .collect();
    // The box in green; the frustum's own edges (white) run along the image's border.
    let white = |p: &[u8]| p[..3].iter().all(|&c| c > 230);
    let greens = changed.iter().filter(|p| green(p)).count();
    assert!(greens > 20, "{greens} green pixels");
    assert!(
        changed.iter().all(|p| green(p) || white(p)),
        "{} pixels neither green nor white",
        changed.iter().filter(|p| !green(p) && !white(p)).count()
    );
    assert_eq!(CULLED[3], 1.0);
}

/// Objects the build stored a progressive mesh for are refined view by view as the
/// walk goes: drawn from the refiner's selective mesh, whose changed ranges reach the
/// GPU frame by frame, and the pictures stay close to full detail.
#[test]
fn large_objects_are_refined_view_by_view() {
    use flaneur::walk::lod_select::REFINED;
    let dir = tempfile::tempdir().unwrap();
    // Every building above 1,000 triangles gets its progressive mesh and DAG.
    let db = build(dir.path(), &common::with_landmarks());
    let gpu = gpu();
    let cfg = ReviewConfig {
        pace: None,
        ..ReviewConfig::preset(Preset::Box)
    };
    let path = motion::generate(&db.bounds(), Motion::Normal, 90, 30.0, 5).unwrap();
    // Each large object refined from its first frame, whatever the decoding threads'
    // speed, so that the walk is the same on a loaded machine.
    let writer = FrameWriter::drawing(&gpu, (64, 64), (&db.bounds(), cfg.far))
        .unwrap()
        .with_lod_tau(0.001)
        .unwrap()
        .settling_lods();
    let mut sink = AtLevels {
        writer,
        full: Vec::new(),
        refined: HashMap::new(),
    };
    review_walk_sink(&db, &path, &cfg, &mut sink).unwrap();
    let lod = sink.writer.times.lod.unwrap();
    assert!(lod.refined_draws > 0 && lod.refine_ops > 0, "{lod:?}");
    assert_eq!(lod.drawn_while_decoding, 0, "{lod:?}");
    let refined: Vec<_> = sink
        .writer
        .resident()
        .keys()
        .filter(|k| k.1 == REFINED)
        .collect();
    assert!(!refined.is_empty());
    // What the GPU holds of each is the refiner's selective mesh, after a walk of
    // incremental uploads.
    for key in &refined {
        let mesh = &sink.refined[&key.0];
        let (vertices, indices) = sink.writer.resident().read_back(&gpu, *key).unwrap();
        assert_eq!(indices, mesh.indices(), "object {}", key.0);
        for &i in &indices {
            let v = vertices[i as usize];
            assert_eq!(v.position, mesh.positions()[i as usize], "object {}", key.0);
            assert_eq!(v.normal, mesh.normals()[i as usize]);
        }
    }
    // The same walk against full detail.
    let r = fidelity(&db, &gpu, &path, cfg.clone(), "box", (64, Some(0.001)));
    let mean_differ = r.mean_differ();
    assert!(
        mean_differ < 0.05,
        "{:.1} % of pixels differ",
        100.0 * mean_differ
    );
}

/// VISUAL's fidelity: at η = 0 it draws each visible object in view at the level its
/// DoV deserves, so never more triangles than the reference; at a large η groups drawn
/// at their nodes' internal LODs appear, and the pictures stay close to full detail.
#[test]
fn fidelity_of_the_visual_walk() {
    let dir = tempfile::tempdir().unwrap();
    let db = build(
        dir.path(),
        &BuildOptions {
            hdov: Some(flaneur::hdov::HdovOptions::default()),
            ..common::with_visibility()
        },
    );
    let path = flaneur::path::cell_walk(&db, 60, 0.5, 30.0, 2).unwrap();
    let gpu = gpu();
    let at = |eta: f32| flaneur::walk::visual::VisualConfig {
        eta,
        pace: None,
        ..Default::default()
    };
    let exact = at(0.0);
    let r = fidelity(&db, &gpu, &path, exact.clone(), "visual", (96, None));
    assert_eq!(r.rows.len(), 60);
    assert!(r
        .rows
        .iter()
        .all(|row| row.triangles <= row.reference_triangles));
    assert!(r.mean_differ() < 0.05, "{:.3}", r.mean_differ());
    let coarse = at(0.05);
    let c = fidelity(&db, &gpu, &path, coarse.clone(), "visual", (96, None));
    assert_eq!(c.rows.len(), 60);
    assert!(c.mean_differ() < 0.2, "{:.3}", c.mean_differ());
}

/// The scene tree's fidelity: CONV draws every object in the frustum at full detail, so
/// its pictures are the reference's on every frame; VSC(0) draws the visible ones at
/// the level their DoV deserves, never more triangles, and PB(n) within its budget.
#[test]
fn fidelity_of_the_scene_tree_traversals() {
    use flaneur::walk::scene::SceneConfig;
    use flaneur::walk::scene::Traversal;
    let dir = tempfile::tempdir().unwrap();
    let db = with_visibility(dir.path());
    let path = flaneur::path::cell_walk(&db, 40, 0.5, 30.0, 2).unwrap();
    let gpu = gpu();
    let conv = SceneConfig::new(Traversal::Conv);
    let r = fidelity(&db, &gpu, &path, conv, "conv", (96, None));
    assert_eq!(r.rows.len(), 40);
    for row in &r.rows {
        assert_eq!(row.triangles, row.reference_triangles, "{row:?}");
        assert!(row.psnr.is_infinite() && row.differ == 0.0, "{row:?}");
    }
    let vsc = SceneConfig::new(Traversal::Vsc { eta: 0.0 });
    let v = fidelity(&db, &gpu, &path, vsc, "vsc", (96, None));
    assert!(v
        .rows
        .iter()
        .all(|row| row.triangles <= row.reference_triangles));
    let pb = SceneConfig::new(Traversal::Pb { budget: 5_000 });
    let p = fidelity(&db, &gpu, &path, pb, "pb", (96, None));
    assert!(
        p.rows.iter().all(|row| row.triangles <= 5_000),
        "{:?}",
        p.rows
    );
}

/// `walk --render --adapt-ahead`: the walk refines its landmarks off the frame's
/// thread and says what it drew refined; without --render the flag is refused.
#[test]
fn walk_adapts_ahead_when_drawn() {
    let dir = tempfile::tempdir().unwrap();
    build(dir.path(), &common::with_landmarks());
    let db = dir.path().join("c.flaneur");
    let out = common::drawn_walk(
        &db,
        &dir.path().join("frames"),
        &["--frames", "60", "--adapt-ahead"],
    );
    let text = common::succeeded(&out);
    let refined = common::number_before(&text, " draws refined view by view");
    assert!(refined > 0, "{text}");
    let out = common::flaneur(&["walk", db.to_str().unwrap(), "--quiet", "--adapt-ahead"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--adapt-ahead is for a walk drawn"));
}

/// Records each streamed mesh as the renderer takes it.
struct Recorded {
    inner: flaneur_stream::StreamedLandmarks,
    meshes: std::sync::Arc<std::sync::Mutex<HashMap<u64, flaneur::lod::CompactMesh>>>,
}

impl flaneur::walk::RemoteRefinements for Recorded {
    fn refines(&self, id: u64) -> bool {
        self.inner.refines(id)
    }

    fn frame(&mut self, camera: &Camera) -> flaneur::Result<()> {
        self.inner.frame(camera)
    }

    fn triangles(&self, id: u64) -> usize {
        self.inner.triangles(id)
    }

    fn refined(&mut self, id: u64) -> Option<flaneur::walk::lod_select::RefinedView<'_>> {
        let view = self.inner.refined(id)?;
        self.meshes.lock().unwrap().insert(id, view.mesh.clone());
        Some(view)
    }
}

/// A walk whose landmarks come from a stream server: the GPU ends holding, for each,
/// exactly the selective mesh the batches made, after a walk of incremental uploads of
/// the ranges they changed; the other objects are drawn as ever.
#[test]
fn landmarks_streamed_into_a_walk_reach_the_gpu_as_the_batches_made_them() {
    use flaneur::walk::lod_select::REFINED;
    let dir = tempfile::tempdir().unwrap();
    let db = build(dir.path(), &common::with_landmarks());
    let landmarks = flaneur_stream::Landmark::all_in(&db, 64).unwrap();
    assert!(!landmarks.is_empty());
    let server = flaneur_stream::StreamServer::bind(
        "127.0.0.1:0",
        landmarks,
        flaneur_stream::ServerConfig::default(),
    )
    .unwrap()
    .spawn()
    .unwrap();
    let hello = flaneur_stream::Hello {
        traversal: flaneur::lod::Traversal::Priority,
        fov: flaneur::geom::DEFAULT_FOV,
        budget: Some(flaneur::lod::THESIS_BUDGET as u32),
        out_of_view: true,
        back_face: true,
        scheme: flaneur_stream::Scheme::Dag,
    };
    let refinement = flaneur_stream::Refinement {
        tau: 0.001,
        n: 500,
        initial_span: 1,
        predictor: flaneur_stream::Predictor::Quadratic,
    };
    let client = flaneur_stream::PredictiveClient::connect(
        server.addr(),
        hello,
        refinement,
        std::time::Duration::from_secs(20),
    )
    .unwrap();
    let (inner, figures) = flaneur_stream::StreamedLandmarks::new(client);
    let meshes = std::sync::Arc::new(std::sync::Mutex::new(HashMap::new()));
    let recorded = Recorded {
        inner,
        meshes: meshes.clone(),
    };
    let gpu = gpu();
    let cfg = ReviewConfig {
        pace: None,
        ..ReviewConfig::preset(Preset::Box)
    };
    let path = motion::generate(&db.bounds(), Motion::Normal, 90, 30.0, 5).unwrap();
    let mut writer = FrameWriter::drawing(&gpu, (64, 64), (&db.bounds(), cfg.far))
        .unwrap()
        .with_lod_tau(0.001)
        .unwrap()
        .with_remote(Box::new(recorded));
    review_walk_sink(&db, &path, &cfg, &mut writer).unwrap();
    let lod = writer.times.lod.unwrap();
    assert!(lod.streamed_draws > 0, "{lod:?}");
    let f = figures.lock().unwrap().clone();
    assert_eq!(f.frames, 90);
    assert!(f.modified > 0 && f.bytes > 0, "{f:?}");
    let streamed: Vec<_> = writer
        .resident()
        .keys()
        .filter(|k| k.1 == REFINED)
        .collect();
    assert!(!streamed.is_empty());
    let meshes = meshes.lock().unwrap();
    for key in streamed {
        let mesh = &meshes[&key.0];
        assert!(mesh.triangle_count() > 0);
        let (vertices, indices) = writer.resident().read_back(&gpu, key).unwrap();
        assert_eq!(indices, mesh.indices(), "object {}", key.0);
        for &i in &indices {
            let v = vertices[i as usize];
            assert_eq!(v.position, mesh.positions()[i as usize], "object {}", key.0);
            assert_eq!(v.normal, mesh.normals()[i as usize]);
        }
    }
}

/// A headless shot where no Wayland session exists (no `XDG_RUNTIME_DIR`, no
/// `WAYLAND_DISPLAY`) prints nothing on stderr: Mesa's device-select layer would ask
/// Wayland for the default GPU and libwayland print "error: XDG_RUNTIME_DIR is invalid",
/// which reads as our failure.
#[test]
fn a_headless_shot_prints_no_windowing_noise() {
    let c = common::city(40, 3, &BuildOptions::default());
    let b = c.bounds();
    let at = format!("{},2,{}", b.center().x, b.center().z);
    let png = c.dir.path().join("shot.png");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_flaneur"))
        .args([
            "shot",
            c.db.to_str().unwrap(),
            "--at",
            &at,
            "--size",
            "64x48",
        ])
        .arg("-o")
        .arg(&png)
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("NODEVICE_SELECT")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.is_empty(), "stderr: {err}");
    assert!(png.exists());
}
