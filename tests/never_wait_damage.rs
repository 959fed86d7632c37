//! A never-wait walk never hides what it could not load: a damaged LOD-chain page is
//! named (its page and its object) as the walk meets it, counted in the frame it is
//! learnt of and in the walk's summary, and the headless walk fails at its end, as the
//! waiting walk fails where it meets the page; REVIEW, BOX and PVS alike. A server that
//! lets the open through and then resets every connection is named too, and fails the
//! walk, however short the walk was.

mod common;
#[path = "common/http.rs"]
mod servers;

use std::os::unix::fs::FileExt;
use std::path::Path;

use common::recorder::Recorder;
use flaneur::geom::Aabb;
use flaneur::path::motion::{self, Motion};
use flaneur::path::{cell_poses, Pose};
use flaneur::store::PAGE_HEADER_LEN;
use flaneur::walk::review::{self, Preset, ReviewConfig};
use flaneur::walk::{self, Frames, WalkConfig};
use flaneur::Database;
use glam::Vec3;
use servers::{Fault, Misbehaving};

/// The object nearest a point 20 m ahead of `pose`'s eye: one the walk's first loads
/// bring, whatever the mode.
fn ahead_of(db: &Database, pose: &Pose) -> u64 {
    let camera = pose.camera().unwrap();
    let at = camera.position + camera.forward() * 20.0;
    let around = Aabb::new(
        (at - Vec3::splat(60.0)).into(),
        (at + Vec3::splat(60.0)).into(),
    )
    .unwrap();
    let distance = |b: &Aabb| (b.center() - at).length();
    db.range(&around)
        .unwrap()
        .objects
        .into_iter()
        .min_by(|a, b| distance(&a.bounds).total_cmp(&distance(&b.bounds)))
        .expect("an object near the path's start")
        .id
}

/// Damages the first page of object `id`'s LOD chain past its header, as
/// `tests/lod_store.rs` does; that page.
fn damage_chain(path: &Path, id: u64) -> u64 {
    let page_size = Database::open(path).unwrap().store().page_size();
    let page = common::lod_chain_page(path, id);
    let file = std::fs::OpenOptions::new().write(true).open(path).unwrap();
    file.write_all_at(
        &[0x77],
        page * page_size as u64 + PAGE_HEADER_LEN as u64 + 200,
    )
    .unwrap();
    page
}

