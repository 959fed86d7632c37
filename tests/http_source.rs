//! A database read over HTTP by byte ranges answers exactly as the local file does, from
//! nginx on loopback; and every way a server can fail is named, never a panic and never
//! pages of two files mixed.

mod common;
#[path = "common/http.rs"]
mod servers;

use std::path::Path;
use std::time::{Duration, SystemTime};

use common::recorder::Recorder;
use flaneur::geom::Aabb;
use flaneur::path::motion::{self, Motion};
use flaneur::scene::MeshCodec;
use flaneur::store::HttpOptions;
use flaneur::walk::review::{self, Preset, ReviewConfig};
use flaneur::walk::{self, Frames, Playback, Viewer};
use flaneur::{BuildOptions, Database, Error};
use glam::Vec3;
use servers::{impatient, Fault, Misbehaving, Nginx, NginxConfig};

/// A small city built into its own folder, which nginx serves.
fn city(objects: u64, seed: u64) -> common::City {
    common::city(
        objects,
        seed,
        &BuildOptions {
            page_size: 1024,
            ..Default::default()
        },
    )
}

/// Walks `path` through `db` under `cfg`, drawing nothing, its frames kept.
fn review_walk(
    db: &Database,
    path: &flaneur::path::CameraPath,
    cfg: &ReviewConfig,
) -> flaneur::Result<review::WalkReport> {
    review_walk_at(db, cfg, &mut Playback::path(path))
}

/// Walks `db` under `cfg` with the poses `viewer` gives, its frames kept.
fn review_walk_at(
    db: &Database,
    cfg: &ReviewConfig,
    viewer: &mut dyn Viewer,
) -> flaneur::Result<review::WalkReport> {
    walk::run(db, &cfg.clone().into(), viewer, Frames::Keep)?.try_into()
}

fn boxes(db: &Database, n: usize) -> Vec<Aabb> {
    let b = db.bounds();
    let (min, ext) = (b.min, b.extent());
    (0..n)
        .map(|i| {
            let f = |k: usize| ((i * 7919 + k * 104_729) % 1000) as f32 / 1000.0;
            let lo = min + Vec3::new(f(1), 0.0, f(2)) * ext * 0.8;
            let size = Vec3::new(0.05 + 0.3 * f(3), 1.0, 0.05 + 0.3 * f(4)) * ext;
            Aabb::new(lo.to_array(), (lo + size).to_array()).unwrap()
        })
        .collect()
}

#[test]
fn queries_over_http_answer_as_the_local_file() {
    let c = city(400, 3);
    let server = Nginx::start(c.dir.path());
    let local = Database::open(&c.db).unwrap();
    let remote = Database::open_url(&server.url("city.flaneur")).unwrap();
    let opened = remote.remote_stats().unwrap();
    assert_eq!(
        (opened.requests, opened.round_trips),
        (2, 1),
        "a cold open is one round trip: the file's head and tail together"
    );
    assert_eq!(
        serde_json::to_value(local.info().unwrap()).unwrap(),
        serde_json::to_value(remote.info().unwrap()).unwrap()
    );
    let mut history = Vec::new();
    let queries = boxes(&local, 25);
    for q in &queries {
        let q = *q;
        let (a, b) = (local.range(&q).unwrap(), remote.range(&q).unwrap());
        assert_eq!(a.ids(), b.ids());
        assert_eq!(a.pages, b.pages, "the same pages, in the same order");
        let (a, b) = (
            local.csearch(&q, &history).unwrap(),
            remote.csearch(&q, &history).unwrap(),
        );
        assert_eq!((a.ids(), a.pages), (b.ids(), b.pages));
        for o in a.objects.iter().take(5) {
            assert_eq!(local.mesh(o).unwrap(), remote.mesh(o).unwrap());
        }
        history.push(q);
    }
    assert_eq!(
        local.io().page_reads,
        remote.io().page_reads,
        "pages counted alike"
    );
    let first = remote.remote_stats().unwrap();
    assert!(first.pages_fetched <= first.page_reads, "{first:?}");
    // The client cache holds the whole small city: the same queries again cost nothing.
    for (i, q) in queries.iter().enumerate() {
        remote.range(q).unwrap();
        let found = remote.csearch(q, &queries[..i]).unwrap();
        for o in found.objects.iter().take(5) {
            remote.mesh(o).unwrap();
        }
    }
    let again = remote.remote_stats().unwrap();
    assert_eq!(again.requests, first.requests, "{again:?}");
    assert!(again.page_reads > first.page_reads && again.hit_rate() > first.hit_rate());
}

