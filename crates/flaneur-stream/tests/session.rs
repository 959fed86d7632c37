//! Stream sessions over real TCP on loopback: the client's meshes against a local
//! refiner's, and what a session that breaks the protocol gets.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::sync::Arc;
use std::time::Duration;

use flaneur::lod::{
    bumpy_torus, Criteria, Dag, DagConstruction, ProgressiveMesh, RefineParams, Refiner, Traversal,
    View,
};
use flaneur_stream::protocol::{receive, Message, MAX_N, MAX_TO_CLIENT};
use flaneur_stream::{
    HeldNodes, Hello, Landmark, RunningServer, ServerConfig, StreamClient, StreamError,
    StreamServer, ViewPacket,
};
use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const FOV: f32 = 1.0;
const BUDGET: u32 = 6_000;

/// Two landmarks: the bunny, and a bumpy torus beside it.
fn landmarks() -> Vec<Landmark> {
    let mut torus = bumpy_torus(20_000);
    for p in &mut torus.positions {
        p[0] += 3.0;
    }
    [flaneur::scene::bunny(), torus]
        .into_iter()
        .enumerate()
        .map(|(i, mesh)| {
            let pm = ProgressiveMesh::build(&mesh).unwrap();
            let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
            Landmark {
                id: 10 + i as u64,
                pm: Arc::new(pm),
                dag: Arc::new(dag),
            }
        })
        .collect()
}

fn serve(landmarks: &[Landmark], config: ServerConfig) -> RunningServer {
    StreamServer::bind("127.0.0.1:0", landmarks.to_vec(), config)
        .unwrap()
        .spawn()
        .unwrap()
}

fn hello(traversal: Traversal) -> Hello {
    Hello {
        traversal,
        fov: FOV,
        budget: Some(BUDGET),
        out_of_view: true,
        back_face: true,
        scheme: flaneur_stream::Scheme::Dag,
    }
}

/// Views from anywhere around the two objects, at any τ, mode and N.
fn random_views(seed: u64, frames: u32) -> Vec<ViewPacket> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..frames)
        .map(|frame| {
            let at = |rng: &mut ChaCha8Rng, r: f32| {
                [
                    rng.gen_range(-r..r) + 1.5,
                    rng.gen_range(-r..r),
                    rng.gen_range(-r..r),
                ]
            };
            ViewPacket {
                frame: 2 * frame + rng.gen_range(0..2),
                eye: at(&mut rng, 6.0),
                aim: at(&mut rng, 1.5),
                tau: 10f32.powf(rng.gen_range(-4.0..-2.0)),
                budget_mode: rng.gen_bool(0.7),
                n: rng.gen_range(1..=MAX_N),
            }
        })
        .collect()
}

/// What a local refiner does with `v` under `h`.
fn params(h: &Hello, v: &ViewPacket) -> (View, RefineParams) {
    let eye = Vec3::from(v.eye);
    let view = View::new(eye, Vec3::from(v.aim) - eye, h.fov).unwrap();
    let params = RefineParams {
        traversal: h.traversal,
        tau: v.tau,
        budget: v.budget_mode.then_some(BUDGET as usize),
        max_work: v.n as usize,
        criteria: Criteria {
            out_of_view: h.out_of_view,
            back_face: h.back_face,
        },
    };
    (view, params)
}

#[test]
fn after_random_views_each_client_mesh_is_the_local_refiners_triangle_for_triangle() {
    let landmarks = landmarks();
    let server = serve(&landmarks, ServerConfig::default());
    for (seed, traversal) in Traversal::ALL.into_iter().enumerate() {
        let h = hello(traversal);
        let mut client = StreamClient::connect(server.addr(), h, Duration::from_secs(20)).unwrap();
        let ids: Vec<u64> = client.objects().iter().map(|o| o.id).collect();
        assert_eq!(ids, [10, 11]);
        let mut local: Vec<Refiner> = landmarks
            .iter()
            .map(|l| Refiner::new(&l.pm, &l.dag).unwrap())
            .collect();
        let (mut splits, mut collapses, mut largest) = (0, 0, 0);
        for v in random_views(seed as u64, 400) {
            client.send_view(&v).unwrap();
            let batch = client.receive_batch().unwrap();
            largest = largest.max(batch.largest_object);
            (splits, collapses) = (splits + batch.splits, collapses + batch.collapses);
            let (view, p) = params(&h, &v);
            for (refiner, streamed) in local.iter_mut().zip(client.objects()) {
                refiner.refine(&view, &p).unwrap();
                let (mine, theirs) = (refiner.mesh(), streamed.mesh());
                assert_eq!(
                    mine.triangle_count(),
                    theirs.triangle_count(),
                    "frame {}",
                    v.frame
                );
                assert_eq!(theirs.shared_with(mine), 1.0, "frame {}", v.frame);
            }
        }
        // Each object's part of a batch within Zheng's 64 KiB at N up to 500.
        assert!(largest <= 64 << 10, "an object's part of {largest} bytes");
        // The views moved both ways through the hierarchy.
        assert!(
            splits > 1000 && collapses > 1000,
            "{splits} splits, {collapses} collapses"
        );
        client.bye().unwrap();
    }
    // Each session ended at the client's word, every view answered.
    for _ in Traversal::ALL {
        let end = server.ends().recv_timeout(Duration::from_secs(10)).unwrap();
        assert_eq!((end.frames, end.reason), (400, None));
    }
}

