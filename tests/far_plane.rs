//! Nothing hangs in the air at the far end of the view. From 250 m up behind a small
//! town, looking down across it, a 300 m tower stands 1,045 m away: the box query
//! selects it (its top is within the 1 km eyesight), and a picture cut at the query's
//! far plane drew its top with sky under it, its foot and the ground there being past
//! the plane. A second tower, 760 m away, is wholly within. Whatever a picture draws
//! must hang together with the ground, not be parted from it by sky: in `flaneur
//! shot`'s picture (offscreen) and in the window's, read from the screen of an Xvfb
//! server the test starts. That screen is 1280 × 720, too small for the default
//! window, which must open fitted to it.

mod common;
#[path = "common/window.rs"]
mod window;

use flaneur::path::{CameraPath, Pose};
use flaneur::scene::{Mesh, ObjectKind, SceneObject};
use flaneur::walk::review::{Preset, ReviewConfig};
use flaneur::walk::{self, Frames, WalkConfig};
use flaneur::{BuildOptions, Database};
use flaneur_render::{ViewOptions, WalkMode, WalkWindow};
use glam::Vec3;

/// How high the eye is, and how far down it looks (radians).
const EYE_HEIGHT: f32 = 250.0;
const PITCH: f32 = -25.0 * std::f32::consts::PI / 180.0;

/// A box from `min` to `max`: four corners a face, each face its own normal.
fn cuboid(min: Vec3, max: Vec3) -> Mesh {
    let mut mesh = Mesh::default();
    for axis in 0..3 {
        for side in [-1.0f32, 1.0] {
            let mut normal = Vec3::ZERO;
            normal[axis] = side;
            // Two axes across the face, in the order that winds it counter-clockwise
            // from outside.
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let (u, v) = if side > 0.0 { (u, v) } else { (v, u) };
            let base = mesh.positions.len() as u32;
            for (a, b) in [(0, 0), (1, 0), (1, 1), (0, 1)] {
                let mut p = if side > 0.0 { max } else { min };
                p[u] = if a == 0 { min[u] } else { max[u] };
                p[v] = if b == 0 { min[v] } else { max[v] };
                mesh.positions.push(p.to_array());
                mesh.normals.push(normal.to_array());
            }
            mesh.indices
                .extend([0, 1, 2, 0, 2, 3].into_iter().map(|i| base + i));
        }
    }
    mesh
}

/// A town of 30 citygen buildings with the two towers beyond it, built into `dir`;
/// the database and the pose 250 m up behind the town, looking across it at the towers.
fn town(dir: &std::path::Path) -> (Database, Pose) {
    let config = citygen::CityConfig {
        objects: 30,
        seed: 5,
        landmarks: 0.0,
        ..Default::default()
    };
    let scene = dir.join("town.scene");
    let mut w = citygen::SceneWriter::create(&scene).unwrap();
    let mut bounds: Option<(Vec3, Vec3)> = None;
    for id in 0..config.objects {
        let o = citygen::object(&config, id).unwrap();
        let (lo, hi) = o.mesh.bounds();
        let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
        bounds = Some(bounds.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))));
        w.write(&o).unwrap();
    }
    let (lo, hi) = bounds.unwrap();
    // 250 m back from the town, so that it fills the lower part of the view.
    let eye = Vec3::new(lo.x - 250.0, EYE_HEIGHT, 0.5 * (lo.z + hi.z));
    // Looking along +x: the far tower straight ahead, the near one to the right.
    let towers = [
        (
            Vec3::new(1045.0, 0.0, -15.0),
            Vec3::new(1075.0, 300.0, 15.0),
        ),
        (Vec3::new(760.0, 0.0, 85.0), Vec3::new(790.0, 200.0, 115.0)),
    ];
    for (k, (a, b)) in towers.into_iter().enumerate() {
        let at = Vec3::new(eye.x, lo.y, eye.z);
        w.write(&SceneObject {
            id: config.objects + k as u64,
            kind: ObjectKind::Tower,
            mesh: cuboid(at + a, at + b),
        })
        .unwrap();
    }
    w.finish().unwrap();
    let db_path = dir.join("town.flaneur");
    let opts = BuildOptions {
        lod: None,
        ..Default::default()
    };
    flaneur::build_from_scene(&scene, &db_path, &opts).unwrap();
    let pose = Pose {
        time: 0.0,
        position: eye,
        yaw: 0.0,
        pitch: PITCH,
    };
    (Database::open(&db_path).unwrap(), pose)
}