#[test]
fn a_walk_over_http_reads_what_the_local_walk_reads() {
    let c = city(400, 4);
    let server = Nginx::start(c.dir.path());
    let local = Database::open(&c.db).unwrap();
    let remote = Database::open_url(&server.url("city.flaneur")).unwrap();
    let path = motion::generate(&local.bounds(), Motion::Normal, 120, 30.0, 2).unwrap();
    let cfg = ReviewConfig {
        far: 150.0,
        ..ReviewConfig::preset(Preset::Box)
    };
    let a = review_walk(&local, &path, &cfg).unwrap();
    let b = review_walk(&remote, &path, &cfg).unwrap();
    let figures = |r: &review::WalkReport| -> Vec<_> {
        r.frames
            .iter()
            .map(|f| {
                (
                    f.objects_loaded,
                    f.objects_buffered,
                    f.objects_drawn,
                    f.triangles_drawn,
                    f.index_pages,
                    f.mesh_pages,
                    f.visual_misses,
                )
            })
            .collect()
    };
    assert_eq!(figures(&a), figures(&b));
}

#[test]
fn each_frame_over_http_reports_the_client_cache() {
    let c = city(200, 5);
    let server = Nginx::start(c.dir.path());
    let local = Database::open(&c.db).unwrap();
    let remote = Database::open_url(&server.url("city.flaneur")).unwrap();
    let path = motion::generate(&local.bounds(), Motion::Normal, 60, 30.0, 2).unwrap();
    let cfg = ReviewConfig {
        pace: None,
        ..ReviewConfig::preset(Preset::Box)
    };
    let mut here = Recorder::new(path.poses.clone());
    review_walk_at(&local, &cfg, &mut here).unwrap();
    assert_eq!(here.figures.len(), 60);
    assert!(
        here.figures.iter().all(|f| f.remote.is_none()),
        "a local file has no network figures"
    );
    let mut there = Recorder::new(path.poses.clone());
    review_walk_at(&remote, &cfg, &mut there).unwrap();
    let seen: Vec<_> = there
        .figures
        .iter()
        .map(|f| f.remote.expect("figures over HTTP"))
        .collect();
    assert_eq!(seen.len(), 60);
    // Cumulative, and the last frame's are the reader's own.
    assert!(seen.windows(2).all(|w| w[1].page_reads >= w[0].page_reads));
    let last = seen[59];
    assert_eq!(Some(last), remote.remote_stats());
    assert!(
        last.page_reads > last.pages_fetched && last.pages_fetched > 0,
        "{last:?}"
    );
    assert!((0.0..1.0).contains(&last.hit_rate()));
}

#[test]
fn the_cli_takes_a_url_wherever_it_takes_a_database() {
    let c = city(200, 5);
    let server = Nginx::start(c.dir.path());
    let url = server.url("city.flaneur");
    let db = c.db.to_str().unwrap();
    let out = |args: &[&str]| {
        let o = common::flaneur(args);
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8(o.stdout).unwrap()
    };
    // The same lines but the database's name, the time and the network's own line.
    let same = |text: String| -> Vec<String> {
        text.lines()
            .filter(|l| !l.starts_with("database") && !l.starts_with("http") && !l.ends_with("µs"))
            .map(str::to_string)
            .collect()
    };
    let info = out(&["info", &url]);
    assert_eq!(same(out(&["info", db])), same(info.clone()));
    assert!(
        info.contains("http        "),
        "info reports the network: {info}"
    );
    let q = ["--box=-100,0,-100,100,30,100"];
    assert_eq!(
        same(out(&[&["query", db][..], &q].concat())),
        same(out(&[&["query", &url][..], &q].concat()))
    );
    let walk = out(&["walk", &url, "--mode", "box", "--frames", "30", "--quiet"]);
    assert!(
        walk.contains("http "),
        "the walk reports the network: {walk}"
    );
}

#[test]
fn a_server_without_range_support_is_named() {
    let c = city(60, 6);
    let server = Nginx::start_with(c.dir.path(), NginxConfig { no_ranges: true });
    match Database::open_url_with(&server.url("city.flaneur"), &impatient()) {
        Err(Error::Remote { url, what }) => {
            assert!(url.ends_with("/city.flaneur"));
            assert!(what.contains("does not serve byte ranges"), "{what}");
        }
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("opened a database from a server that ignores Range"),
    }
}

#[test]
fn a_missing_file_and_a_file_that_is_not_a_database_are_named() {
    let c = city(60, 7);
    std::fs::write(c.dir.path().join("notes.txt"), vec![b'x'; 5000]).unwrap();
    let server = Nginx::start(c.dir.path());
    match Database::open_url_with(&server.url("nothing.flaneur"), &impatient()) {
        Err(Error::Remote { what, .. }) => assert!(what.contains("404"), "{what}"),
        other => panic!("{:?}", other.err()),
    }
    assert!(matches!(
        Database::open_url_with(&server.url("notes.txt"), &impatient()),
        Err(Error::NotADatabase { .. })
    ));
}