/// A client whose connection breaks, a batch lost with it, reconnects and resumes: the
/// new session goes on from the meshes the client holds, and they stay, frame by frame
/// and triangle for triangle, those of a local refiner restored from the same nodes and
/// sent the same views.
#[test]
fn a_reconnect_resumes_to_the_same_mesh() {
    let landmarks = landmarks();
    let server = serve(&landmarks, ServerConfig::default());
    for (seed, traversal) in Traversal::ALL.into_iter().enumerate() {
        let h = hello(traversal);
        let mut client = StreamClient::connect(server.addr(), h, Duration::from_secs(20)).unwrap();
        let views = random_views(20 + seed as u64, 240);
        for v in &views[..80] {
            client.send_view(v).unwrap();
            client.receive_batch().unwrap();
        }
        // The server answers view 80, but its batch never reaches the client.
        client.send_view(&views[80]).unwrap();
        let before: Vec<_> = client.objects().iter().map(|o| o.mesh().clone()).collect();
        let held: Vec<Vec<u32>> = client.objects().iter().map(|o| o.held_nodes()).collect();
        assert!(
            held.iter().all(|h| h.len() > 10),
            "{traversal:?}: little held"
        );
        client.reconnect().unwrap();
        // Reconnecting changes nothing the client holds.
        for (o, mesh) in client.objects().iter().zip(&before) {
            assert_eq!(o.mesh().shared_with(mesh), 1.0);
            assert_eq!(o.mesh().triangle_count(), mesh.triangle_count());
        }
        let mut local: Vec<Refiner> = landmarks
            .iter()
            .zip(&held)
            .map(|(l, nodes)| {
                let mut r = Refiner::new(&l.pm, &l.dag).unwrap();
                r.restore(nodes).unwrap();
                r
            })
            .collect();
        let (mut splits, mut collapses) = (0, 0);
        for v in &views[81..] {
            client.send_view(v).unwrap();
            let batch = client.receive_batch().unwrap();
            (splits, collapses) = (splits + batch.splits, collapses + batch.collapses);
            let (view, p) = params(&h, v);
            for (refiner, streamed) in local.iter_mut().zip(client.objects()) {
                refiner.refine(&view, &p).unwrap();
                let (mine, theirs) = (refiner.mesh(), streamed.mesh());
                assert_eq!(
                    mine.triangle_count(),
                    theirs.triangle_count(),
                    "{traversal:?} frame {}",
                    v.frame
                );
                assert_eq!(
                    theirs.shared_with(mine),
                    1.0,
                    "{traversal:?} frame {}",
                    v.frame
                );
            }
        }
        assert!(
            splits > 100 && collapses > 100,
            "{splits} splits, {collapses} collapses"
        );
        // A frame at or below the one lost is refused: frames go on increasing.
        let stale = ViewPacket {
            frame: views[80].frame,
            ..views[0]
        };
        client.send_view(&stale).unwrap();
        match client.receive_batch() {
            Err(StreamError::Refused(why)) => assert!(why.contains("must increase"), "{why}"),
            other => panic!("{other:?}"),
        }
    }
    // Each traversal's two sessions: the first ended by the broken connection, having
    // answered the 80 views whose batches came and perhaps the lost one (its batch
    // may meet the closed connection); the second refused at the stale frame.
    let ends: Vec<_> = (0..2 * Traversal::ALL.len())
        .map(|_| server.ends().recv_timeout(Duration::from_secs(10)).unwrap())
        .collect();
    let (second, first): (Vec<_>, Vec<_>) = ends.iter().partition(|e| e.frames > 100);
    assert_eq!(first.len(), Traversal::ALL.len());
    assert!(
        first.iter().all(|e| (80..=81).contains(&e.frames)),
        "{first:?}"
    );
    for e in second {
        assert_eq!(e.frames, 159);
        assert!(e
            .reason
            .as_ref()
            .is_some_and(|r| r.contains("must increase")));
    }
}

