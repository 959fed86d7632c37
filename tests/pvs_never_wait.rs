//! The PVS walk that never waits on a read: the client on a loader thread, the viewer
//! drawing what has arrived; locally and over HTTP from nginx, through a server that
//! goes away, from the command line and in `bench pvs-http`.

mod common;
#[path = "common/http.rs"]
mod servers;

use std::time::Duration;

use flaneur::path::{cell_walk, CameraPath};
use flaneur::prefetch::pvs::DEFAULT_BORDER;
use flaneur::store::HttpOptions;
use flaneur::walk::pvs::{PvsPrefetch, PvsWalkConfig, PvsWalkReport};
use flaneur::walk::{self, Frames, Playback, WalkConfig};
use flaneur::{BuildOptions, Database};
use servers::Nginx;

const BORDER: f64 = DEFAULT_BORDER;

fn rules() -> [PvsPrefetch; 3] {
    [
        PvsPrefetch::Snp,
        PvsPrefetch::Pbnp { border: BORDER },
        PvsPrefetch::Lanp { border: BORDER },
    ]
}

/// Walks `path` over `db`'s visibility as `cfg` says (a [`PvsPrefetch`] alone: waiting,
/// as the thesis), its frames kept.
fn pvs_walk(
    db: &Database,
    path: &CameraPath,
    cfg: impl Into<PvsWalkConfig>,
) -> flaneur::Result<PvsWalkReport> {
    walk::run(
        db,
        &WalkConfig::Pvs(cfg.into()),
        &mut Playback::path(path),
        Frames::Keep,
    )?
    .try_into()
}

fn never_waiting(prefetch: PvsPrefetch) -> PvsWalkConfig {
    PvsWalkConfig {
        pace: Some(1.0),
        ..PvsWalkConfig::never_waiting(prefetch)
    }
}

/// What must hold of a never-wait walk of `path` against the waiting walk of the same
/// rule on the local file: the same frames in the same cells, nothing failed, and the
/// last frame complete, drawing its cell's whole PVS as the waiting walk does.
fn check_against_waiting(path: &CameraPath, r: &PvsWalkReport, waits: &PvsWalkReport) {
    assert!(r.never_wait && !waits.never_wait);
    assert_eq!(r.frames.len(), path.poses.len());
    let cells = |r: &PvsWalkReport| r.frames.iter().map(|f| f.cell).collect::<Vec<_>>();
    assert_eq!(cells(r), cells(waits), "{:?}", r.prefetch);
    assert_eq!(r.failed_loads, 0, "{:?}", r.last_load_error);
    let last = r.frames.last().unwrap();
    let count = waits.frames.last().unwrap().drawn;
    assert!(last.cell.is_some() && count > 0);
    assert_eq!(
        (last.visual_misses, last.drawn),
        (0, count),
        "{:?}",
        r.prefetch
    );
    assert!(r.first_complete_frame.is_some());
    assert!(r.visual_misses >= r.visual_misses_after_start);
    // The waiting walk's answers come in the frame that asks.
    assert_eq!(waits.round_trip_frames, 0);
    assert!(r.transactions >= 1 && r.objects_sent >= count);
}

#[test]
fn a_never_wait_pvs_walk_draws_what_arrives_and_ends_with_its_whole_pvs() {
    let c = common::city_with_lods_and_visibility(21);
    let db = Database::open(&c.db).unwrap();
    let path = common::walk_then_stand(&db);
    for prefetch in rules() {
        let waits = pvs_walk(&db, &path, prefetch).unwrap();
        let r = pvs_walk(&db, &path, never_waiting(prefetch)).unwrap();
        check_against_waiting(&path, &r, &waits);
        // The loader's reads are the walk's: every object's coarse level and mesh.
        assert!(r.pages > waits.pages, "{} against {}", r.pages, waits.pages);
    }
}