/// Every object's mesh, read from `db`, or the first error.
fn all_meshes(db: &Database) -> Result<Vec<flaneur::scene::Mesh>, Error> {
    let all = db.range(&db.bounds())?;
    all.objects.iter().map(|o| db.mesh(o)).collect()
}

/// Replaces the file `c` serves with `other`'s, as a deploy would (a rename), newer.
fn swap_served(c: &common::City, other: &common::City) {
    let staged = c.dir.path().join("staged");
    std::fs::copy(&other.db, &staged).unwrap();
    let later = SystemTime::now() + Duration::from_secs(60);
    std::fs::File::options()
        .write(true)
        .open(&staged)
        .unwrap()
        .set_modified(later)
        .unwrap();
    std::fs::rename(&staged, &c.db).unwrap();
}

#[test]
fn a_file_swapped_mid_walk_is_refused_not_mixed() {
    let c = city(300, 8);
    let other = city(300, 9);
    let server = Nginx::start(c.dir.path());
    let db = Database::open_url_with(&server.url("city.flaneur"), &impatient()).unwrap();
    swap_served(&c, &other);
    match all_meshes(&db) {
        Err(Error::RemoteChanged { url, what }) => {
            assert!(url.ends_with("/city.flaneur"));
            assert!(what.contains("412"), "{what}");
        }
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("read a whole city across a swap of its file"),
    }
}

#[test]
fn a_server_gone_mid_walk_is_an_error_naming_the_pages() {
    let c = city(300, 10);
    let mut server = Nginx::start(c.dir.path());
    let url = server.url("city.flaneur");
    let db = Database::open_url_with(&url, &impatient()).unwrap();
    server.stop();
    match all_meshes(&db) {
        Err(Error::Remote { url: u, what }) => {
            assert_eq!(u, url);
            assert!(
                what.contains("page") && what.contains("3 attempts"),
                "{what}"
            );
        }
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("read a city from a stopped server"),
    }
    assert_eq!(db.remote_stats().unwrap().retries, 2);
}

/// The error reading every mesh from a misbehaving server that opens honestly.
fn misbehaved(fault: Fault) -> Error {
    let c = city(200, 11);
    let server = Misbehaving::start(std::fs::read(&c.db).unwrap(), 2, fault);
    let db = Database::open_url_with(&server.url(), &impatient()).unwrap();
    all_meshes(&db).expect_err("a misbehaving server's pages were all accepted")
}

#[test]
fn garbage_bytes_are_caught_by_the_page_checksums() {
    match misbehaved(Fault::Garble) {
        Error::CorruptPage { page, what, .. } => {
            assert!(page > 0);
            assert!(what.contains("checksum"), "{what}");
        }
        e => panic!("{e}"),
    }
}

#[test]
fn a_cut_body_is_retried_then_named() {
    match misbehaved(Fault::CutBody) {
        Error::Remote { what, .. } => assert!(what.contains("3 attempts"), "{what}"),
        e => panic!("{e}"),
    }
}

#[test]
fn a_long_or_short_answer_is_refused() {
    match misbehaved(Fault::LongBody) {
        Error::Remote { what, .. } => assert!(what.contains("more than"), "{what}"),
        e => panic!("{e}"),
    }
    match misbehaved(Fault::ShortRange) {
        Error::Remote { what, .. } => assert!(what.contains("the server sent"), "{what}"),
        e => panic!("{e}"),
    }
}

#[test]
fn server_errors_are_retried_and_client_errors_are_not() {
    match misbehaved(Fault::Status(503)) {
        Error::Remote { what, .. } => assert!(
            what.contains("3 attempts") && what.contains("503"),
            "{what}"
        ),
        e => panic!("{e}"),
    }
    match misbehaved(Fault::Status(403)) {
        Error::Remote { what, .. } => {
            assert!(what.contains("403") && !what.contains("attempts"), "{what}")
        }
        e => panic!("{e}"),
    }
    match misbehaved(Fault::Status(416)) {
        Error::RemoteChanged { what, .. } => assert!(what.contains("416"), "{what}"),
        e => panic!("{e}"),
    }
}

#[test]
fn a_local_path_is_not_taken_for_a_url() {
    let c = city(60, 12);
    let path: &Path = &c.db;
    let db = Database::open_location(
        path.to_str().unwrap(),
        Default::default(),
        &HttpOptions::default(),
    )
    .unwrap();
    assert!(db.remote_stats().is_none());
}

