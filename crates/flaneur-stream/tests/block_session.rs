//! Sessions of El-Sana's view-dependence blocks over real TCP on loopback: the client's
//! meshes against a local refiner's after random views, on a torus and on a building
//! of crease runs, with the server predicting between them; the predicted blocks of a
//! slow walk; and what a session that breaks the protocol gets.

mod common;

use std::io::Write;
use std::net::TcpStream;
use std::time::Duration;

use flaneur::lod::{bumpy_torus, NodeName, SelectiveSource};
use flaneur_stream::protocol::{receive, Message, ObjectSwitch, Switch, MAX_TO_CLIENT};
use flaneur_stream::{
    BlockStreamClient, Hello, Landmark, RunningServer, Scheme, ServerConfig, StreamServer,
    SwitchReport, ViewPacket,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use common::{canonical, hello, landmark, raw_session, refusal, view_of, Local, WAIT};

fn serve(landmarks: &[Landmark], config: ServerConfig) -> RunningServer {
    StreamServer::bind("127.0.0.1:0", landmarks.to_vec(), config)
        .unwrap()
        .spawn()
        .unwrap()
}

fn meshes(client: &BlockStreamClient) -> Vec<Vec<[NodeName; 3]>> {
    client
        .objects()
        .iter()
        .map(|o| canonical(o.triangles()))
        .collect()
}

/// Adds up a session's frame reports.
fn total(reports: &[SwitchReport]) -> SwitchReport {
    reports
        .iter()
        .fold(SwitchReport::default(), |t, r| SwitchReport {
            frame: r.frame,
            splits: t.splits + r.splits,
            collapses: t.collapses + r.collapses,
            released: t.released + r.released,
            bytes: t.bytes + r.bytes,
            blocks: t.blocks + r.blocks,
            predicted_kept: t.predicted_kept + r.predicted_kept,
            predicted_discarded: t.predicted_discarded + r.predicted_discarded,
            round_trips: t.round_trips + r.round_trips,
        })
}

/// `views` random views, each of one of `shapes`, streamed as landmarks in blocks of
/// `levels` levels by a server that predicts after a millisecond's silence, so that its
/// predictions cross the client's SWITCHes, to a client that keeps every block or
/// (`cache`) that many per landmark beyond those in use: after each view every
/// landmark's mesh is a local refiner's, triangle for triangle. The session's figures.
fn blocks_stream_as_a_local_refiner(
    shapes: &[flaneur::scene::Mesh],
    levels: u8,
    cache: Option<usize>,
    views: u32,
    seed: u64,
) -> SwitchReport {
    let landmarks: Vec<Landmark> = shapes
        .iter()
        .enumerate()
        .map(|(i, m)| landmark(7 + i as u64, m))
        .collect();
    let config = ServerConfig {
        block_levels: levels,
        idle: Duration::from_millis(1),
        ..ServerConfig::default()
    };
    let server = serve(&landmarks, config);
    let mut client =
        BlockStreamClient::connect(server.addr(), hello(Scheme::Blocks), WAIT).unwrap();
    if let Some(blocks) = cache {
        client = client.with_capacity(blocks);
    }
    assert_eq!(client.levels(), u32::from(levels));
    let mut local = Local::new(&landmarks);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut reports = Vec::new();
    for step in 0..views {
        let at = rng.gen_range(0..shapes.len());
        let v = view_of(&mut rng, &shapes[at], 100 * step, 500);
        reports.push(client.select(&v).unwrap());
        assert_eq!(meshes(&client), local.select(&v), "step {step}");
    }
    let dropped: usize = client.objects().iter().map(|o| o.dropped()).sum();
    client.bye().unwrap();
    let end = server.ends().recv_timeout(WAIT).unwrap();
    assert_eq!(end.reason, None, "{end:?}");
    let t = total(&reports);
    assert_eq!(t.released, dropped);
    assert_eq!(end.frames, t.round_trips as u64);
    assert!(end.predicted_blocks >= (t.predicted_kept + t.predicted_discarded) as u64);
    t
}

#[test]
fn a_client_of_blocks_over_tcp_holds_a_local_refiners_mesh_of_a_torus() {
    // Two tori side by side. Their few hundred blocks come in a few round trips, most
    // of them asked ahead; the views then refine and coarsen from the blocks held.
    let mut beside = bumpy_torus(1500);
    for p in &mut beside.positions {
        p[0] += 3.0;
    }
    let tori = [bumpy_torus(1500), beside];
    let t = blocks_stream_as_a_local_refiner(&tori, 2, None, 250, 3);
    assert!(t.round_trips >= 5 && t.blocks > 200, "{t:?}");
    assert!(
        t.splits > 10_000 && t.collapses > 10_000 && t.released == 0,
        "{t:?}"
    );
    // With a cache of 4 blocks beyond those in use, the client drops blocks and asks
    // for them again, while predictions cross its releases.
    let t = blocks_stream_as_a_local_refiner(&tori, 2, Some(4), 250, 3);
    assert!(t.released > 200 && t.round_trips > 50, "{t:?}");
}

/// A building: flat-shaded, its splits in crease runs (placed by their leaves).
#[test]
fn a_client_of_blocks_over_tcp_holds_a_local_refiners_mesh_of_a_building() {
    let building = citygen::sample_building(600).unwrap();
    let t = blocks_stream_as_a_local_refiner(std::slice::from_ref(&building), 3, None, 150, 4);
    assert!(
        t.round_trips >= 2 && t.blocks > 100 && t.splits > 5_000,
        "{t:?}"
    );
    let t = blocks_stream_as_a_local_refiner(&[building], 3, Some(4), 150, 4);
    assert!(t.released > 50, "{t:?}");
}

/// A relay between a client and a server that, before the answer to the client's
/// first SWITCH, hands the client `inject` as if the server had sent it. Its address.
fn injecting_relay(server: std::net::SocketAddr, inject: Message) -> std::net::SocketAddr {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap();
    std::thread::spawn(move || {
        let (mut client, _) = listener.accept().unwrap();
        let mut upstream = TcpStream::connect(server).unwrap();
        let (mut from_client, mut to_server) =
            (client.try_clone().unwrap(), upstream.try_clone().unwrap());
        std::thread::spawn(move || std::io::copy(&mut from_client, &mut to_server));
        let mut inject = Some(inject);
        while let Ok(Some((m, _))) = receive(&mut upstream, MAX_TO_CLIENT) {
            if matches!(m, Message::Blocks { .. }) {
                if let Some(first) = inject.take() {
                    client.write_all(&first.encode()).unwrap();
                }
            }
            if client.write_all(&m.encode()).is_err() {
                return;
            }
        }
    });
    addr
}

/// The next message on a raw session of blocks: a BLOCKS' flag and tops (`None` for
/// BLOCKS-WELCOME).
fn next(s: &mut TcpStream) -> (Option<bool>, Vec<NodeName>) {
    match receive(s, MAX_TO_CLIENT).unwrap().unwrap().0 {
        Message::Blocks {
            predicted, objects, ..
        } => (
            Some(predicted),
            objects
                .iter()
                .flat_map(|o| &o.blocks)
                .map(|b| b.top.clone())
                .collect(),
        ),
        Message::BlocksWelcome { .. } => (None, vec![]),
        m => panic!("{m:?}"),
    }
}

/// A prediction that crosses the client's release of the block above it (§6.3, ours):
/// the client discards a predicted block under a block it does not hold, and the server
/// forgets the blocks of its last prediction below a block released. Both sides, each
/// with a crossing made to order.
#[test]
fn a_prediction_crossing_a_release_is_forgotten_on_both_sides() {
    let torus = bumpy_torus(1500);
    let landmarks = [landmark(3, &torus)];
    let source = SelectiveSource::new(&landmarks[0].pm, &landmarks[0].dag).unwrap();
    let h = source.hierarchy();
    // The client's side: a block two levels down, under a root block the client does
    // not hold, comes predicted before the first answer.
    let deep = (0..h.len() as u32)
        .find(|&n| h.parent(n).is_some_and(|p| h.parent(p).is_some()) && h.children(n).is_some())
        .map(|n| h.name(h.block_top(n, 2)))
        .unwrap();
    let mut blocks = flaneur::lod::BlockServer::new(&source, 2).unwrap();
    let orphan = blocks
        .send(&source, std::slice::from_ref(&deep))
        .unwrap()
        .pop()
        .unwrap();
    assert_eq!(orphan.top, deep);
    let inject = Message::Blocks {
        frame: 9,
        predicted: true,
        objects: vec![flaneur_stream::protocol::ObjectBlocks {
            index: 0,
            blocks: vec![orphan],
        }],
    };
    let server = serve(&landmarks, ServerConfig::default());
    let relay = injecting_relay(server.addr(), inject);
    let mut client = BlockStreamClient::connect(relay, hello(Scheme::Blocks), WAIT).unwrap();
    let mut local = Local::new(&landmarks);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for step in 0..20 {
        let v = view_of(&mut rng, &torus, 10 + 100 * step, 500);
        let r = client.select(&v).unwrap();
        if step == 0 {
            // The server's own predictions, if any came, are all taken.
            assert_eq!(r.predicted_discarded, 1, "{r:?}");
        }
        assert_eq!(meshes(&client), local.select(&v), "step {step}");
    }
    assert_eq!(client.objects()[0].discarded(), 1);
    client.bye().unwrap();
    assert_eq!(server.ends().recv_timeout(WAIT).unwrap().reason, None);

    // The server's side, spoken by hand: root blocks asked for, then silence until a
    // prediction comes with blocks under them.
    let config = ServerConfig {
        idle: Duration::from_millis(5),
        predict_blocks: 64,
        ..ServerConfig::default()
    };
    let server = serve(&landmarks, config);
    let mut s = raw_session(&server, hello(Scheme::Blocks));
    let roots: Vec<NodeName> = (0..h.len() as u32)
        .filter(|&n| h.parent(n).is_none() && h.children(n).is_some())
        .map(|n| h.name(n))
        .collect();
    s.write_all(&switch(0, 0, roots, vec![]).encode()).unwrap();
    assert!(matches!(next(&mut s), (None, _)), "BLOCKS-WELCOME first");
    let (Some(false), answer) = next(&mut s) else {
        panic!("no answer")
    };
    let (Some(true), predicted) = next(&mut s) else {
        panic!("no prediction")
    };
    // A root block with predicted blocks right under it, and no answered one.
    let parent = |t: &NodeName| flaneur::lod::block_of(&t.up(1), 2);
    let released = predicted
        .iter()
        .filter(|t| t.depth() > 0)
        .map(parent)
        .find(|x| answer.contains(x) && !answer.iter().any(|a| a.depth() > 0 && parent(a) == *x))
        .expect("a prediction under an answered root block");
    let under: Vec<NodeName> = predicted
        .iter()
        .filter(|t| t.depth() > 0 && parent(t) == released)
        .cloned()
        .collect();
    // Released as if the prediction had not come: the server forgets the blocks under
    // it too, and sends them again, after it, when asked.
    s.write_all(&switch(1, 0, vec![], vec![released.clone()]).encode())
        .unwrap();
    assert_eq!(next(&mut s), (Some(false), vec![]));
    s.write_all(&switch(2, 0, under.clone(), vec![]).encode())
        .unwrap();
    let (_, again) = next(&mut s);
    assert_eq!(again[0], released);
    assert!(under.iter().all(|u| again.contains(u)), "{again:?}");
    s.write_all(&Message::Bye.encode()).unwrap();
    assert_eq!(server.ends().recv_timeout(WAIT).unwrap().reason, None);
}

/// A slow orbit close round the torus, the client pausing longer than the server's idle
/// time after each frame: the server predicts from the last two SWITCHes and sends blocks
/// unasked, which the client takes (or discards, held already) by their names, and its
/// mesh stays the local refiner's.
#[test]
fn a_slow_walk_is_sent_predicted_blocks_which_the_client_takes_by_name() {
    let torus = bumpy_torus(1500);
    let landmarks = [landmark(3, &torus)];
    let config = ServerConfig {
        idle: Duration::from_millis(15),
        predict_blocks: 8,
        ..ServerConfig::default()
    };
    let server = serve(&landmarks, config);
    let mut client =
        BlockStreamClient::connect(server.addr(), hello(Scheme::Blocks), WAIT).unwrap();
    let mut local = Local::new(&landmarks);
    let mut reports = Vec::new();
    for step in 0..40 {
        let a = 0.06 * step as f32;
        let v = ViewPacket {
            frame: step,
            eye: [1.6 * a.cos(), 0.5, 1.6 * a.sin()],
            aim: [0.8 * (a + 0.4).cos(), 0.0, 0.8 * (a + 0.4).sin()],
            tau: 0.001,
            budget_mode: false,
            n: 500,
        };
        reports.push(client.select(&v).unwrap());
        assert_eq!(meshes(&client), local.select(&v), "step {step}");
        std::thread::sleep(Duration::from_millis(45));
    }
    let t = total(&reports);
    assert!(t.predicted_kept + t.predicted_discarded > 0, "{t:?}");
    client.bye().unwrap();
    let end = server.ends().recv_timeout(WAIT).unwrap();
    assert_eq!(end.reason, None, "{end:?}");
    assert!(end.predicted_blocks >= (t.predicted_kept + t.predicted_discarded) as u64);
    // With no idle time the server never predicts.
    let quiet = serve(
        &landmarks,
        ServerConfig {
            idle: Duration::ZERO,
            ..config
        },
    );
    let mut client = BlockStreamClient::connect(quiet.addr(), hello(Scheme::Blocks), WAIT).unwrap();
    for step in 0..5 {
        let v = ViewPacket {
            frame: step,
            eye: [0.4, 0.3, 3.0 - 0.2 * step as f32],
            aim: [0.0; 3],
            tau: 0.002,
            budget_mode: false,
            n: 500,
        };
        let r = client.select(&v).unwrap();
        assert_eq!(r.predicted_kept + r.predicted_discarded, 0, "{r:?}");
        std::thread::sleep(Duration::from_millis(20));
    }
    client.bye().unwrap();
    assert_eq!(quiet.ends().recv_timeout(WAIT).unwrap().predicted_blocks, 0);
}

/// A SWITCH of frame `frame` naming, for object `index`, `down` and `released`.
fn switch(frame: u32, index: u32, down: Vec<NodeName>, released: Vec<NodeName>) -> Message {
    Message::Switch(Switch {
        frame,
        eye: [0.0, 0.0, 3.0],
        aim: [0.0; 3],
        tau: 0.002,
        objects: vec![ObjectSwitch {
            index,
            down,
            ahead: vec![],
            released,
        }],
    })
}

/// Each bad message closes its own session with the reason, logged, and a session of
/// blocks beside it goes on.
#[test]
fn bad_sessions_of_blocks_are_refused_by_name_and_others_go_on() {
    let torus = bumpy_torus(1500);
    let landmarks = [landmark(3, &torus)];
    let server = serve(&landmarks, ServerConfig::default());
    let source = SelectiveSource::new(&landmarks[0].pm, &landmarks[0].dag).unwrap();
    let h = source.hierarchy();
    // A root that splits: a block's top (depth 0); its child, at depth 1, is none with
    // blocks of 2 levels.
    let root = (0..h.len() as u32)
        .find(|&n| h.parent(n).is_none() && h.children(n).is_some())
        .unwrap();
    let (top, below) = (h.name(root), h.name(h.children(root).unwrap()[0]));
    let mut good = BlockStreamClient::connect(server.addr(), hello(Scheme::Blocks), WAIT).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let blocks = hello(Scheme::Blocks);
    let cases: Vec<(Hello, Vec<Message>, &str)> = vec![
        (
            blocks,
            vec![switch(0, 0, vec![below.clone()], vec![])],
            "is no block's top",
        ),
        (
            blocks,
            vec![switch(0, 0, vec![], vec![top.clone()])],
            "was not sent",
        ),
        (
            blocks,
            vec![
                switch(4, 0, vec![top.clone()], vec![]),
                switch(4, 0, vec![top.clone()], vec![]),
            ],
            "SWITCH of frame 4 after frame 4: frames must increase",
        ),
        (
            blocks,
            vec![switch(0, 3, vec![top.clone()], vec![])],
            "object 3, not in WELCOME's 1",
        ),
        (
            blocks,
            vec![Message::View(view_of(&mut rng, &torus, 0, 500))],
            "VIEW in a session of blocks: it sends SWITCH",
        ),
        (
            blocks,
            vec![Message::Resume {
                next_frame: 0,
                objects: vec![],
            }],
            "RESUME where SWITCH or BYE was due",
        ),
        (
            hello(Scheme::Selective),
            vec![switch(0, 0, vec![top.clone()], vec![])],
            "SWITCH outside a session of blocks",
        ),
        (
            Hello {
                back_face: false,
                ..blocks
            },
            vec![],
            "without both criteria",
        ),
    ];
    let mut frame = 0;
    for (hello, messages, why) in cases {
        let mut s = raw_session(&server, hello);
        for m in &messages {
            s.write_all(&m.encode()).unwrap();
        }
        let said = refusal(&mut s);
        assert!(said.contains(why), "{said}");
        let end = server.ends().recv_timeout(WAIT).unwrap();
        assert!(end.reason.unwrap().contains(why));
        // The good session beside it goes on.
        frame += 100;
        good.select(&view_of(&mut rng, &torus, frame, 500))
            .unwrap_or_else(|e| panic!("after {why}: {e}"));
    }
    // A client of blocks speaks no other scheme.
    let e = BlockStreamClient::connect(server.addr(), hello(Scheme::Selective), WAIT).unwrap_err();
    assert!(e.to_string().contains("speaks the blocks scheme"), "{e}");
    good.bye().unwrap();
    // A session of blocks that says nothing is closed when idle, as any other.
    let strict = serve(
        &landmarks,
        ServerConfig {
            idle_timeout: Duration::from_millis(300),
            ..ServerConfig::default()
        },
    );
    let said = refusal(&mut raw_session(&strict, blocks));
    assert!(said.contains("idle for 300ms"), "{said}");
    assert_eq!(strict.ends().recv_timeout(WAIT).unwrap().frames, 0);
}