/// Sends `bytes` on a new connection and reads what comes back until the server closes:
/// the REFUSED reason, if one came.
fn refusal_of(server: &RunningServer, bytes: &[u8]) -> Option<String> {
    let mut s = TcpStream::connect(server.addr()).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    s.write_all(bytes).unwrap();
    let mut reason = None;
    while let Ok(Some((m, _))) = receive(&mut s, MAX_TO_CLIENT) {
        if let Message::Refused(why) = m {
            reason = Some(why);
        }
    }
    reason
}

#[test]
fn a_session_that_breaks_the_protocol_is_closed_with_its_reason_and_no_other_notices() {
    let landmarks = landmarks();
    let server = serve(&landmarks, ServerConfig::default());
    let h = hello(Traversal::Linear);
    let mut good = StreamClient::connect(server.addr(), h, Duration::from_secs(20)).unwrap();
    let mut local: Vec<Refiner> = landmarks
        .iter()
        .map(|l| Refiner::new(&l.pm, &l.dag).unwrap())
        .collect();
    let views = random_views(7, 72);
    let hello_bytes = Message::Hello(h).encode();
    let view = |frame: u32| Message::View(ViewPacket { frame, ..views[0] }).encode();
    let resume = |index: u32, nodes: Vec<u32>| {
        Message::Resume {
            next_frame: 0,
            objects: vec![HeldNodes { index, nodes }],
        }
        .encode()
    };
    let dag = &landmarks[0].dag;
    let below_a_root = (0..dag.node_count() as u32)
        .find(|&n| !dag.parents(n).is_empty())
        .unwrap();
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (b"GET / HTTP/1.1\r\n\r\n".to_vec(), "above the 4096"),
        (vec![3, 0, 0, 0, 0x55, 1, 2], "kind 0x55"),
        (view(1), "VIEW where HELLO was due"),
        (
            [hello_bytes.clone(), view(5), view(5)].concat(),
            "frames must increase",
        ),
        (
            [hello_bytes.clone(), hello_bytes.clone()].concat(),
            "HELLO where VIEW",
        ),
        (
            [hello_bytes.clone(), {
                let mut v = view(1);
                v[9..13].copy_from_slice(&f32::INFINITY.to_le_bytes());
                v
            }]
            .concat(),
            "not finite",
        ),
        (
            [
                hello_bytes.clone(),
                Message::View(ViewPacket { n: 0, ..views[0] }).encode(),
            ]
            .concat(),
            "N = 0",
        ),
        (resume(0, vec![]), "RESUME where HELLO was due"),
        (
            [hello_bytes.clone(), view(1), resume(0, vec![])].concat(),
            "RESUME where VIEW or BYE was due",
        ),
        (
            [hello_bytes.clone(), resume(2, vec![])].concat(),
            "object 2, not in WELCOME",
        ),
        (
            [
                hello_bytes.clone(),
                resume(0, vec![dag.node_count() as u32]),
            ]
            .concat(),
            "past the DAG",
        ),
        (
            [hello_bytes.clone(), resume(0, vec![below_a_root])].concat(),
            "is named split but its parent",
        ),
    ];
    for (i, (bytes, why)) in cases.iter().enumerate() {
        let said = refusal_of(&server, bytes).unwrap_or_else(|| panic!("case {i}: no REFUSED"));
        assert!(said.contains(why), "case {i}: {said}");
        // The good session goes on as before, between the bad ones.
        for v in &views[i * 6..i * 6 + 6] {
            good.send_view(v).unwrap();
            good.receive_batch().unwrap();
            let (view, p) = params(&h, v);
            for (refiner, streamed) in local.iter_mut().zip(good.objects()) {
                refiner.refine(&view, &p).unwrap();
                assert_eq!(streamed.mesh().shared_with(refiner.mesh()), 1.0);
                assert_eq!(
                    streamed.mesh().triangle_count(),
                    refiner.mesh().triangle_count()
                );
            }
        }
    }
    // The server's log names each bad session's reason.
    let reasons: Vec<String> = (0..cases.len())
        .map(|_| {
            let end = server.ends().recv_timeout(Duration::from_secs(10)).unwrap();
            end.reason.expect("a bad session ended with a reason")
        })
        .collect();
    for (_, why) in &cases {
        assert!(
            reasons.iter().any(|r| r.contains(why)),
            "{why} not in {reasons:?}"
        );
    }
}

