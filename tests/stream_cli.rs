//! `flaneur serve-stream` as a user runs it: a real process on loopback, a stream
//! client against it.

mod common;
#[path = "common/http.rs"]
mod http;

use std::io::{BufRead, BufReader};
use std::process::{Child, ChildStdout, Command, Stdio};
use std::time::Duration;

use flaneur::lod::{LodOptions, Traversal};
use flaneur::{BuildOptions, Database};
use flaneur_stream::{Hello, Landmark, StreamClient, ViewPacket};

/// Runs `flaneur bench` with `args` into a folder of its own, which it returns; a test's
/// failure, with the command's words, when the command fails.
fn bench(args: &[&str]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().to_str().unwrap().to_string();
    let all: Vec<&str> = ["bench"]
        .into_iter()
        .chain(args.iter().copied())
        .chain(["--out", out_dir.as_str()])
        .collect();
    let out = common::flaneur(&all);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    dir
}

/// The server's process, killed when dropped, and its printed lines.
struct Served {
    child: Child,
    lines: std::io::Lines<BufReader<ChildStdout>>,
}

impl Served {
    /// The server's first line, and the address it names (after `tcp://`).
    fn first_line(&mut self) -> (String, String) {
        let first = self.lines.next().unwrap().unwrap();
        let addr = first
            .split("tcp://")
            .nth(1)
            .and_then(|rest| rest.split(';').next())
            .unwrap()
            .to_string();
        (first, addr)
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn serve_stream(db: &std::path::Path, extra: &[&str]) -> Served {
    let mut child = Command::new(env!("CARGO_BIN_EXE_flaneur"))
        .args(["serve-stream", db.to_str().unwrap(), "--port", "0"])
        .args(extra)
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let lines = BufReader::new(child.stdout.take().unwrap()).lines();
    Served { child, lines }
}

#[test]
fn serve_stream_streams_a_databases_landmarks_to_a_client() {
    let every_object = BuildOptions {
        lod: Some(LodOptions {
            pm_threshold: 0,
            ..Default::default()
        }),
        ..Default::default()
    };
    let c = common::city(40, 31, &every_object);
    let db = Database::open(&c.db).unwrap();
    let landmarks = Landmark::all_in(&db, 8).unwrap();
    assert_eq!(landmarks.len(), 8);
    let mut served = serve_stream(&c.db, &["--landmarks", "8"]);
    let (first, addr) = served.first_line();
    assert!(first.starts_with("streaming 8 landmarks"), "{first}");
    let hello = Hello {
        traversal: Traversal::Priority,
        fov: 1.0,
        budget: None,
        out_of_view: false,
        back_face: false,
        scheme: flaneur_stream::Scheme::Dag,
    };
    let mut client = StreamClient::connect(&addr, hello, Duration::from_secs(20)).unwrap();
    // The eight largest, by id, each from its base mesh.
    let ids: Vec<u64> = client.objects().iter().map(|o| o.id).collect();
    assert_eq!(ids, landmarks.iter().map(|l| l.id).collect::<Vec<_>>());
    for (o, l) in client.objects().iter().zip(&landmarks) {
        assert_eq!(o.mesh().triangle_count(), l.pm.base.triangle_count());
    }
    let b = db.bounds();
    let view = ViewPacket {
        frame: 1,
        eye: (b.center() + glam::Vec3::new(0.0, 200.0, 0.0)).to_array(),
        aim: b.center().to_array(),
        tau: 0.0001,
        budget_mode: false,
        n: 500,
    };
    client.send_view(&view).unwrap();
    assert!(client.receive_batch().unwrap().splits > 0);
    client.bye().unwrap();
    let end = served.lines.next().unwrap().unwrap();
    assert!(
        end.contains("1 views answered") && end.ends_with("the client ended it"),
        "{end}"
    );
}

/// A database given as a URL is read over HTTP, as every command reads one: the same
/// landmarks as from the file.
#[test]
fn serve_stream_streams_a_database_given_as_a_url() {
    let c = common::city(60, 3, &common::with_landmarks());
    let nginx = http::Nginx::start(c.dir.path());
    let url = nginx.url("city.flaneur");
    let mut served = serve_stream(std::path::Path::new(&url), &["--landmarks", "4"]);
    let (first, addr) = served.first_line();
    let local = Landmark::all_in(&Database::open(&c.db).unwrap(), 4).unwrap();
    assert!(
        first.starts_with(&format!("streaming {} landmarks", local.len())),
        "{first}"
    );
    let hello = Hello {
        traversal: Traversal::Priority,
        fov: 1.0,
        budget: None,
        out_of_view: false,
        back_face: false,
        scheme: flaneur_stream::Scheme::Dag,
    };
    let client = StreamClient::connect(&addr, hello, Duration::from_secs(20)).unwrap();
    let ids: Vec<u64> = client.objects().iter().map(|o| o.id).collect();
    assert_eq!(ids, local.iter().map(|l| l.id).collect::<Vec<_>>());
    client.bye().unwrap();
}

#[test]
fn serve_stream_says_when_there_is_nothing_to_stream() {
    let c = common::city(
        20,
        32,
        &BuildOptions {
            lod: None,
            ..Default::default()
        },
    );
    let out = common::flaneur(&["serve-stream", c.db.to_str().unwrap(), "--port", "0"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no object with a progressive mesh"), "{err}");
    let out = common::flaneur(&["serve-stream", c.db.to_str().unwrap(), "--idle-s", "0"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("--idle-s"));
}

#[test]
fn bench_stream_hides_the_round_trip_that_the_sequential_client_waits_for() {
    let dir = bench(&[
        "stream",
        "--triangles",
        "20000",
        "--frames",
        "60",
        "--frame-ms",
        "20",
        "--rtts",
        "100",
    ]);
    assert!(dir.path().join(flaneur_bench::stream::PLOT).exists());
    let csv = common::Csv::read(&dir.path().join("stream.csv"));
    let [sequential, linear, quadratic] = &csv.rows[..] else {
        panic!("{} rows", csv.rows.len())
    };
    let clients: Vec<&str> = csv.rows.iter().map(|r| csv.get(r, "client")).collect();
    assert_eq!(clients, ["sequential", "linear", "quadratic"]);
    // The sequential client waits the round trip every frame, its mesh the reference's.
    assert!(csv.num(sequential, "mean_frame_ms") >= 100.0);
    assert_eq!(csv.num(sequential, "accuracy_all"), 1.0);
    // The predictive ones keep the frame period, predicting as many frames ahead as the
    // round trip spans (100 ms over 20 ms frames, and the traversal's time).
    for predictive in [linear, quadratic] {
        assert!(
            csv.num(predictive, "mean_frame_ms") < 50.0,
            "{predictive:?}"
        );
        let span = csv.num(predictive, "final_span");
        assert!((4.0..=10.0).contains(&span), "{predictive:?}");
        let accuracy = csv.num(predictive, "accuracy");
        assert!(accuracy > 0.0 && accuracy < 1.0, "{predictive:?}");
    }
}

#[test]
fn bench_stream_crowd_serves_every_client_and_reports_the_server() {
    let dir = bench(&[
        "stream-crowd",
        "--clients",
        "4",
        "--triangles",
        "20000",
        "--frames",
        "60",
        "--traversal",
        "constant",
    ]);
    let csv = common::Csv::read(&dir.path().join("stream-crowd.csv"));
    let row = &csv.rows[0];
    assert_eq!(csv.num(row, "clients"), 4.0);
    assert_eq!(csv.get(row, "traversal"), "constant");
    assert_eq!(csv.num(row, "failed"), 0.0);
    // The session threads were found and measured, each session's memory counted.
    assert!(csv.num(row, "server_cpu_s") > 0.0, "{row:?}");
    assert!(csv.num(row, "memory_mean") > 0.0, "{row:?}");
    assert!(csv.num(row, "shared_memory") > 0.0, "{row:?}");
    // The constant-time traversal evaluates at most 2N nodes a view, and was timed.
    let (n, evaluated) = (csv.num(row, "n"), csv.num(row, "most_evaluated"));
    assert!(evaluated > 0.0 && evaluated <= 2.0 * n, "{row:?}");
    assert!(csv.num(row, "traversal_p95_ms") > 0.0, "{row:?}");
    // Each view's operations and each batch's bytes, as El-Sana's Table 1 gives them.
    assert!(csv.num(row, "operations_per_view") > 0.0, "{row:?}");
    assert!(csv.num(row, "bytes_per_batch") > 0.0, "{row:?}");
    assert!(csv.num(row, "triangles_held") > 0.0, "{row:?}");
    assert!(csv.num(row, "round_trip_p50_ms") > 0.0, "{row:?}");
    let md = std::fs::read_to_string(dir.path().join("stream-crowd.md")).unwrap();
    assert!(md.contains("4 predictive clients"), "{md}");
}

/// `flaneur walk --render --stream`: the walk draws its landmarks from a stream server
/// of the same database, says what the session did, and refuses the flag without
/// --render.
#[test]
fn walk_draws_its_landmarks_from_a_stream_server() {
    let c = common::city(60, 3, &common::with_landmarks());
    let mut served = serve_stream(&c.db, &[]);
    let (_, addr) = served.first_line();
    let fixed = [
        "--config", "box", "--frames", "90", "--seed", "5", "--stream", &addr,
    ];
    let out = common::drawn_walk(&c.db, &c.dir.path().join("frames"), &fixed);
    let text = common::succeeded(&out);
    let number_before = |what: &str| common::number_before(&text, what);
    // Landmarks were drawn from the stream, and batches came for them.
    assert!(
        number_before(" draws of landmarks from the stream") > 0,
        "{text}"
    );
    assert!(number_before(" of 90 frames applied a batch") > 0, "{text}");
    assert!(
        text.contains(&format!("streamed landmarks from {addr}")),
        "{text}"
    );
    let db = c.db.to_str().unwrap();
    let out = common::flaneur(&[&["walk", db, "--quiet"][..], &fixed].concat());
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--stream is for a walk drawn"));
}

/// `flaneur view --stream` refuses a walk at full detail, and names a server it cannot
/// reach, before any window opens.
#[test]
fn view_with_a_stream_says_what_is_wrong_before_opening_a_window() {
    let c = common::city(20, 3, &BuildOptions::default());
    let db = c.db.to_str().unwrap();
    let out = common::flaneur(&["view", db, "--stream", "127.0.0.1:1", "--lod-tau", "0"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("give a --lod-tau above 0"), "{err}");
    // A port nobody listens on (bound, then let go).
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let addr = format!("127.0.0.1:{port}");
    let out = common::flaneur(&["view", db, "--stream", &addr]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!("connecting to the stream server at {addr}")),
        "{err}"
    );
}

/// `flaneur bench stream-bytes`: for one close view, streaming view-dependently costs
/// fewer bytes and triangles than view-independently, and under the cap it holds all
/// the view needs where the view-independent stream holds only part of it; likewise by
/// Kim–Lee–Kobbelt's scheme, and by El-Sana's blocks for more bytes.
#[test]
fn bench_stream_bytes_finds_the_view_dependent_stream_cheaper() {
    let dir = bench(&["stream-bytes", "--triangles", "20000"]);
    let csv = common::Csv::read(&dir.path().join("stream-bytes.csv"));
    let [dependent, independent, selective, selective_all, cut_only, blocks] = &csv.rows[..] else {
        panic!("{:?}", csv.rows)
    };
    assert_eq!(csv.get(dependent, "scheme"), "view-dependent");
    for what in ["bytes", "triangles", "frames"] {
        assert!(
            csv.num(dependent, what) < csv.num(independent, what),
            "{what}: {dependent:?} against {independent:?}"
        );
    }
    assert_eq!(csv.num(dependent, "cap_share"), 1.0);
    assert!(csv.num(independent, "cap_share") < 0.9, "{independent:?}");
    // The same for Kim–Lee–Kobbelt's truly selective scheme.
    assert_eq!(
        csv.get(selective, "scheme"),
        "truly-selective view-dependent"
    );
    for what in ["bytes", "triangles"] {
        assert!(
            csv.num(selective, what) < csv.num(selective_all, what),
            "{what}: {selective:?} against {selective_all:?}"
        );
    }
    assert_eq!(csv.num(selective, "cap_share"), 1.0);
    // KLK §7: without the data for the client's own refinement, the same mesh for fewer
    // bytes.
    assert_eq!(
        csv.num(cut_only, "triangles"),
        csv.num(selective, "triangles")
    );
    assert!(csv.num(cut_only, "bytes") < csv.num(selective, "bytes"));
    // El-Sana's blocks: the same mesh, for more bytes (a block brings the splits beside
    // the ones the view wants).
    assert_eq!(
        csv.get(blocks, "scheme"),
        "El-Sana blocks (2 levels) in process"
    );
    assert_eq!(
        csv.num(blocks, "triangles"),
        csv.num(selective, "triangles")
    );
    assert!(csv.num(blocks, "bytes") > csv.num(selective, "bytes"));
}

/// `flaneur bench stream-blocks` (El-Sana Table 1): over one walk, the truly selective
/// client and the clients of blocks draw the same meshes frame by frame (each is a
/// local refiner's), the predicting server's sessions take predicted blocks while the
/// quiet one's take none, and the bounded cache drops blocks.
#[test]
fn bench_stream_blocks_walks_every_scheme_to_the_same_meshes() {
    let dir = bench(&[
        "stream-blocks",
        "--triangles",
        "20000",
        "--frames",
        "40",
        "--rtt",
        "0",
        "--frame-ms",
        "20",
        "--idle-ms",
        "2",
        "--cache",
        "4",
    ]);
    let csv = common::Csv::read(&dir.path().join("stream-blocks.csv"));
    let [dag, selective, blocks, predicted, bounded] = &csv.rows[..] else {
        panic!("{:?}", csv.rows)
    };
    assert_eq!(csv.get(dag, "scheme"), "Zheng DAG (sequential)");
    for row in [blocks, predicted, bounded] {
        assert_eq!(
            csv.num(row, "triangles"),
            csv.num(selective, "triangles"),
            "{row:?}"
        );
        assert!(csv.num(row, "blocks") > 0.0, "{row:?}");
    }
    for row in [dag, selective, blocks, predicted, bounded] {
        assert!(
            csv.num(row, "operations") > 0.0 && csv.num(row, "bytes") > 0.0,
            "{row:?}"
        );
    }
    assert_eq!(csv.num(blocks, "predicted_kept"), 0.0);
    assert!(csv.num(predicted, "predicted_kept") > 0.0, "{predicted:?}");
    assert!(csv.num(bounded, "dropped") > 0.0, "{bounded:?}");
    assert_eq!(csv.num(predicted, "dropped"), 0.0);
}
