//! The sessions of El-Sana's blocks in the fuzz corpora (`fuzz/corpus/`, docs/stream.md
//! "Fuzzing"): `blocks_batch`'s inputs replayed as the target runs them, each BLOCKS
//! handed to a client of blocks with a small cache that then refines for a view.
//!
//! `write_blocks_seeds` (ignored) wrote the seeds: sessions of blocks a client may send
//! (its SWITCHes made by a client of blocks in process, as the real one makes them)
//! and sessions the server refuses, for `stream_session`; what the server answered each
//! with, for `stream_batch` and `blocks_batch`.

use std::fs;
use std::net::SocketAddr;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Arc;

use flaneur::fuzzing::{corpus_dir, corpus_inputs};

use flaneur::lod::{
    bumpy_torus, BlockClient, BlockServer, Dag, DagConstruction, NodeName, ProgressiveMesh,
    SelectiveSource, Traversal, View,
};
use flaneur_stream::protocol::{receive, send, Message, ObjectSwitch, Switch, MAX_TO_CLIENT};
use flaneur_stream::{Hello, Landmark, Scheme, ServerConfig, StreamServer, ViewPacket};

const LEVELS: u32 = 2;

fn torus() -> (ProgressiveMesh, Dag) {
    let pm = ProgressiveMesh::build(&bumpy_torus(1_000)).unwrap();
    let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
    (pm, dag)
}

/// The fuzz targets' server, as in `fuzz_corpus.rs`: one torus of about 1,000
/// triangles, blocks of two levels.
fn server() -> StreamServer {
    let (pm, dag) = torus();
    let landmark = Landmark {
        id: 1,
        pm: Arc::new(pm),
        dag: Arc::new(dag),
    };
    StreamServer::bind("127.0.0.1:0", vec![landmark], ServerConfig::default()).unwrap()
}

/// The torus as the `blocks_batch` target's client sees it, and the view it refines for.
fn source() -> (SelectiveSource, View) {
    let (pm, dag) = torus();
    let view = View::new(glam::Vec3::new(0.0, 0.3, 2.0), glam::Vec3::NEG_Z, 1.0).unwrap();
    (SelectiveSource::new(&pm, &dag).unwrap(), view)
}

fn peer() -> SocketAddr {
    SocketAddr::from(([127, 0, 0, 1], 9))
}

/// One input of `target`'s corpus run as the `blocks_batch` target runs it: the blocks
/// taken, or 0 when the first BLOCKS was refused.
fn take_blocks(source: &SelectiveSource, view: &View, mut input: &[u8]) -> usize {
    let mut client = BlockClient::new(source.base(), LEVELS).with_capacity(4);
    let mut taken = 0;
    while let Ok(Some((m, _))) = receive(&mut input, MAX_TO_CLIENT) {
        let Message::Blocks { objects, .. } = m else {
            continue;
        };
        for o in objects.iter().filter(|o| o.index == 0) {
            if client.receive(&o.blocks).is_err() || client.select(view, 0.002).is_err() {
                return taken;
            }
            taken += o.blocks.len();
        }
    }
    taken
}

#[test]
fn every_blocks_batch_of_the_corpus_ends_without_a_panic() {
    let (source, view) = source();
    let inputs = corpus_inputs("blocks_batch").unwrap();
    assert!(inputs.len() > 5, "{} inputs", inputs.len());
    let mut taken = 0;
    for (name, data) in &inputs {
        let got = catch_unwind(AssertUnwindSafe(|| take_blocks(&source, &view, data)));
        taken += got.unwrap_or_else(|_| panic!("blocks_batch/{name} panicked"));
    }
    // The seeds are real sessions: their blocks are taken.
    assert!(taken > 100, "{taken} blocks taken");
}

/// Frame `frame` of a walk in towards the torus and round it, looking at its ring.
fn view(frame: u32) -> ViewPacket {
    let (angle, distance) = (0.4 * frame as f32, 4.0 - 0.4 * frame as f32);
    ViewPacket {
        frame,
        eye: [distance * angle.sin(), 0.3, distance * angle.cos()],
        aim: [angle.sin(), 0.0, angle.cos()],
        tau: 0.02 / (1 + frame) as f32,
        budget_mode: false,
        n: 500,
    }
}

fn hello() -> Hello {
    Hello {
        traversal: Traversal::Priority,
        fov: 1.0,
        budget: None,
        out_of_view: true,
        back_face: true,
        scheme: Scheme::Blocks,
    }
}

fn session(rest: impl IntoIterator<Item = Message>) -> Vec<u8> {
    let mut bytes = Vec::new();
    for m in [Message::Hello(hello())].into_iter().chain(rest) {
        send(&mut bytes, &m).unwrap();
    }
    bytes
}

