//! The fuzz targets' corpora (`fuzz/corpus/`, docs/stream.md "Fuzzing") replayed as the
//! targets run them, so that an input that once found a fault stays a test without
//! libFuzzer: `stream_session`'s through a server's `serve` with the output thrown
//! away, `stream_batch`'s through `receive` in a loop as a client reads a server.
//!
//! `selective_batch`'s are decoded and handed to a truly selective client.
//!
//! `write_seed_corpus` (ignored) wrote the seeds the corpora grew from: well-formed
//! sessions and sessions the server refuses, and what the server answered each with.

use std::collections::BTreeSet;
use std::fs;
use std::io;
use std::net::SocketAddr;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Arc;

use flaneur::fuzzing::{corpus_dir, corpus_inputs};

use flaneur::lod::{bumpy_torus, Dag, DagConstruction, ProgressiveMesh, Traversal, View};
use flaneur::lod::{
    CutVertexClient, HeapIndex, NodeName, SelectiveClient, SelectiveServer, SelectiveSource,
};
use flaneur_stream::protocol::{receive, send, Message, MAX_N, MAX_TO_CLIENT, MAX_TO_SERVER};
use flaneur_stream::selective_wire::{decode_vsplits, encode_vsplits};
use flaneur_stream::{
    HeldLeaves, HeldNodes, Hello, Landmark, Scheme, ServerConfig, StreamServer, ViewPacket,
};

/// The server the `stream_session` target serves each input with: one torus of about
/// 1,000 triangles.
fn server() -> StreamServer {
    let pm = ProgressiveMesh::build(&bumpy_torus(1_000)).unwrap();
    let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
    let torus = Landmark {
        id: 1,
        pm: Arc::new(pm),
        dag: Arc::new(dag),
    };
    StreamServer::bind("127.0.0.1:0", vec![torus], ServerConfig::default()).unwrap()
}

fn peer() -> SocketAddr {
    SocketAddr::from(([127, 0, 0, 1], 9))
}

/// What the `stream_batch` target does with an input: the messages read before an
/// error or the end.
fn read_as_client(data: &[u8]) -> usize {
    let mut input = data;
    let mut read = 0;
    while let Ok(Some(_)) = receive(&mut input, MAX_TO_CLIENT) {
        read += 1;
    }
    read
}

#[test]
fn every_session_of_the_corpus_ends_without_a_panic() {
    let server = server();
    let (mut answered, mut refused) = (0, 0);
    for (name, data) in corpus_inputs("stream_session").unwrap() {
        let end = catch_unwind(AssertUnwindSafe(|| {
            server.serve(&data[..], io::sink(), peer())
        }))
        .unwrap_or_else(|_| panic!("stream_session input {name} panicked the server"));
        answered += usize::from(end.frames > 0);
        refused += usize::from(end.reason.is_some());
    }
    // Both sides of the protocol's checks are exercised: sessions served past HELLO,
    // and sessions refused.
    assert!(answered > 0, "no input of the corpus had a view answered");
    assert!(refused > 0, "no input of the corpus was refused");
}

#[test]
fn every_server_stream_of_the_corpus_reads_without_a_panic() {
    let mut read = 0;
    for (name, data) in corpus_inputs("stream_batch").unwrap() {
        read += catch_unwind(|| read_as_client(&data))
            .unwrap_or_else(|_| panic!("stream_batch input {name} panicked the client's reader"));
    }
    assert!(
        read > 0,
        "no input of the corpus held a message a client reads"
    );
}

/// The `selective_batch` target's clients' sources, each with a view: a small torus's
/// (placed by cut vertices) and a flat-shaded building's (placed by leaves).
fn selective_sources() -> [(SelectiveSource, View); 2] {
    let source = |mesh: &flaneur::scene::Mesh| {
        let pm = ProgressiveMesh::build(mesh).unwrap();
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
        SelectiveSource::new(&pm, &dag).unwrap()
    };
    let building = citygen::sample_building(600).unwrap();
    let p = glam::Vec3::from(building.positions[0]);
    let torus_view = View::new(glam::Vec3::new(0.0, 0.0, 2.0), glam::Vec3::NEG_Z, 1.0);
    let building_view = View::new(p + glam::Vec3::new(0.0, 5.0, 40.0), glam::Vec3::NEG_Z, 1.0);
    [
        (source(&bumpy_torus(600)), torus_view.unwrap()),
        (source(&building), building_view.unwrap()),
    ]
}