#[test]
fn a_session_that_says_nothing_is_closed_when_idle() {
    let server = serve(
        &landmarks()[..1],
        ServerConfig {
            idle_timeout: Duration::from_millis(300),
            ..ServerConfig::default()
        },
    );
    let said = refusal_of(&server, &Message::Hello(hello(Traversal::Linear)).encode());
    assert!(said.is_some_and(|s| s.contains("idle for 300ms")));
    let end = server.ends().recv_timeout(Duration::from_secs(10)).unwrap();
    assert_eq!(end.frames, 0);
}

#[test]
fn a_client_refuses_a_batch_that_does_not_fit_its_mesh() {
    // A server of our own that answers with a collapse of a node never split.
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap();
    let landmarks = landmarks();
    let welcome = Message::Welcome(vec![flaneur_stream::protocol::WelcomeObject {
        id: 1,
        splits: landmarks[0].pm.splits.len() as u32,
        base: landmarks[0].pm.base.clone(),
    }]);
    std::thread::spawn(move || {
        let (mut s, _) = listener.accept().unwrap();
        let mut buf = [0u8; 25];
        s.read_exact(&mut buf).unwrap();
        s.write_all(&welcome.encode()).unwrap();
        let mut view = [0u8; 42];
        s.read_exact(&mut view).unwrap();
        let batch = Message::Batch {
            frame: 0,
            objects: vec![flaneur_stream::protocol::ObjectUpdates {
                index: 0,
                collapses: vec![3],
                splits: vec![],
            }],
        };
        s.write_all(&batch.encode()).unwrap();
    });
    let mut client =
        StreamClient::connect(addr, hello(Traversal::Priority), Duration::from_secs(10)).unwrap();
    client
        .send_view(&ViewPacket {
            frame: 0,
            ..random_views(1, 1)[0]
        })
        .unwrap();
    match client.receive_batch() {
        Err(StreamError::Malformed(why)) => assert!(why.contains("never split"), "{why}"),
        other => panic!("{other:?}"),
    }
}

/// A client that sends views and never reads their batches stalls only its own
/// session: another client is served meanwhile, view for view, and the stalled one is
/// closed once its batches have filled the connection for the idle timeout.
#[test]
fn a_stalled_client_holds_back_no_other_and_is_closed() {
    let landmarks = landmarks();
    let server = serve(
        &landmarks,
        ServerConfig {
            idle_timeout: Duration::from_millis(500),
            ..ServerConfig::default()
        },
    );
    let h = hello(Traversal::Priority);
    // The stalled client: HELLO and thousands of views on a thread of its own (its
    // writes block once the server stops reading), never a read.
    let stalled = TcpStream::connect(server.addr()).unwrap();
    let mut writer = stalled.try_clone().unwrap();
    let writes = std::thread::spawn(move || {
        let mut bytes = Message::Hello(h).encode();
        for (frame, v) in random_views(31, 4000).into_iter().enumerate() {
            let v = ViewPacket {
                frame: frame as u32,
                tau: 1e-4,
                budget_mode: false,
                n: MAX_N,
                ..v
            };
            bytes.extend(Message::View(v).encode());
        }
        let _ = writer.write_all(&bytes);
    });
    // Meanwhile a good client is served, its meshes the local refiner's.
    let mut good = StreamClient::connect(server.addr(), h, Duration::from_secs(20)).unwrap();
    let mut local: Vec<Refiner> = landmarks
        .iter()
        .map(|l| Refiner::new(&l.pm, &l.dag).unwrap())
        .collect();
    for v in random_views(32, 60) {
        good.send_view(&v).unwrap();
        good.receive_batch().unwrap();
        let (view, p) = params(&h, &v);
        for (refiner, streamed) in local.iter_mut().zip(good.objects()) {
            refiner.refine(&view, &p).unwrap();
            assert_eq!(streamed.mesh().shared_with(refiner.mesh()), 1.0);
        }
    }
    good.bye().unwrap();
    let ends: Vec<_> = (0..2)
        .map(|_| server.ends().recv_timeout(Duration::from_secs(30)).unwrap())
        .collect();
    let stalled_end = ends.iter().find(|e| e.reason.is_some()).expect("closed");
    let why = stalled_end.reason.as_ref().unwrap();
    assert!(why.contains("not reading for 500ms"), "{why}");
    assert!(
        stalled_end.frames > 0 && stalled_end.frames < 4000,
        "{stalled_end:?}"
    );
    assert!(ends.iter().any(|e| e.frames == 60 && e.reason.is_none()));
    drop(stalled);
    writes.join().unwrap();
}