#[test]
fn a_cold_first_query_waits_for_two_round_trips_not_one_per_level() {
    // A tree of three levels whose leaves lie beyond the first round trip's tail.
    let c = city(2500, 13);
    let server = Nginx::start(c.dir.path());
    let local = Database::open(&c.db).unwrap();
    assert_eq!(local.tree().height, 3);
    let opts = HttpOptions {
        suffix_bytes: 8 << 10,
        ..HttpOptions::default()
    };
    let b = local.bounds();
    let mid = b.min + b.extent() * 0.5;
    let q = Aabb::new(
        (mid - Vec3::new(150.0, 0.0, 150.0)).to_array(),
        (mid + Vec3::new(150.0, 50.0, 150.0)).to_array(),
    )
    .unwrap();
    let remote = Database::open_url_with(&server.url("city.flaneur"), &opts).unwrap();
    let found = remote.range(&q).unwrap();
    assert_eq!(found, local.range(&q).unwrap());
    let leaves = found.pages.len() - 1 - 2;
    assert!(leaves > 4, "the query reads {} nodes", found.pages.len());
    let s = remote.remote_stats().unwrap();
    assert_eq!(s.round_trips, 2, "{s:?}");
    // Without the look-ahead each leaf would have cost one.
    assert!(s.requests < 2 + leaves as u64, "{s:?}");
}

/// `flaneur serve` on a free port over `dbs`; the process and the URL of each.
fn flaneur_serve(dbs: &[&Path]) -> (std::process::Child, Vec<String>) {
    use std::io::BufRead;
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_flaneur"))
        .arg("serve")
        .args(dbs)
        .args(["--port", "0"])
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = std::io::BufReader::new(child.stdout.take().unwrap()).lines();
    let urls = lines
        .by_ref()
        .map(|line| line.unwrap())
        .filter_map(|line| {
            let url = line.strip_prefix("serving ")?;
            Some(url.split_whitespace().next().unwrap().to_string())
        })
        .take(dbs.len())
        .collect();
    // Keep reading what the server prints, so it never writes into a closed pipe.
    std::thread::spawn(move || lines.for_each(drop));
    (child, urls)
}

#[test]
fn flaneur_serve_answers_as_nginx_does() {
    let c = city(300, 14);
    let (mut server, urls) = flaneur_serve(&[&c.db]);
    let local = Database::open(&c.db).unwrap();
    let remote = Database::open_url_with(&urls[0], &impatient()).unwrap();
    for q in boxes(&local, 10) {
        let (a, b) = (local.range(&q).unwrap(), remote.range(&q).unwrap());
        assert_eq!((a.ids(), &a.pages), (b.ids(), &b.pages));
        for o in a.objects.iter().take(3) {
            assert_eq!(local.mesh(o).unwrap(), remote.mesh(o).unwrap());
        }
    }
    // A new build copied over the served file: its ETag changes, If-Match fails.
    let other = city(300, 15);
    let staged = c.dir.path().join("staged");
    std::fs::copy(&other.db, &staged).unwrap();
    std::fs::rename(&staged, &c.db).unwrap();
    let changed = all_meshes(&remote);
    let _ = server.kill();
    let _ = server.wait();
    match changed {
        Err(Error::RemoteChanged { .. }) => {}
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("read a whole city across a swap of its file"),
    }
}