#[test]
fn every_selective_batch_of_the_corpus_ends_without_a_panic() {
    let sources = selective_sources();
    let (mut decoded, mut refused, mut taken) = (0, 0, [0, 0]);
    for (name, data) in corpus_inputs("selective_batch").unwrap() {
        catch_unwind(AssertUnwindSafe(|| match decode_vsplits(&data) {
            Ok(packets) => {
                decoded += 1;
                for (k, (source, view)) in sources.iter().enumerate() {
                    let mut client = SelectiveClient::new(source.base());
                    if client.receive(&packets).is_ok() {
                        taken[k] += usize::from(!packets.is_empty());
                        let _ = client.select(view, 0.001);
                    }
                    let _ = CutVertexClient::new(source.base()).receive(&packets);
                }
            }
            Err(_) => refused += 1,
        }))
        .unwrap_or_else(|_| panic!("selective_batch input {name} panicked a client"));
    }
    assert!(
        decoded > 0 && refused > 0,
        "{decoded} decoded, {refused} refused"
    );
    // Both placements take some batch whole.
    assert!(taken[0] > 0 && taken[1] > 0, "batches taken: {taken:?}");
}

/// Writes the `selective_batch` target's seeds: the batches a server sends each client
/// for a few views, and a few bad ones.
#[test]
#[ignore = "writes the fuzz corpus's seeds; run by hand"]
fn write_selective_seeds() {
    let dir = corpus_dir("selective_batch");
    fs::create_dir_all(&dir).unwrap();
    let sources = ["torus", "building"].into_iter().zip(selective_sources());
    for ((name, (source, view)), distance) in sources.zip([2.0f32, 40.0]) {
        let mut server = SelectiveServer::new(&source);
        let mut cut = SelectiveServer::new(&source).cut_vertex_only();
        for (k, closer) in [0.0f32, 0.3, 0.6].into_iter().enumerate() {
            let eye = view.eye + view.look * closer * distance;
            let v = View::new(eye, view.look, 1.0).unwrap();
            let packets = server.refine(&source, &v, 0.002).unwrap();
            fs::write(
                dir.join(format!("seed-{name}-view-{k}")),
                encode_vsplits(&packets),
            )
            .unwrap();
            let packets = cut.refine(&source, &v, 0.002).unwrap();
            fs::write(
                dir.join(format!("seed-{name}-cut-{k}")),
                encode_vsplits(&packets),
            )
            .unwrap();
        }
    }
    fs::write(dir.join("seed-empty"), encode_vsplits(&[])).unwrap();
    fs::write(dir.join("seed-count-too-big"), [0xff, 0xff, 0, 0]).unwrap();
}

fn encode(messages: &[Message]) -> Vec<u8> {
    let mut bytes = Vec::new();
    for m in messages {
        send(&mut bytes, m).unwrap();
    }
    bytes
}

fn hello(traversal: Traversal, budget: Option<u32>, criteria: u8) -> Hello {
    Hello {
        traversal,
        fov: 1.0,
        budget,
        out_of_view: criteria & 1 != 0,
        back_face: criteria & 2 != 0,
        scheme: Scheme::Dag,
    }
}

/// Frame `frame` of a walk in towards the torus (radius 1.4 about the origin, in the xz
/// plane) and round it, looking at its ring.
fn view(frame: u32, n: u32, budget_mode: bool) -> ViewPacket {
    let (angle, distance) = (0.4 * frame as f32, 4.0 - 0.4 * frame as f32);
    ViewPacket {
        frame,
        eye: [distance * angle.sin(), 0.3, distance * angle.cos()],
        aim: [angle.sin(), 0.0, angle.cos()],
        tau: 0.02 / (1 + frame) as f32,
        budget_mode,
        n,
    }
}

/// HELLO, then `rest`, as a client sends them.
fn session(hello: Hello, rest: impl IntoIterator<Item = Message>) -> Vec<u8> {
    encode(
        &[Message::Hello(hello)]
            .into_iter()
            .chain(rest)
            .collect::<Vec<_>>(),
    )
}

fn views(frames: std::ops::Range<u32>, n: u32) -> impl Iterator<Item = Message> {
    frames.map(move |f| Message::View(view(f, n, false)))
}

/// The nodes a client holds split after reading `answer` (WELCOME, then BATCHes).
fn held_split(mut answer: &[u8]) -> Vec<u32> {
    let mut held = BTreeSet::new();
    while let Some((m, _)) = receive(&mut answer, MAX_TO_CLIENT).unwrap() {
        if let Message::Batch { objects, .. } = m {
            for o in objects {
                o.collapses.iter().for_each(|n| assert!(held.remove(n)));
                held.extend(o.splits.iter().map(|s| s.node));
            }
        }
    }
    held.into_iter().collect()
}