/// The largest difference of a channel between two colours.
fn differ(a: [u8; 3], b: [u8; 3]) -> u8 {
    (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap()
}

/// Checks a `width` × `height` picture whose pixels `at` gives, looking down across the
/// town: its top row at the left is the sky (the ground there is past the eyesight);
/// everything drawn hangs together with the ground at the bottom of the picture, not
/// parted from it by sky; and the near tower is drawn (in the columns between
/// `near_tower`'s fractions of the width, in the upper fifth of the picture).
fn nothing_floats(
    what: &str,
    (width, height): (usize, usize),
    at: impl Fn(usize, usize) -> [u8; 3],
    near_tower: (f32, f32),
) {
    // Left of the towers (straight ahead and to the right).
    let sky = at(width / 10, 0);
    assert!(
        sky[2] > sky[0] + 20,
        "{what}: the top of the picture is not sky but {sky:?}"
    );
    let diff: Vec<u8> = (0..width * height)
        .map(|i| differ(at(i % width, i / width), sky))
        .collect();
    // What the ground at the bottom reaches without crossing the sky: anything not
    // quite the sky's colour, the faded ground far off included.
    let mut grounded = vec![false; width * height];
    let mut todo: Vec<usize> = ((height - 1) * width..height * width)
        .filter(|&i| diff[i] > 3)
        .collect();
    for &i in &todo {
        grounded[i] = true;
    }
    while let Some(i) = todo.pop() {
        let (x, y) = (i % width, i / width);
        let around = [
            (x > 0).then(|| i - 1),
            (x + 1 < width).then(|| i + 1),
            (y > 0).then(|| i - width),
            (y + 1 < height).then(|| i + width),
        ];
        for j in around.into_iter().flatten() {
            if !grounded[j] && diff[j] > 3 {
                grounded[j] = true;
                todo.push(j);
            }
        }
    }
    // Clearly drawn, yet cut off from the ground by sky: hanging in the air.
    let floating: Vec<(usize, usize)> = (0..width * height)
        .filter(|&i| diff[i] > 16 && !grounded[i])
        .map(|i| (i % width, i / width))
        .collect();
    assert!(
        floating.is_empty(),
        "{what}: {} pixels hang in the sky, cut off from the ground, e.g. (column, row) {:?}",
        floating.len(),
        &floating[..floating.len().min(8)]
    );
    let near_seen = (0..width * height / 5).any(|i| {
        let f = (i % width) as f32 / width as f32;
        f > near_tower.0 && f < near_tower.1 && diff[i] > 16
    });
    assert!(near_seen, "{what}: the near tower is not drawn");
}

#[test]
fn a_shot_draws_nothing_above_sky() {
    let dir = tempfile::tempdir().unwrap();
    let (db, pose) = town(dir.path());
    let db_path = dir.path().join("town.flaneur");
    let png = dir.path().join("shot.png");
    let p = pose.position;
    let out = common::flaneur(&[
        "shot",
        db_path.to_str().unwrap(),
        "--at",
        &format!("{},{},{}", p.x, p.y, p.z),
        "--look",
        &format!("0,{}", PITCH.to_degrees()),
        "--fov",
        "45",
        "--size",
        "240x160",
        "-o",
        png.to_str().unwrap(),
    ]);
    let said = common::succeeded(&out);
    // Both towers and some of the town were selected: 2 + the houses in view.
    assert!(common::number_before(&said, " objects") >= 3, "{said}");
    drop(db);
    let image = image::open(&png).unwrap().to_rgb8();
    let (w, h) = image.dimensions();
    nothing_floats(
        "flaneur shot",
        (w as usize, h as usize),
        |x, y| image.get_pixel(x as u32, y as u32).0,
        (0.55, 0.68),
    );
}

#[test]
fn the_window_fits_the_screen_and_draws_nothing_above_sky() {
    if std::env::var_os("DISPLAY").is_some() {
        eprintln!("skipped: a display of the session's own, whose pixels are not a file");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let Some(_display) = window::display_sized_in(dir.path(), (1280, 720)) else {
        eprintln!("skipped: no Xvfb to start");
        return;
    };
    let (db, pose) = town(dir.path());
    let poses = (0..12)
        .map(|k| Pose {
            time: k as f64 * 0.05,
            ..pose
        })
        .collect();
    // The default window: 1024 × 768, too tall for this screen.
    let opts = ViewOptions {
        play: Some(CameraPath::new(poses).unwrap()),
        lod_tau: None,
        ..ViewOptions::new(db.bounds(), pose)
    };
    let mut window = WalkWindow::open(opts, WalkMode::Box).unwrap();
    window.show_hud = false;
    let cfg = ReviewConfig {
        pace: None,
        ..ReviewConfig::preset(Preset::Box)
    };
    let screen = dir.path().join("Xvfb_screen0");
    let mut shot = None;
    let mut viewer = window::Ticking::new(&mut window, |frame| {
        if frame == 8 {
            shot = Some(window::Screen::read(&screen));
        }
    });
    walk::run(&db, &WalkConfig::Review(cfg), &mut viewer, Frames::Keep).unwrap();
    let shot = shot.expect("a frame 8");
    let (w, h) = window.drawn_size().expect("a window drawn");
    // The window sits at the screen's corner (no window manager); what of it is on
    // the screen is checked.
    let seen = ((w as usize).min(shot.width), (h as usize).min(shot.height));
    nothing_floats("the window", seen, |x, y| shot.at(x, y), (0.55, 0.68));
    assert!(
        w <= 1280 && h <= 720 * 9 / 10,
        "a {w} × {h} window on a 1280 × 720 screen: it leaves no room for a title bar"
    );
    assert!(
        h >= 600,
        "a {w} × {h} window: shrunk more than the screen asks"
    );
    let shape = w as f32 / h as f32;
    assert!(
        (shape - 4.0 / 3.0).abs() < 0.01,
        "a {w} × {h} window: the default 4:3 shape is not kept"
    );
}