#[test]
fn flaneur_serve_refuses_a_file_that_is_not_a_database() {
    let dir = tempfile::tempdir().unwrap();
    let junk = dir.path().join("junk.flaneur");
    std::fs::write(&junk, b"not a city").unwrap();
    let out = common::flaneur(&["serve", junk.to_str().unwrap(), "--port", "0"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("junk.flaneur"), "{err}");
}

#[test]
fn a_never_wait_walk_goes_on_without_its_server_and_says_so() {
    let c = city(300, 16);
    let mut server = Nginx::start(c.dir.path());
    let url = server.url("city.flaneur");
    let db = Database::open_url_with(&url, &impatient()).unwrap();
    // The whole index is read while the server is up; then it goes, and no mesh can be.
    db.range(&db.bounds()).unwrap();
    server.stop();
    let path = motion::generate(&db.bounds(), Motion::Normal, 60, 30.0, 2).unwrap();
    let cfg = ReviewConfig {
        far: 150.0,
        pace: Some(8.0),
        never_wait: true,
        ..ReviewConfig::preset(Preset::Optimal)
    };
    let report = review_walk(&db, &path, &cfg).expect("the walk stopped");
    let s = &report.summary;
    assert_eq!(report.frames.len(), 60);
    assert!(s.failed_loads >= 1, "{s:?}");
    let said = s.last_load_error.as_deref().unwrap();
    assert!(said.contains(&url) && said.contains("3 attempts"), "{said}");
    assert!(s.visual_misses > 0 && s.first_complete_frame.is_none());
    // The thesis's walk, which waits on its reads, stops with the error instead.
    let waits = ReviewConfig {
        never_wait: false,
        ..cfg
    };
    match review_walk(&db, &path, &waits) {
        Err(Error::Remote { url: u, .. }) => assert_eq!(u, url),
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("a walk read meshes from a stopped server"),
    }
}

#[test]
fn bench_http_walks_through_a_link_of_set_round_trip() {
    let c = city(300, 17);
    let dir = c.dir.path().join("bench");
    let out = common::flaneur(&[
        "bench",
        "http",
        c.db.to_str().unwrap(),
        "--frames",
        "90",
        "--fps",
        "60",
        "--far",
        "150",
        "--speed",
        "8",
        "--patterns",
        "normal",
        "--rtts",
        "0,40",
        "--mbits",
        "100",
        "--policy",
        "path",
        "--index-cache-kb",
        "8",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in flaneur_bench::http_walk::PLOTS
        .iter()
        .chain(&["http.csv", "http.md"])
    {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    let csv = common::Csv::read(&dir.join("http.csv"));
    let rows = &csv.rows;
    let kinds: Vec<&str> = rows.iter().map(|r| csv.get(r, "source")).collect();
    assert_eq!(kinds, ["local", "local-waiting", "http", "http"]);
    let num = |r: &[String], name: &str| csv.num(r, name);
    for r in &rows[2..] {
        // Never a search on the viewer's thread; every walk asked the server for pages.
        assert_eq!(num(r, "sync_queries"), 0.0);
        assert!(num(r, "requests") > 0.0 && num(r, "bytes") > 0.0, "{r:?}");
        assert_eq!(num(r, "failed_loads"), 0.0);
    }
    for r in rows {
        // The index cache asked for: 8 pages of 1 KiB under the path policy.
        let hit_rate = num(r, "index_hit_rate");
        assert!((0.0..=1.0).contains(&hit_rate), "{r:?}");
    }
    let md = std::fs::read_to_string(dir.join("http.md")).unwrap();
    assert!(md.contains("index cache path, 8 KiB"), "{md}");
    // Opening over the 40 ms link took its first round trip at least.
    assert!(num(&rows[3], "open_ms") >= 40.0, "{:?}", rows[3]);
    assert!(num(&rows[2], "open_ms") < num(&rows[3], "open_ms"));
}

#[test]
fn coarse_levels_over_http_come_in_a_few_round_trips() {
    let c = city(300, 18);
    let server = Nginx::start(c.dir.path());
    let local = Database::open(&c.db).unwrap();
    let remote = Database::open_url(&server.url("city.flaneur")).unwrap();
    let objects = local.range(&local.bounds()).unwrap().objects;
    remote.range(&remote.bounds()).unwrap();
    let before = remote.remote_stats().unwrap();
    let coarse = remote.coarsest_meshes(&objects).unwrap();
    assert_eq!(local.coarsest_meshes(&objects).unwrap(), coarse);
    assert!(coarse.iter().any(|(level, _)| *level > 0));
    // The chains' heads (directory and coarsest level) asked for whole, and a build
    // batch's heads side by side in the file: a few runs of pages, not a request per
    // object, and a round trip or two, not a few per object as reading them one by one
    // takes.
    let spent = remote.remote_stats().unwrap().since(&before);
    let rt = spent.round_trips;
    assert!(
        spent.requests * 10 < objects.len() as u64,
        "{} requests for the coarsest levels of {} objects",
        spent.requests,
        objects.len()
    );
    let one_by_one = Database::open_url(&server.url("city.flaneur")).unwrap();
    one_by_one.range(&one_by_one.bounds()).unwrap();
    let before = one_by_one.remote_stats().unwrap();
    for o in &objects {
        let levels = one_by_one.lod_levels(o.id).unwrap().unwrap();
        one_by_one.lod_mesh(o.id, levels.len() - 1).unwrap();
    }
    let slow = one_by_one.remote_stats().unwrap().round_trips - before.round_trips;
    assert!(
        rt * 5 < slow,
        "{rt} round trips together, {slow} one by one"
    );
    println!("{rt} round trips together, {slow} one by one");
}

#[test]
fn a_second_visit_reads_the_pages_from_the_cache_folder() {
    let c = city(300, 19);
    let server = Nginx::start(c.dir.path());
    let url = server.url("city.flaneur");
    let folder = tempfile::tempdir().unwrap();
    let opts = HttpOptions {
        cache_dir: Some(folder.path().to_path_buf()),
        ..HttpOptions::default()
    };
    let local = Database::open(&c.db).unwrap();
    let want = all_meshes(&local).unwrap();
    let first = Database::open_url_with(&url, &opts).unwrap();
    assert_eq!(all_meshes(&first).unwrap(), want);
    let cold = first.remote_stats().unwrap();
    drop(first);
    // Only the open's first round trip (which pins the version) goes to the server.
    let second = Database::open_url_with(&url, &opts).unwrap();
    assert_eq!(all_meshes(&second).unwrap(), want);
    let warm = second.remote_stats().unwrap();
    assert!(cold.requests > 2, "{cold:?}");
    assert_eq!((warm.requests, warm.round_trips), (2, 1), "{warm:?}");
    assert_eq!(warm.pages_fetched, 0);
    // A new build of the file is another version: its pages are fetched, never mixed.
    let other = city(300, 20);
    let staged = c.dir.path().join("staged");
    std::fs::copy(&other.db, &staged).unwrap();
    std::fs::rename(&staged, &c.db).unwrap();
    let third = Database::open_url_with(&url, &opts).unwrap();
    let new_local = Database::open(&other.db).unwrap();
    assert_eq!(all_meshes(&third).unwrap(), all_meshes(&new_local).unwrap());
    assert!(third.remote_stats().unwrap().pages_fetched > 0);
    // A cache folder that cannot be made is named.
    let blocked = HttpOptions {
        cache_dir: Some(c.db.join("not-a-folder")),
        ..HttpOptions::default()
    };
    let err = Database::open_url_with(&url, &blocked).err().unwrap();
    assert!(err.to_string().contains("cache folder"), "{err}");
}

#[test]
fn a_crowd_of_walkers_reads_one_nginx_without_errors() {
    use flaneur_bench::crowd::{self, CrowdConfig};
    use flaneur_bench::walk_setup::WalkSetup;
    let c = city(300, 19);
    let server = flaneur_bench::nginx::Nginx::start(c.dir.path(), NginxConfig::default()).unwrap();
    let cfg = CrowdConfig {
        walk: WalkSetup {
            frames: 60,
            fps: 60.0,
            far: 150.0,
            pace: Some(8.0),
            patterns: vec![Motion::Normal, Motion::Fast],
            ..WalkSetup::default()
        },
        walkers: 4,
        cache_bytes: 16 << 20,
    };
    let r = crowd::run(&server.url("city.flaneur"), "nginx", &cfg, || {
        server.cpu_seconds()
    })
    .unwrap();
    assert_eq!(r.rows.len(), 4);
    assert_eq!(
        r.errors(),
        0,
        "{:?}",
        r.rows.iter().map(|w| &w.error).collect::<Vec<_>>()
    );
    for (i, w) in r.rows.iter().enumerate() {
        assert_eq!((w.walker, w.frames), (i, 60));
        assert_eq!(w.pattern, [Motion::Normal, Motion::Fast][i % 2]);
        assert_eq!(w.seed, 1 + i as u64);
        assert!(w.requests > 0 && w.bytes > 0, "{w:?}");
        assert!(w.p50_ms > 0.0 && w.p50_ms <= w.p99_ms, "{w:?}");
    }
    // Every request of every walker is in the merged times, and nothing else.
    assert_eq!(r.requests, r.rows.iter().map(|w| w.requests).sum::<u64>());
    assert!(r.p50_ms <= r.p99_ms && r.p99_ms <= r.max_ms);
    let cpu = r.server_cpu_s.expect("nginx's CPU time is known");
    assert!(cpu > 0.0 && cpu < r.wall_s * 2.0, "{cpu} s of {}", r.wall_s);
    assert!(r.client_cpu_s > 0.0);
    // A URL nothing serves is one clear error, before any walker starts.
    let gone = crowd::run("http://127.0.0.1:9/none.flaneur", "nobody", &cfg, || None);
    assert!(
        matches!(gone, Err(Error::Remote { .. })),
        "{:?}",
        gone.err()
    );
}

#[test]
fn bench_crowd_serves_the_file_with_nginx_and_writes_its_report() {
    let c = city(150, 21);
    let dir = c.dir.path().join("bench");
    let db = c.db.to_str().unwrap();
    let out = common::flaneur(&[
        "bench",
        "crowd",
        db,
        "--walkers",
        "3",
        "--frames",
        "30",
        "--fps",
        "60",
        "--far",
        "150",
        "--speed",
        "8",
        "--patterns",
        "normal,fast",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("crowd.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 3, "{csv}");
    let md = std::fs::read_to_string(dir.join("crowd.md")).unwrap();
    assert!(
        md.contains("| errors (walkers stopped + loads failed) | 0 |"),
        "{md}"
    );
    assert!(md.contains("one nginx"), "{md}");
    let none = common::flaneur(&["bench", "crowd", db, "--walkers", "0"]);
    assert!(!none.status.success());
    assert!(String::from_utf8_lossy(&none.stderr).contains("walkers"));
}

/// A person at a window: walks a path, and would rather walk on past what cannot be read
/// than stop (`Viewer::skips_damaged`); keeps what it was told was left out.
struct AtAWindow<'p> {
    path: &'p flaneur::path::CameraPath,
    damaged: Vec<String>,
}

impl flaneur::walk::FrameSink for AtAWindow<'_> {
    fn frame(
        &mut self,
        _: usize,
        _: &flaneur::geom::Camera,
        _: &flaneur::walk::ObjectBuffer,
        _: &mut flaneur::walk::Selection<'_>,
    ) -> flaneur::Result<()> {
        Ok(())
    }
}

impl flaneur::walk::Viewer for AtAWindow<'_> {
    fn next_pose(&mut self, frame: usize) -> flaneur::Result<Option<flaneur::path::Pose>> {
        Ok(self.path.poses.get(frame).copied())
    }

    fn figures(&mut self, figures: &flaneur::walk::FrameFigures) {
        self.damaged.extend(figures.damaged.iter().cloned());
    }

    fn skips_damaged(&self) -> bool {
        true
    }
}

#[test]
fn a_never_wait_walk_asks_again_for_what_an_outage_kept_from_it() {
    // Full meshes only, so that the outage falls on the loader's reads of meshes; raw
    // floats, so that the file is larger than the first round trip's two ends (format
    // version 2's is not, and the outage would find nothing left to read).
    let c = common::city(
        300,
        17,
        &BuildOptions {
            page_size: 1024,
            lod: None,
            codec: MeshCodec::Raw,
            ..Default::default()
        },
    );
    let bytes = std::fs::read(&c.db).unwrap();
    let open = |url: &str| {
        let db = Database::open_url_with(url, &impatient()).unwrap();
        db.range(&db.bounds()).unwrap();
        db
    };
    // The requests that open the database and read its whole index, counted on an
    // honest server: the outage starts at the walk's first.
    let before_walk = {
        let honest = Misbehaving::start(bytes.clone(), usize::MAX, Fault::Garble);
        open(&honest.url());
        honest.requests.load(std::sync::atomic::Ordering::Relaxed)
    };
    let server = Misbehaving::start(bytes, before_walk, Fault::Outage(60));
    let db = open(&server.url());
    let mut path = motion::generate(&db.bounds(), Motion::Normal, 60, 30.0, 2).unwrap();
    // Then the viewer stands, long enough for what it lacks to come.
    let last = *path.poses.last().unwrap();
    path.poses.extend((1..=120).map(|i| flaneur::path::Pose {
        time: last.time + f64::from(i) / 30.0,
        ..last
    }));
    let cfg = ReviewConfig {
        far: 150.0,
        pace: Some(2.0),
        never_wait: true,
        ..ReviewConfig::preset(Preset::Optimal)
    };
    let mut viewer = AtAWindow {
        path: &path,
        damaged: Vec::new(),
    };
    let report = review_walk_at(&db, &cfg, &mut viewer).expect("the walk stopped");
    let s = &report.summary;
    assert!(s.failed_loads >= 1, "the outage missed the walk: {s:?}");
    let said = s.last_load_error.as_deref().unwrap();
    assert!(said.contains(&server.url()), "{said}");
    // Nothing was taken for damage, and the standing viewer ends with all it sees.
    assert!(viewer.damaged.is_empty(), "{:?}", viewer.damaged);
    assert_eq!(report.frames.last().unwrap().visual_misses, 0, "{s:?}");
}

#[test]
fn a_file_swapped_under_a_walk_at_a_window_stops_it_though_damage_would_not() {
    // Raw floats, so that the walk still has pages to read after the swap: format
    // version 2's file of this city comes whole with the first round trip's two ends.
    let full_meshes = BuildOptions {
        page_size: 1024,
        lod: None,
        codec: MeshCodec::Raw,
        ..Default::default()
    };
    let c = common::city(300, 18, &full_meshes);
    let other = common::city(300, 19, &full_meshes);
    let server = Nginx::start(c.dir.path());
    let db = Database::open_url_with(&server.url("city.flaneur"), &impatient()).unwrap();
    // The index is read before the swap, so that the walk meets it reading meshes.
    db.range(&db.bounds()).unwrap();
    swap_served(&c, &other);
    let path = motion::generate(&db.bounds(), Motion::Normal, 60, 30.0, 2).unwrap();
    let cfg = ReviewConfig {
        far: 150.0,
        pace: Some(8.0),
        never_wait: true,
        ..ReviewConfig::preset(Preset::Optimal)
    };
    let mut viewer = AtAWindow {
        path: &path,
        damaged: Vec::new(),
    };
    match review_walk_at(&db, &cfg, &mut viewer) {
        Err(Error::RemoteChanged { url, .. }) => assert!(url.ends_with("/city.flaneur")),
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("walked on across a swap of its file: {:?}", viewer.damaged),
    }
}

#[test]
fn a_server_naming_no_version_is_warned_of_once() {
    let c = city(60, 16);
    let server = Misbehaving::start(std::fs::read(&c.db).unwrap(), 0, Fault::NoValidators);
    let url = server.url();
    let db = Database::open_url_with(&url, &impatient()).unwrap();
    let warnings = db.remote_warnings();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].contains(&url) && warnings[0].contains("ETag"),
        "{warnings:?}"
    );
    // The command line says it once, on standard error.
    let out = common::flaneur(&["info", &url]);
    let stdout = common::succeeded(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.matches("warning:").count(), 1, "{stderr}");
    assert!(
        stderr.contains(&url) && stderr.contains("Last-Modified"),
        "{stderr}"
    );
    assert!(!stdout.contains("warning"), "{stdout}");
    // A well-kept server gets none.
    let nginx = Nginx::start(c.dir.path());
    let db = Database::open_url_with(&nginx.url("city.flaneur"), &impatient()).unwrap();
    assert!(
        db.remote_warnings().is_empty(),
        "{:?}",
        db.remote_warnings()
    );
}

#[test]
fn a_compressed_answer_is_named_as_such() {
    match misbehaved(Fault::Gzip) {
        Error::Remote { what, .. } => assert!(
            what.contains("Content-Encoding: gzip") && what.contains("must not compress"),
            "{what}"
        ),
        e => panic!("{e}"),
    }
}

/// Runs `flaneur` with `args` and waits for it by its own pid, to read its peak resident
/// memory (`ru_maxrss`, KiB) from that wait alone rather than from every child of the
/// test process; its exit status (success) and standard error.
// The child is reaped by wait4, which clippy does not see.
#[allow(clippy::zombie_processes)]
fn flaneur_peak_rss(args: &[&str]) -> (bool, String, u64) {
    use std::io::Read;
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_flaneur"))
        .args(args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    });
    let mut status = 0;
    // SAFETY: rusage is plain data; wait4 fills it for the child named.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let pid = child.id() as libc::pid_t;
    // SAFETY: waits for our own child, whose pid std's Child no longer waits on.
    let got = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    assert_eq!(got, pid);
    let ok = libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0;
    (ok, reader.join().unwrap(), usage.ru_maxrss as u64)
}

#[test]
fn cache_mb_is_bounded_and_reserves_nothing_up_front() {
    let c = city(200, 17);
    let server = Nginx::start(c.dir.path());
    let url = server.url("city.flaneur");
    // No memory size at all: refused, naming the value and the limit (a cap would
    // hide a slip such as bytes given for MiB).
    let (ok, err, _) = flaneur_peak_rss(&["info", &url, "--cache-mb", "4294967296"]);
    assert!(!ok, "took --cache-mb 4294967296");
    assert!(
        err.contains("--cache-mb 4294967296") && err.contains("134217728 MiB"),
        "{err}"
    );
    assert!(
        !err.contains("panicked") && !err.contains("memory allocation"),
        "{err}"
    );
    // A bound far above the file: taken, capped at the file, nothing reserved for it.
    // Sized from the bound, the cache's map for a million MiB of 1 KiB pages took
    // gigabytes at once.
    let (ok, err, default_peak) = flaneur_peak_rss(&["info", &url]);
    assert!(ok, "{err}");
    let (ok, err, huge_peak) = flaneur_peak_rss(&["info", &url, "--cache-mb", "1000000"]);
    assert!(ok, "{err}");
    assert!(
        huge_peak < default_peak + 32 * 1024,
        "peak RSS {huge_peak} KiB with --cache-mb 1000000, {default_peak} KiB with the default"
    );
    assert!(!err.contains("warning"), "{err}");
}

#[test]
fn check_reads_a_url_as_it_reads_the_file() {
    let c = city(200, 18);
    let server = Nginx::start(c.dir.path());
    let url = server.url("city.flaneur");
    let local = common::succeeded(&common::flaneur(&["check", c.db.to_str().unwrap()]));
    let remote = common::succeeded(&common::flaneur(&["check", &url]));
    // "ok: NAME — P pages, O objects, … (R page reads)": the same but the name.
    let figures = |s: &str| s.split_once(" — ").map(|(_, rest)| rest.to_string());
    assert!(remote.starts_with("ok: "), "{remote}");
    assert_eq!(figures(&local), figures(&remote));
    // A damaged page is named over HTTP as on disk.
    let bad = c.dir.path().join("bad.flaneur");
    let mut bytes = std::fs::read(&c.db).unwrap();
    bytes[3 * 1024 + 100] ^= 0x40;
    std::fs::write(&bad, bytes).unwrap();
    let out = common::flaneur(&["check", &server.url("bad.flaneur")]);
    assert!(!out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("page 3 "), "{text}");
}

#[test]
fn a_build_input_given_for_a_database_says_how_to_build_one() {
    let c = city(30, 19);
    let obj = c.dir.path().join("house.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    for (input, what) in [(&c.scene, "a scene file"), (&obj, "an OBJ model")] {
        let input = input.to_str().unwrap();
        let out = common::flaneur(&["info", input]);
        assert!(!out.status.success(), "info took {input}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(what), "{err}");
        assert!(
            err.contains(&format!("flaneur build {input} -o city.flaneur")),
            "{err}"
        );
    }
    // Anything else is still only "not a database".
    let junk = c.dir.path().join("junk.bin");
    std::fs::write(&junk, b"seven sevens").unwrap();
    let out = common::flaneur(&["info", junk.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && !err.contains("flaneur build"),
        "{err}"
    );
}