/// Seeds: sessions a client may send, then ones the server refuses.
fn seed_sessions(server: &StreamServer) -> Vec<(String, Vec<u8>)> {
    let mut seeds = Vec::new();
    let traversals = [
        ("priority", Traversal::Priority),
        ("linear", Traversal::Linear),
        ("constant-time", Traversal::ConstantTime),
    ];
    for (name, traversal) in traversals {
        for criteria in 0..4 {
            for (mode, budget) in [("free", None), ("budget", Some(300))] {
                let walk = (0..6).map(|f| Message::View(view(f, 40, budget.is_some())));
                let bye = [Message::Bye];
                seeds.push((
                    format!("{name}-{mode}-criteria{criteria}"),
                    session(hello(traversal, budget, criteria), walk.chain(bye)),
                ));
            }
        }
    }
    let priority = hello(Traversal::Priority, None, 3);
    let bye = || [Message::Bye];
    seeds.push(("no-bye".into(), session(priority, views(0..4, 40))));
    seeds.push((
        "n-max".into(),
        session(priority, views(0..4, MAX_N).chain(bye())),
    ));
    seeds.push(("hello-bye".into(), session(priority, bye())));
    seeds.push(("hello-only".into(), session(priority, [])));

    // A client that held what six views brought resumes on a new connection.
    let mut answer = Vec::new();
    let before = session(priority, views(0..6, 40).chain(bye()));
    server.serve(&before[..], &mut answer, peer());
    let held = held_split(&answer);
    assert!(!held.is_empty(), "six views split nothing to resume from");
    let resume = |next_frame, objects: Vec<(u32, Vec<u32>)>| Message::Resume {
        next_frame,
        objects: objects
            .into_iter()
            .map(|(index, nodes)| HeldNodes { index, nodes })
            .collect(),
    };
    for (name, traversal) in traversals {
        let r = resume(6, vec![(0, held.clone())]);
        let rest = [r].into_iter().chain(views(6..10, 40)).chain(bye());
        seeds.push((
            format!("resume-{name}"),
            session(hello(traversal, None, 3), rest),
        ));
    }
    let reversed = held.iter().rev().copied().collect();
    let rest = [resume(6, vec![(0, reversed)])].into_iter();
    seeds.push((
        "resume-reversed".into(),
        session(priority, rest.chain(views(6..8, 40))),
    ));
    let rest = [resume(0, vec![])].into_iter().chain(views(0..2, 40));
    seeds.push(("resume-nothing".into(), session(priority, rest)));

    // Refused: each breaks one rule.
    let mut bad_magic = session(priority, bye());
    bad_magic[5] = b'X';
    seeds.push(("refused-magic".into(), bad_magic));
    let mut bad_version = session(priority, bye());
    bad_version[13] = 9;
    seeds.push(("refused-version".into(), bad_version));
    for fov in [0.0, 4.0, f32::NAN] {
        let h = Hello { fov, ..priority };
        seeds.push((format!("refused-fov-{fov}"), session(h, views(0..4, 40))));
    }
    seeds.push((
        "refused-view-first".into(),
        encode(&[Message::View(view(0, 40, false)), Message::Bye]),
    ));
    seeds.push((
        "refused-hello-twice".into(),
        session(priority, [Message::Hello(priority)]),
    ));
    let backwards = views(0..4, 40).chain(views(0..1, 40));
    seeds.push(("refused-frame-order".into(), session(priority, backwards)));
    for n in [0, MAX_N + 1] {
        seeds.push((format!("refused-n-{n}"), session(priority, views(0..1, n))));
    }
    let mut blind = view(0, 40, false);
    blind.aim = blind.eye;
    seeds.push((
        "refused-no-direction".into(),
        session(priority, [Message::View(blind)]),
    ));
    seeds.push((
        "refused-server-message".into(),
        session(priority, [Message::Refused("no".into())]),
    ));
    seeds.push(("refused-kind".into(), vec![1, 0, 0, 0, 0x7f]));
    let over = (MAX_TO_SERVER as u32 + 1).to_le_bytes();
    seeds.push(("refused-over-bound".into(), over.to_vec()));
    let mut cut = session(priority, views(0..4, 40));
    cut.truncate(cut.len() - 10);
    seeds.push(("refused-cut".into(), cut));
    let bad_resumes = [
        ("out-of-range", vec![(0, vec![u32::MAX])]),
        ("object", vec![(1, held.clone())]),
        ("object-twice", vec![(0, vec![]), (0, vec![])]),
        ("node-twice", vec![(0, vec![held[0], held[0]])]),
        ("no-parent", vec![(0, held[1..].to_vec())]),
    ];
    for (name, objects) in bad_resumes {
        let rest = [resume(6, objects)].into_iter().chain(views(6..7, 40));
        seeds.push((format!("refused-resume-{name}"), session(priority, rest)));
    }
    let rest = [resume(6, vec![(0, held.clone())])].into_iter();
    seeds.push((
        "refused-resume-frame".into(),
        session(priority, rest.chain(views(5..6, 40))),
    ));
    let late = views(0..1, 40).chain([resume(6, vec![(0, held)])]);
    seeds.push(("refused-resume-late".into(), session(priority, late)));
    seeds.extend(selective_seed_sessions(server));
    seeds
}