fn switch(frame: u32, v: &ViewPacket, part: ObjectSwitch) -> Message {
    Message::Switch(Switch {
        frame,
        eye: v.eye,
        aim: v.aim,
        tau: v.tau,
        objects: vec![part],
    })
}

/// The SWITCHes a client of blocks with a cache of `cache` blocks sends over `frames`
/// views of the walk, made in process against a server of blocks as the real pair
/// speaks them.
fn walk_switches(frames: u32, cache: Option<usize>) -> Vec<Message> {
    let (pm, dag) = torus();
    let source = SelectiveSource::new(&pm, &dag).unwrap();
    let mut server = BlockServer::new(&source, LEVELS).unwrap();
    let mut client = BlockClient::new(source.base(), LEVELS);
    if let Some(blocks) = cache {
        client = client.with_capacity(blocks);
    }
    let mut switches = Vec::new();
    for f in 0..frames {
        let v = view(f);
        let eye = glam::Vec3::from(v.eye);
        let local = View::new(eye, glam::Vec3::from(v.aim) - eye, 1.0).unwrap();
        loop {
            let down = client.select(&local, v.tau).unwrap();
            server.release(&source, &down.released).unwrap();
            let done = down.needed.is_empty();
            if down == Default::default() {
                break;
            }
            let tops: Vec<NodeName> = down.needed.iter().chain(&down.ahead).cloned().collect();
            client
                .receive(&server.send(&source, &tops).unwrap())
                .unwrap();
            let frame = switches.len() as u32;
            switches.push(switch(
                frame,
                &v,
                ObjectSwitch {
                    index: 0,
                    down: down.needed,
                    ahead: down.ahead,
                    released: down.released,
                },
            ));
            if done {
                break;
            }
        }
    }
    switches
}

/// Sessions of blocks a client may send, then ones the server refuses.
fn blocks_seed_sessions() -> Vec<(String, Vec<u8>)> {
    let mut seeds = Vec::new();
    let walk = walk_switches(6, None);
    assert!(walk.len() > 3, "{} switches", walk.len());
    seeds.push((
        "blocks-walk".into(),
        session(walk.iter().cloned().chain([Message::Bye])),
    ));
    let cached = walk_switches(8, Some(2));
    let releases = cached
        .iter()
        .filter(|m| matches!(m, Message::Switch(s) if !s.objects[0].released.is_empty()))
        .count();
    assert!(releases > 0, "a cache of 2 blocks released none");
    seeds.push(("blocks-cache".into(), session(cached.iter().cloned())));
    seeds.push(("blocks-hello-bye".into(), session([Message::Bye])));
    let first = match &walk[0] {
        Message::Switch(s) => s.objects[0].clone(),
        _ => unreachable!("a walk of switches"),
    };
    let below_top = NodeName {
        tree: 0,
        node: first.down[0].node.child(true),
    };
    let refused: Vec<(&str, Vec<Message>)> = vec![
        (
            "not-a-top",
            vec![switch(
                0,
                &view(0),
                ObjectSwitch {
                    index: 0,
                    down: vec![below_top],
                    ..Default::default()
                },
            )],
        ),
        (
            "release-unsent",
            vec![switch(
                0,
                &view(0),
                ObjectSwitch {
                    index: 0,
                    released: first.down.clone(),
                    ..Default::default()
                },
            )],
        ),
        (
            "object",
            vec![switch(
                0,
                &view(0),
                ObjectSwitch {
                    index: 1,
                    ..first.clone()
                },
            )],
        ),
        ("frame-order", vec![walk[1].clone(), walk[0].clone()]),
        ("view", vec![Message::View(view(0))]),
    ];
    for (name, rest) in refused {
        seeds.push((format!("refused-blocks-{name}"), session(rest)));
    }
    seeds
}

/// Writes the blocks seeds into the corpora: the sessions for `stream_session`, what
/// the server answered each for `stream_batch` and `blocks_batch`. Run once (and again
/// when the protocol changes), then fuzz and minimise (docs/stream.md, "Fuzzing").
#[test]
#[ignore = "writes the fuzz corpora's seeds"]
fn write_blocks_seeds() {
    let server = server();
    for target in ["stream_session", "stream_batch", "blocks_batch"] {
        fs::create_dir_all(corpus_dir(target)).unwrap();
    }
    for (name, data) in blocks_seed_sessions() {
        let mut answer = Vec::new();
        let end = server.serve(&data[..], &mut answer, peer());
        assert_eq!(
            name.starts_with("refused"),
            end.reason.is_some(),
            "{name}: {:?}",
            end.reason
        );
        fs::write(
            corpus_dir("stream_session").join(format!("seed-{name}")),
            &data,
        )
        .unwrap();
        for target in ["stream_batch", "blocks_batch"] {
            fs::write(corpus_dir(target).join(format!("seed-{name}")), &answer).unwrap();
        }
    }
}