#[test]
fn a_never_wait_pvs_walk_over_http_ends_as_the_local_one() {
    let c = common::city_with_lods_and_visibility_raw(22);
    let server = Nginx::start(c.dir.path());
    let local = Database::open(&c.db).unwrap();
    let path = common::walk_then_stand(&local);
    for prefetch in rules() {
        let waits = pvs_walk(&local, &path, prefetch).unwrap();
        let db = Database::open_url(&server.url("city.flaneur")).unwrap();
        let r = pvs_walk(&db, &path, never_waiting(prefetch)).unwrap();
        check_against_waiting(&path, &r, &waits);
        assert!(db.remote_stats().unwrap().requests > 2);
    }
}

#[test]
fn a_never_wait_pvs_walk_goes_on_without_its_server_and_says_so() {
    let c = common::city_with_lods_and_visibility_raw(23);
    let mut server = Nginx::start(c.dir.path());
    let url = server.url("city.flaneur");
    let db = Database::open_url_with(&url, &servers::impatient()).unwrap();
    // The index and the visibility directory are read while the server is up; then it
    // goes, and no row or mesh can be.
    db.range(&db.bounds()).unwrap();
    db.visibility().unwrap();
    server.stop();
    let path = cell_walk(&db, 30, 1.0, 30.0, 3).unwrap();
    let cfg = PvsWalkConfig {
        pace: Some(4.0),
        ..PvsWalkConfig::never_waiting(PvsPrefetch::Lanp { border: BORDER })
    };
    let r = pvs_walk(&db, &path, cfg).expect("the walk stopped");
    assert_eq!(r.frames.len(), 30);
    assert!(r.failed_loads >= 1);
    let said = r.last_load_error.as_deref().unwrap();
    assert!(said.contains(&url), "{said}");
    assert!(r.first_complete_frame.is_none() && r.visual_misses > 0);
}

#[test]
fn a_bad_pace_is_refused_before_the_walk() {
    let c = common::city(40, 24, &common::with_visibility());
    let db = Database::open(&c.db).unwrap();
    let path = cell_walk(&db, 5, 1.0, 30.0, 3).unwrap();
    for pace in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        let cfg = PvsWalkConfig {
            pace: Some(pace),
            ..PvsWalkConfig::never_waiting(PvsPrefetch::Snp)
        };
        let e = pvs_walk(&db, &path, cfg).unwrap_err();
        assert!(e.to_string().contains("pace"), "{e}");
    }
}