/// Seeds of the truly selective schemes: sessions a client may send, a resume from
/// the leaves a session left, then ones the server refuses.
fn selective_seed_sessions(server: &StreamServer) -> Vec<(String, Vec<u8>)> {
    let mut seeds = Vec::new();
    let selective = |scheme, criteria| Hello {
        scheme,
        ..hello(Traversal::Priority, None, criteria)
    };
    for (name, scheme) in [
        ("selective", Scheme::Selective),
        ("cut-vertex", Scheme::CutVertex),
    ] {
        for criteria in 0..4 {
            let walk = views(0..6, 40).chain([Message::Bye]);
            seeds.push((
                format!("{name}-criteria{criteria}"),
                session(selective(scheme, criteria), walk),
            ));
        }
    }
    let hello = selective(Scheme::Selective, 3);
    // A client that held what six views brought resumes on a new connection.
    let mut answer = Vec::new();
    let before = session(hello, views(0..6, 40).chain([Message::Bye]));
    server.serve(&before[..], &mut answer, peer());
    let leaves = held_leaves(&answer);
    let resume = |leaves: Vec<NodeName>| Message::ResumeLeaves {
        next_frame: 6,
        objects: vec![HeldLeaves { index: 0, leaves }],
    };
    let rest = [resume(leaves.clone())].into_iter().chain(views(6..10, 40));
    seeds.push(("selective-resume".into(), session(hello, rest)));
    let refused: Vec<(&str, Vec<Message>)> = vec![
        ("budget", vec![Message::View(view(0, 40, true))]),
        (
            "resume-dag",
            vec![Message::Resume {
                next_frame: 0,
                objects: vec![],
            }],
        ),
        ("leaves-missing", vec![resume(leaves[1..].to_vec())]),
        (
            "leaves-twice",
            vec![resume([&leaves[..], &leaves[..1]].concat())],
        ),
    ];
    for (name, rest) in refused {
        seeds.push((format!("refused-selective-{name}"), session(hello, rest)));
    }
    let dag = selective(Scheme::Dag, 3);
    seeds.push((
        "refused-dag-resume-leaves".into(),
        session(dag, [resume(leaves)]),
    ));
    seeds
}

/// The leaves a truly selective client holds after reading `answer`
/// (SELECTIVE-WELCOME, then VSPLITSes): the roots, each split node giving way to its
/// children.
fn held_leaves(mut answer: &[u8]) -> Vec<NodeName> {
    let mut held = BTreeSet::new();
    while let Some((m, _)) = receive(&mut answer, MAX_TO_CLIENT).unwrap() {
        match m {
            Message::SelectiveWelcome(objects) => {
                held.extend(
                    (0..objects[0].base.roots.len() as u32).map(|tree| NodeName {
                        tree,
                        node: HeapIndex::root(),
                    }),
                );
            }
            Message::Vsplits { objects, .. } => {
                for p in &objects[0].packets {
                    assert!(held.remove(&p.node));
                    for right in [false, true] {
                        held.insert(NodeName {
                            tree: p.node.tree,
                            node: p.node.node.child(right),
                        });
                    }
                }
            }
            _ => {}
        }
    }
    held.into_iter().collect()
}

/// Writes the seeds into the corpora: the sessions for `stream_session`, and for
/// `stream_batch` what the server sent each (WELCOME, BATCHes, REFUSED). Run once (and
/// again when the protocol's version changes), then fuzz and minimise (docs/stream.md,
/// "Fuzzing").
#[test]
#[ignore = "writes the fuzz corpora's seeds"]
fn write_seed_corpus() {
    let server = server();
    let (sessions, streams) = (corpus_dir("stream_session"), corpus_dir("stream_batch"));
    fs::create_dir_all(&sessions).unwrap();
    fs::create_dir_all(&streams).unwrap();
    for (name, data) in seed_sessions(&server) {
        let mut answer = Vec::new();
        server.serve(&data[..], &mut answer, peer());
        fs::write(sessions.join(format!("seed-{name}")), &data).unwrap();
        fs::write(streams.join(format!("seed-{name}")), &answer).unwrap();
    }
}
