//! The `flaneur` binary end to end: build, info, query (text and JSON), and its errors.

mod common;

use common::flaneur;

use flaneur::BuildOptions;

#[test]
fn build_info_query() {
    let c = common::city(300, 2, &BuildOptions::default());
    let db = c.dir.path().join("cli.flaneur");
    let out = flaneur(&[
        "build",
        c.scene.to_str().unwrap(),
        "--out",
        db.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("300 objects"));

    let out = flaneur(&["info", db.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("objects     300") && text.contains("height"),
        "{text}"
    );
    let out = flaneur(&["info", db.to_str().unwrap(), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["objects"], 300);

    let b = c.bounds();
    let q = format!(
        "{},{},{},{},{},{}",
        b.min.x,
        b.min.y,
        b.min.z,
        b.center().x,
        b.max.y,
        b.center().z
    );
    let h = format!(
        "{},{},{},{},{},{}",
        b.min.x,
        b.min.y,
        b.min.z,
        b.min.x + 50.0,
        b.max.y,
        b.max.z
    );
    let out = flaneur(&[
        "query",
        db.to_str().unwrap(),
        "--box",
        &q,
        "--history",
        &h,
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let ids: Vec<u64> = v["ids"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect();
    assert_eq!(
        ids,
        c.brute_complement(&q.parse().unwrap(), &[h.parse().unwrap()])
    );
    assert_eq!(v["query"], "csearch");
    assert_eq!(
        v["pages"].as_array().unwrap().len() as u64,
        v["page_reads"].as_u64().unwrap()
    );

    let out = flaneur(&[
        "query",
        db.to_str().unwrap(),
        "--box",
        &q,
        "--backend",
        "pread",
    ]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("pages read"));
}

#[test]
fn errors_are_messages_not_panics() {
    let c = common::city(100, 2, &BuildOptions::default());
    let db = c.db.to_str().unwrap();
    for args in [
        vec!["query", db, "--box", "nan,0,0,1,1,1"],
        vec!["query", db, "--box", "5,0,0,1,1,1"],
        vec!["query", db, "--box", "1,2,3"],
        vec!["query", "no-such.flaneur", "--box", "0,0,0,1,1,1"],
        vec!["info", c.scene.to_str().unwrap()],
        vec!["build", "no-such.scene", "--out", "x.flaneur"],
        // A build never writes over its own input.
        vec![
            "build",
            c.scene.to_str().unwrap(),
            "--out",
            c.scene.to_str().unwrap(),
        ],
        // A field of view given in degrees is refused in degrees.
        vec!["shot", db, "--at", "0,2,0", "--fov", "180"],
        vec!["lod", c.scene.to_str().unwrap(), "--fov", "nan"],
        // A walk that cannot keep the promise is refused, not walked waiting.
        vec!["walk", db, "--mode", "vsc", "--never-wait"],
    ] {
        let out = flaneur(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
        assert!(err.contains("error"), "{args:?}: {err}");
        if args.iter().any(|a| a.starts_with("no-such")) {
            assert_eq!(
                err.matches("No such file or directory").count(),
                1,
                "the system's words once: {err}"
            );
        }
        if args[0] == "build" && args[1] == args[3] {
            assert!(err.contains("is an input of the build"), "{err}");
            assert!(
                c.scene.metadata().unwrap().len() > 0,
                "the input was overwritten"
            );
        }
        if args.contains(&"--fov") {
            assert!(
                err.contains("within (0°, 180°)") || err.contains("degrees"),
                "{err}"
            );
            assert!(!err.contains("radian") && !err.contains("3.14"), "{err}");
        }
        if args.contains(&"--never-wait") {
            assert!(
                err.contains("--never-wait is for --mode review, box, pvs and visual"),
                "{err}"
            );
        }
    }
}

#[test]
fn walk_and_index_cache_bench() {
    let c = common::city(
        1500,
        2,
        &BuildOptions {
            page_size: 1024,
            ..Default::default()
        },
    );
    let db = c.db.to_str().unwrap();
    let csv = c.dir.path().join("frames.csv");
    let saved = c.dir.path().join("path.csv");
    let out = flaneur(&[
        "walk",
        db,
        "--path",
        "turning",
        "--frames",
        "90",
        "--far",
        "150",
        "--csv",
        csv.to_str().unwrap(),
        "--save-path",
        saved.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("visual misses 0") && text.contains("hit rate"),
        "{text}"
    );
    assert_eq!(std::fs::read_to_string(&csv).unwrap().lines().count(), 91);
    // The saved path replays as a file.
    let out = flaneur(&[
        "walk",
        db,
        "--path",
        saved.to_str().unwrap(),
        "--config",
        "box",
        "--far",
        "150",
        "--quiet",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A path file walks its first --frames poses, and is never silently cut short.
    let part = c.dir.path().join("part.csv");
    common::succeeded(&flaneur(&[
        "walk",
        db,
        "--path",
        saved.to_str().unwrap(),
        "--frames",
        "30",
        "--far",
        "150",
        "--quiet",
        "--csv",
        part.to_str().unwrap(),
    ]));
    assert_eq!(std::fs::read_to_string(&part).unwrap().lines().count(), 31);
    let out = flaneur(&[
        "walk",
        db,
        "--path",
        saved.to_str().unwrap(),
        "--frames",
        "200",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("--frames 200") && err.contains("holds 90 poses"),
        "{err}"
    );
    let out = flaneur(&["walk", db, "--path", "nowhere.csv", "--quiet"]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("nowhere.csv"));

    let dir = c.dir.path().join("bench");
    let out = flaneur(&[
        "bench",
        "index-cache",
        db,
        "--frames",
        "120",
        "--far",
        "150",
        "--sizes",
        "2,8,32",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in [
        "index-cache.csv",
        "index-cache.md",
        "index-cache-normal.png",
        "index-cache-backward.png",
    ] {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    let csv = std::fs::read_to_string(dir.join("index-cache.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 5 * 3);
    // No online policy beats Belady on any row.
    for line in csv.lines().skip(1) {
        let v: Vec<f64> = line
            .split(',')
            .skip(3)
            .take(4)
            .map(|x| x.parse().unwrap())
            .collect();
        // LRU, DPLRU and path against Belady.
        assert!(v[..3].iter().all(|h| *h <= v[3]), "{line}");
    }
}

#[test]
fn walking_experiments_write_their_outputs() {
    let c = common::city(
        1500,
        3,
        &BuildOptions {
            page_size: 1024,
            ..Default::default()
        },
    );
    let db = c.db.to_str().unwrap();
    let dir = c.dir.path().join("bench");
    let d = dir.to_str().unwrap();
    let walk = ["--frames", "60", "--far", "150"];
    for (args, files) in [
        (
            vec!["prefetch-k", "--ks", "0,0.8"],
            vec![
                "prefetch-k.csv",
                "prefetch-k.md",
                "prefetch-k-frame-time.png",
            ],
        ),
        (
            vec!["view-culling", "--sfs", "1,2"],
            vec!["view-culling.csv", "view-culling.md", "view-culling.png"],
        ),
        (
            vec!["patterns"],
            vec!["patterns.csv", "patterns.md", "patterns-io-per-query.png"],
        ),
    ] {
        let mut all = vec!["bench"];
        all.extend(&args[..1]);
        all.push(db);
        all.extend(&args[1..]);
        all.extend(walk);
        all.extend(["--out", d]);
        let out = flaneur(&all);
        assert!(
            out.status.success(),
            "{all:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        for f in files {
            assert!(dir.join(f).exists(), "{all:?}: {f} missing");
        }
    }
    let out = flaneur(&["bench", "prefetch-k", db, "--ks", "-1", "--out", d]);
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("error"));
}

#[test]
fn lod_writes_levels_and_measures_a_view() {
    let dir = tempfile::tempdir().unwrap();
    let bunny = concat!(env!("CARGO_MANIFEST_DIR"), "/data/bunny.obj");
    let out = dir.path().join("levels");
    let o = flaneur(&[
        "lod",
        bunny,
        "--out",
        out.to_str().unwrap(),
        "--ratio",
        "0.25",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let triangles = |level: &str| -> usize {
        flaneur::scene::load_obj(&out.join(level))
            .unwrap()
            .iter()
            .map(|(_, m)| m.triangle_count())
            .sum()
    };
    let (first, second) = (triangles("level-0.obj"), triangles("level-1.obj"));
    assert_eq!(first, 3674);
    assert!(second <= 3674 / 4 + 2, "{second}");

    // A ratio the simplifier refuses leaves no folder behind.
    let refused = dir.path().join("refused");
    let o = flaneur(&[
        "lod",
        bunny,
        "--out",
        refused.to_str().unwrap(),
        "--ratio",
        "0",
    ]);
    assert!(!o.status.success());
    assert!(!refused.exists(), "an empty folder was left");

    let o = flaneur(&[
        "lod", bunny, "--refine", "--eye", "0,5,20", "--look", "0,5,0", "--tau", "0.001",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("of 3674 triangles") && text.contains("Hausdorff"),
        "{text}"
    );

    for bad in [
        &["lod", bunny][..],
        &["lod", bunny, "--refine", "--eye", "0,5", "--look", "0,5,0"],
        &["lod", "missing.obj", "--out", "x"],
    ] {
        let o = flaneur(bad);
        assert!(!o.status.success(), "{bad:?} succeeded");
        assert!(!o.stderr.is_empty(), "{bad:?}: no error message");
    }
}

/// A vector option takes a value that starts with a minus (a city left of the origin),
/// as it takes `--box=…`.
#[test]
fn vector_options_take_a_leading_minus() {
    let c = common::city(100, 2, &BuildOptions::default());
    let db = c.db.to_str().unwrap();
    let b = c.bounds();
    let q = format!("-1000,-10,-1000,{},{},{}", b.max.x, b.max.y, b.max.z);
    let h = format!("-1000,-10,-1000,{},{},{}", b.center().x, b.max.y, b.max.z);
    let split = flaneur(&["query", db, "--box", &q, "--history", &h, "--json"]);
    let joined = flaneur(&[
        "query",
        db,
        &format!("--box={q}"),
        &format!("--history={h}"),
        "--json",
    ]);
    let err = String::from_utf8_lossy(&split.stderr);
    assert!(split.status.success() && joined.status.success(), "{err}");
    let ids = |out: &std::process::Output| {
        serde_json::from_slice::<serde_json::Value>(&out.stdout).unwrap()["ids"].clone()
    };
    assert_eq!(ids(&split), ids(&joined));
    assert!(!ids(&split).as_array().unwrap().is_empty());
    // An eye and a look left of the origin and downwards parse too: the missing
    // database is what is refused.
    let out = flaneur(&[
        "shot",
        "no-such.flaneur",
        "--at",
        "-5,-1,-5",
        "--look",
        "-30,-10",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("no-such.flaneur") && !err.contains("panicked"),
        "{err}"
    );
}

/// A closed pipe ends the program quietly, as coreutils do (`flaneur query … | head`):
/// no panic about a broken pipe, no message.
#[cfg(unix)]
#[test]
fn a_closed_pipe_ends_the_program_quietly() {
    use std::os::unix::process::ExitStatusExt;
    use std::process::{Command, Stdio};
    let c = common::city(300, 2, &BuildOptions::default());
    let b = c.bounds();
    let q = format!(
        "{},{},{},{},{},{}",
        b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
    );
    for args in [
        vec!["query", c.db.to_str().unwrap(), "--box", &q],
        vec!["info", c.db.to_str().unwrap()],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_flaneur"))
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // The reader goes away before the first line is written.
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.is_empty(), "{args:?}: {err}");
        assert!(
            out.status.success() || out.status.signal() == Some(13),
            "{args:?}: {:?}",
            out.status
        );
    }
}

/// Every number an option takes is finite (NaN meant "no prefetching" to `--k`, which
/// takes a negative number for that), and a negative one is read as a number.
#[test]
fn numbers_are_finite_and_may_be_negative() {
    let c = common::city(100, 2, &BuildOptions::default());
    let db = c.db.to_str().unwrap();
    for (option, value) in [("--k", "nan"), ("--sf", "inf"), ("--speed", "-inf")] {
        let out = flaneur(&["walk", db, &format!("{option}={value}"), "--frames", "3"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{option} {value} walked");
        assert!(
            err.contains("is not a finite number"),
            "{option} {value}: {err}"
        );
    }
    let out = flaneur(&["walk", db, "--k", "-1", "--frames", "3"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(String::from_utf8_lossy(&out.stdout).contains("prefetch off"));
}

/// Every duration an option takes is checked against its range as the arguments are
/// read: `--idle-s 1e20` once reached `Duration::from_secs_f64` and panicked. A real
/// database with landmarks, so that nothing but the parse stands before that point.
#[test]
fn a_duration_out_of_range_is_refused_by_name_not_a_panic() {
    let c = common::city(
        20,
        31,
        &BuildOptions {
            lod: Some(flaneur::lod::LodOptions {
                pm_threshold: 0,
                ..Default::default()
            }),
            ..Default::default()
        },
    );
    let db = c.db.to_str().unwrap();
    for value in ["1e20", "-1", "0", "nan", "inf"] {
        let out = flaneur(&["serve-stream", db, "--port", "0", "--idle-s", value]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("panicked"), "--idle-s {value}: {err}");
        assert_eq!(out.status.code(), Some(2), "--idle-s {value}: {err}");
        assert!(err.contains("--idle-s"), "{err}");
        assert!(
            err.contains("within (0, 86400] s") || err.contains("not a finite number"),
            "--idle-s {value}: {err}"
        );
    }
}

/// The durations, rates, τ, η and the other fractions every command takes are refused
/// outside their ranges before anything is opened (the database named here does not
/// exist), each refusal naming the option and the range.
#[test]
fn durations_and_fractions_are_checked_as_the_arguments_are_read() {
    let db = "no-such.flaneur";
    #[rustfmt::skip]
    let cases: &[(&[&str], &str)] = &[
        (&["serve-stream", db, "--predict-after-ms", "99999999999"], "[0, 3600000] ms"),
        (&["walk", db, "--lod-tau", "-1"], "within [0, 1) of the viewport"),
        (&["walk", db, "--lod-tau", "1"], "within [0, 1) of the viewport"),
        (&["view", db, "--lod-tau", "-1"], "within [0, 1) of the viewport"),
        (&["bench", "fidelity", db, "--lod-tau", "-0.5"], "within [0, 1)"),
        (&["lod", "x.obj", "--refine", "--tau", "0"], "within (0, 1) of the viewport"),
        (&["bench", "lod-refine", "--taus", "0.001,2"], "within (0, 1)"),
        (&["bench", "stream", "--tau", "-1"], "within (0, 1)"),
        (&["walk", db, "--eta", "-0.1"], "within [0, 1] of the view"),
        (&["view", db, "--eta", "2"], "within [0, 1]"),
        (&["bench", "hdov-search", db, "--etas", "0,-1"], "within [0, 1]"),
        (&["walk", db, "--border", "0.7"], "within (0, 0.5] of the cell's side"),
        (&["build", "x.scene", "-o", "x.flaneur", "--fill", "0"], "within [0.1, 1]"),
        (&["lod", "x.obj", "--out", "x", "--ratio", "1"], "within (0, 1)"),
        (&["walk", db, "--fps", "1e-30"], "within [0.1, 1000] frames/s"),
        (&["walk", db, "--speed", "1e9"], "or 0 for unpaced"),
        (&["walk", db, "--k", "1e9"], "within [0, 60] s"),
        (&["bench", "stream", "--frame-ms", "1e300"], "within (0, 10000] ms"),
        (&["bench", "stream", "--rtts", "100,1000000"], "within [0, 60000] ms"),
        (&["bench", "stream-blocks", "--idle-ms", "99999999999"], "within [0, 3600000] ms"),
        (&["bench", "http", db, "--mbits", "1e-300"], "within [0.001, 1000000] Mbit/s"),
    ];
    for (args, range) in cases {
        let out = flaneur(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        let option = args.iter().rev().nth(1).unwrap();
        assert!(
            err.contains(option) && err.contains(range),
            "{args:?}: {err}"
        );
    }
}