/// A relay from a port of its own to a server, whose connections can be cut.
struct Relay {
    addr: std::net::SocketAddr,
    open: Arc<std::sync::Mutex<Vec<TcpStream>>>,
}

impl Relay {
    fn to(server: std::net::SocketAddr) -> Relay {
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap();
        let open = Arc::new(std::sync::Mutex::new(Vec::new()));
        let kept = open.clone();
        std::thread::spawn(move || {
            for client in listener.incoming().flatten() {
                let Ok(upstream) = TcpStream::connect(server) else {
                    return;
                };
                let pipe = |mut from: TcpStream, mut to: TcpStream| {
                    std::thread::spawn(move || {
                        let _ = std::io::copy(&mut from, &mut to);
                        let _ = to.shutdown(std::net::Shutdown::Both);
                    });
                };
                let mut open = kept.lock().unwrap();
                open.extend([client.try_clone().unwrap(), upstream.try_clone().unwrap()]);
                pipe(client.try_clone().unwrap(), upstream.try_clone().unwrap());
                pipe(upstream, client);
            }
        });
        Relay { addr, open }
    }

    /// Cuts every connection it relays, as a network that drops them.
    fn cut(&self) {
        for c in self.open.lock().unwrap().drain(..) {
            let _ = c.shutdown(std::net::Shutdown::Both);
        }
    }
}

/// A walk's stream session whose connection is cut goes on: the landmarks stay drawn
/// as they stood, the client reconnects and resumes from the meshes it holds, batches
/// come again, and each mesh is still the one the nodes it holds split make.
#[test]
fn a_walks_stream_session_survives_a_cut_connection() {
    use flaneur::walk::RemoteRefinements;
    use flaneur_stream::{Predictor, Refinement, StreamedLandmarks};
    let landmarks = landmarks();
    let server = serve(&landmarks, ServerConfig::default());
    let relay = Relay::to(server.addr());
    let refinement = Refinement {
        tau: 0.001,
        n: MAX_N,
        initial_span: 1,
        predictor: Predictor::Linear,
    };
    let client = flaneur_stream::PredictiveClient::connect(
        relay.addr,
        hello(Traversal::Priority),
        refinement,
        Duration::from_secs(20),
    )
    .unwrap();
    let (mut walk, figures) = StreamedLandmarks::new(client);
    let camera = |frame: usize| {
        // Round the two objects, looking at them.
        let a = frame as f32 * 0.05;
        let eye = Vec3::new(1.5 + 4.0 * a.cos(), 0.5, 4.0 * a.sin());
        let to = Vec3::new(1.5, 0.0, 0.0) - eye;
        flaneur::geom::Camera::new(eye, to.z.atan2(to.x), (to.y / to.length()).asin()).unwrap()
    };
    let mut modified_at_cut = 0;
    for frame in 0..160 {
        if frame == 40 {
            modified_at_cut = figures.lock().unwrap().modified;
            relay.cut();
        }
        walk.frame(&camera(frame)).unwrap();
        std::thread::sleep(Duration::from_millis(10));
    }
    let f = figures.lock().unwrap().clone();
    assert!(modified_at_cut > 10, "{f:?}");
    assert!(f.reconnects >= 1, "{f:?}");
    assert!(f.broken_frames >= 1 && f.last_failure.is_some(), "{f:?}");
    assert!(
        f.modified > modified_at_cut + 10,
        "no batches after the cut: {f:?}"
    );
    assert!(walk.status().unwrap().starts_with("round trip"));
    for (l, o) in landmarks.iter().zip(walk.client().objects()) {
        let mut r = Refiner::new(&l.pm, &l.dag).unwrap();
        r.restore(&o.held_nodes()).unwrap();
        assert_eq!(o.mesh().triangle_count(), r.mesh().triangle_count());
        assert_eq!(o.mesh().shared_with(r.mesh()), 1.0);
    }
}