/// `flaneur check` names the page, as it names any damaged page.
fn checked(db: &Path, page: u64, id: u64) {
    let out = common::flaneur(&["check", db.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(
        text.contains(&format!("page {page} (LOD chain of object {id})")),
        "{text}"
    );
}

/// The sum of column `name` of a walk's per-frame CSV.
fn column_sum(csv: &Path, name: &str) -> u64 {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    let at = lines
        .next()
        .unwrap()
        .split(',')
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name}"));
    lines
        .map(|l| l.split(',').nth(at).unwrap().parse::<u64>().unwrap())
        .sum()
}

/// A headless never-wait walk of the damaged city with `args`: it names the page and the
/// object, counts it in its summary and its CSV, and fails at its end.
fn fails_naming(db: &Path, args: &[&str], page: u64, id: u64) {
    let csv = db.with_extension(format!("{}.csv", args.join("_").replace('-', "")));
    let (db_arg, csv_arg) = (db.to_str().unwrap(), csv.to_str().unwrap());
    let mut all = vec!["walk", db_arg, "--never-wait", "--quiet", "--csv", csv_arg];
    all.extend_from_slice(args);
    let out = common::flaneur(&all);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert_eq!(out.status.code(), Some(1), "{args:?}: {stdout}{stderr}");
    assert!(
        stdout.contains("damaged: 1 objects could not be read whole"),
        "{args:?}: {stdout}"
    );
    let named = stdout
        .lines()
        .find(|l| l.trim_start().starts_with(&format!("object {id} ")))
        .unwrap_or_else(|| panic!("{args:?}: object {id} not named: {stdout}"));
    assert!(named.contains(&format!("page {page} ")), "{named}");
    assert!(
        stderr.contains("the walk met damage") && stderr.contains(&format!("page {page} ")),
        "{args:?}: {stderr}"
    );
    assert_eq!(column_sum(&csv, "damaged"), 1, "{args:?}");
}

#[test]
fn never_wait_walks_name_a_damaged_lod_page_and_fail_at_their_end() {
    // REVIEW and BOX from the first pose of the CLI's default path, a motion pattern.
    let c = common::city_with_lods_and_visibility_raw(41);
    let victim = {
        let db = Database::open(&c.db).unwrap();
        let path = motion::generate(&db.bounds(), Motion::Normal, 2, 30.0, 1).unwrap();
        ahead_of(&db, &path.poses[0])
    };
    let page = damage_chain(&c.db, victim);
    checked(&c.db, page, victim);
    fails_naming(&c.db, &["--mode", "review", "--frames", "60"], page, victim);
    fails_naming(&c.db, &["--config", "box", "--frames", "60"], page, victim);

    // PVS from the first pose of its default path, a walk through the viewcells.
    let c = common::city_with_lods_and_visibility_raw(42);
    let victim = {
        let db = Database::open(&c.db).unwrap();
        let first = cell_poses(&db, 2, 1.4 / 30.0, 30.0, 1)
            .unwrap()
            .next()
            .unwrap();
        ahead_of(&db, &first)
    };
    let page = damage_chain(&c.db, victim);
    fails_naming(&c.db, &["--mode", "pvs", "--frames", "60"], page, victim);
}

#[test]
fn a_never_wait_walk_tells_its_viewer_and_its_report_of_a_damaged_lod_page() {
    let c = common::city_with_lods_and_visibility_raw(43);
    let db = Database::open(&c.db).unwrap();
    let path = motion::generate(&db.bounds(), Motion::Normal, 60, 30.0, 1).unwrap();
    let victim = ahead_of(&db, &path.poses[0]);
    drop(db);
    let page = damage_chain(&c.db, victim);
    let db = Database::open(&c.db).unwrap();
    let cfg = ReviewConfig {
        never_wait: true,
        ..ReviewConfig::preset(Preset::Optimal)
    };
    let mut viewer = Recorder::new(path.poses.clone());
    let report: review::WalkReport =
        walk::run(&db, &WalkConfig::Review(cfg), &mut viewer, Frames::Keep)
            .expect("the walk went on")
            .try_into()
            .unwrap();
    // Named once, beside the frame that learnt of it (a window shows it there).
    let told: Vec<&String> = viewer.figures.iter().flat_map(|f| &f.damaged).collect();
    assert_eq!(told.len(), 1, "{told:?}");
    assert!(
        told[0].starts_with(&format!("object {victim} "))
            && told[0].contains(&format!("page {page} ")),
        "{told:?}"
    );
    assert_eq!(report.frames.iter().map(|f| f.damaged).sum::<usize>(), 1);
    // The report's summary, as JSON too.
    let json = serde_json::to_value(&report.summary).unwrap();
    let named = json["damaged"].as_array().unwrap();
    assert_eq!(named.len(), 1);
    assert_eq!(named[0].as_str().unwrap(), told[0]);
    // The object itself is drawn, at full detail: only its coarse level was lost.
    assert!(report.summary.failed_loads == 0, "{:?}", report.summary);
}

#[test]
fn a_never_wait_walk_whose_server_resets_after_the_open_names_it_and_fails() {
    let c = common::city_with_lods_and_visibility_raw(44);
    let bytes = std::fs::read(&c.db).unwrap();
    // PVS reads the viewcells before its walk, on the viewer's thread: those requests
    // too are answered, counted on an honest server.
    let before_cells = {
        let honest = Misbehaving::start(bytes.clone(), usize::MAX, Fault::Garble);
        let db = Database::open_url(&honest.url()).unwrap();
        db.visibility().unwrap();
        honest.requests.load(std::sync::atomic::Ordering::Relaxed)
    };
    // The open's requests are answered; every one after is reset.
    for mode in ["review", "box", "pvs"] {
        let honest = match mode {
            "review" | "box" => 2,
            _ => before_cells,
        };
        let server = Misbehaving::start(bytes.clone(), honest, Fault::Reset);
        let url = server.url();
        let out = common::flaneur(&[
            "walk",
            &url,
            "--mode",
            mode,
            "--never-wait",
            "--frames",
            "30",
            "--quiet",
        ]);
        let (stdout, stderr) = (
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr),
        );
        assert_eq!(out.status.code(), Some(1), "{mode}: {stdout}{stderr}");
        assert!(
            stdout
                .lines()
                .any(|l| l.contains(" failed ") && l.contains(&url)),
            "{mode}: {stdout}{stderr}"
        );
        assert!(
            stderr.contains("loads failed on the network") && stderr.contains(&url),
            "{mode}: {stderr}"
        );
    }
}