#[test]
fn the_cli_walks_pvs_never_waiting_with_lanp_and_benches_it_over_http() {
    // Raw floats, so that the walks over HTTP have pages to ask for after the first
    // round trip: format version 2's file of this city comes whole with its two ends.
    let c = common::city(
        60,
        25,
        &BuildOptions {
            codec: flaneur::scene::MeshCodec::Raw,
            ..common::with_visibility()
        },
    );
    let db = c.db.to_str().unwrap();
    let out = common::flaneur(&[
        "walk",
        db,
        "--mode",
        "pvs",
        "--prefetch",
        "lanp",
        "--never-wait",
        "--frames",
        "60",
        "--speed",
        "8",
    ]);
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        said.contains("lanp prefetch") && said.contains("never waits"),
        "{said}"
    );
    let out = common::flaneur(&["walk", db, "--mode", "pvs", "--prefetch", "far"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("snp, pbnp, lanp"));

    let dir = c.dir.path().join("bench");
    let out = common::flaneur(&[
        "bench",
        "pvs-http",
        db,
        "--frames",
        "60",
        "--speed",
        "8",
        "--rtts",
        "0,40",
        "--rules",
        "pbnp,lanp",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in flaneur_bench::pvs_http::PLOTS
        .iter()
        .chain(&["pvs-http.csv", "pvs-http.md"])
    {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    let csv = common::Csv::read(&dir.join("pvs-http.csv"));
    let rows = &csv.rows;
    let kinds: Vec<(&str, &str)> = rows
        .iter()
        .map(|r| (csv.get(r, "rule"), csv.get(r, "source")))
        .collect();
    assert_eq!(
        kinds,
        [
            ("pbnp", "local-waiting"),
            ("pbnp", "local"),
            ("lanp", "local-waiting"),
            ("lanp", "local"),
            ("pbnp", "http"),
            ("lanp", "http"),
            ("pbnp", "http"),
            ("lanp", "http"),
        ]
    );
    for r in &rows[4..] {
        let n = |name: &str| csv.num(r, name);
        assert!(n("requests") > 0.0 && n("bytes") > 0.0, "{r:?}");
        assert_eq!(n("failed_loads"), 0.0);
    }
}

#[test]
fn a_transactions_rows_come_over_http_in_one_round_trip_not_one_each() {
    let c = common::city(
        300,
        26,
        &BuildOptions {
            page_size: 1024,
            ..common::with_visibility()
        },
    );
    let server = Nginx::start(c.dir.path());
    // A first round trip that brings the header and the R-tree's root, not the whole
    // visibility table with them (as the default's half megabyte of the file's end
    // would of a city this small).
    let opts = HttpOptions {
        prefix_bytes: 4 << 10,
        suffix_bytes: 4 << 10,
        ..HttpOptions::default()
    };
    let db = Database::open_url_with(&server.url("city.flaneur"), &opts).unwrap();
    let head = db.visibility().unwrap().unwrap();
    // Cells far apart in the file, so that no two records share a page, and from the
    // table's end: the head was read with the table's first pages, and any records in
    // them came along.
    let ids: Vec<u32> = head.cells.iter().rev().map(|c| c.id).step_by(16).collect();
    assert!(ids.len() >= 16, "{} cells", head.cells.len());
    let (one_by_one, together) = (&ids[..8], &ids[8..16]);
    let trips = |read: &dyn Fn()| {
        let before = db.remote_stats().unwrap();
        read();
        db.remote_stats().unwrap().since(&before).round_trips
    };
    let apart = trips(&|| {
        for &id in one_by_one {
            db.pvs(id).unwrap().unwrap();
        }
    });
    let announced = trips(&|| {
        db.announce_pvs(together).unwrap();
        for &id in together {
            db.pvs(id).unwrap().unwrap();
        }
    });
    assert_eq!(apart, 8);
    assert_eq!(announced, 1);
}

#[test]
fn a_file_swapped_under_a_never_wait_pvs_walk_stops_it_by_name() {
    let c = common::city_with_lods_and_visibility_raw(27);
    let other = common::city_with_lods_and_visibility_raw(28);
    let server = Nginx::start(c.dir.path());
    let db = Database::open_url(&server.url("city.flaneur")).unwrap();
    let path = common::walk_then_stand(&db);
    // Replace the served file with another city's, as a deploy would (a rename), newer.
    let staged = c.dir.path().join("staged");
    std::fs::copy(&other.db, &staged).unwrap();
    let later = std::time::SystemTime::now() + Duration::from_secs(60);
    std::fs::File::options()
        .write(true)
        .open(&staged)
        .unwrap()
        .set_modified(later)
        .unwrap();
    std::fs::rename(&staged, &c.db).unwrap();
    let cfg = never_waiting(PvsPrefetch::Lanp { border: BORDER });
    match pvs_walk(&db, &path, cfg) {
        Err(flaneur::Error::RemoteChanged { url, .. }) => assert!(url.ends_with("/city.flaneur")),
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("walked a city across a swap of its file"),
    }
}

#[test]
fn a_cold_info_of_a_city_with_lods_and_visibility_takes_two_round_trips() {
    let c = common::city_with_lods_and_visibility(29);
    let server = Nginx::start(c.dir.path());
    // The first round trip's two ends kept short, so that the LOD and visibility
    // tables' heads lie between them, as they do in a large city's file.
    let opts = HttpOptions {
        prefix_bytes: 4 << 10,
        suffix_bytes: 16 << 10,
        ..HttpOptions::default()
    };
    let db = Database::open_url_with(&server.url("city.flaneur"), &opts).unwrap();
    let local = Database::open(&c.db).unwrap();
    let bytes = db.store().page_count() * db.store().page_size() as u64;
    assert!(bytes > 64 << 10, "a city too small to test: {bytes} bytes");
    let info = db.info().unwrap();
    assert_eq!(format!("{info:?}"), format!("{:?}", local.info().unwrap()));
    assert!(info.lod.is_some() && info.visibility.is_some());
    let s = db.remote_stats().unwrap();
    assert_eq!(s.round_trips, 2, "{s:?}");
}
