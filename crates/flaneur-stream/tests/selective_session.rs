//! Truly selective sessions (Kim–Lee–Kobbelt) over real TCP on loopback: the client's
//! meshes against a local refiner's after random views, on tori and on a building of
//! crease runs, a resume on a new connection, and what a session that breaks the
//! protocol gets.

mod common;

use std::io::Write;

use flaneur::lod::{bumpy_torus, NodeName, SelectiveServer, SelectiveSource};
use flaneur_stream::protocol::Message;
use flaneur_stream::{
    HeldLeaves, Landmark, RunningServer, Scheme, SelectiveStreamClient, ServerConfig, StreamServer,
    ViewPacket,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use common::{canonical, hello, landmark, local_view, raw_session, refusal, view_of, Local, WAIT};

/// Two landmarks without crease runs: bumpy tori of 2,000 and 3,000 triangles, side
/// by side (a local refiner's reference fronts cost the square of a mesh's size).
fn landmarks() -> Vec<Landmark> {
    [(0.0, 2_000), (3.0, 3_000)]
        .into_iter()
        .enumerate()
        .map(|(i, (x, triangles))| {
            let mut torus = bumpy_torus(triangles);
            for p in &mut torus.positions {
                p[0] += x;
            }
            landmark(10 + i as u64, &torus)
        })
        .collect()
}

fn serve(landmarks: &[Landmark]) -> RunningServer {
    StreamServer::bind("127.0.0.1:0", landmarks.to_vec(), ServerConfig::default())
        .unwrap()
        .spawn()
        .unwrap()
}

/// A random view of the two landmarks, looking near the middle of one.
fn random_view(rng: &mut ChaCha8Rng, frame: u32, n: u32) -> ViewPacket {
    let at = if rng.gen_bool(0.5) { 0.0 } else { 3.0 };
    let eye = [
        at + rng.gen_range(-2.5..2.5),
        rng.gen_range(-1.5..1.5),
        rng.gen_range(-2.5..2.5),
    ];
    ViewPacket {
        frame,
        eye,
        aim: [
            at + rng.gen_range(-0.3..0.3),
            rng.gen_range(-0.2..0.2),
            rng.gen_range(-0.3..0.3),
        ],
        tau: rng.gen_range(0.0005..0.005),
        budget_mode: false,
        n,
    }
}

fn meshes(client: &SelectiveStreamClient) -> Vec<Vec<[NodeName; 3]>> {
    client
        .objects()
        .iter()
        .map(|o| canonical(o.triangles()))
        .collect()
}

/// Random views, each asked for until the client holds what it wants, at an N of 10
/// so that most take several round trips; a reconnect halfway. After each view the
/// client's meshes are the local refiner's, triangle for triangle.
#[test]
fn a_selective_client_over_tcp_holds_a_local_refiners_mesh_and_resumes_to_it() {
    let landmarks = landmarks();
    let server = serve(&landmarks);
    let mut client =
        SelectiveStreamClient::connect(server.addr(), hello(Scheme::Selective), WAIT).unwrap();
    let mut local = Local::new(&landmarks);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let (mut rounds, mut frame, mut split_views) = (0, 0, 0);
    for step in 0..120 {
        if step == 60 {
            client.reconnect().unwrap();
        }
        let v = random_view(&mut rng, frame, 10);
        let took = client.refine(&v).unwrap();
        rounds += took;
        split_views += usize::from(took > 1);
        frame += 1000;
        assert_eq!(meshes(&client), local.select(&v), "step {step}");
    }
    assert!(
        split_views > 10,
        "{split_views} views took more than one round trip: N = 10 should split more"
    );
    client.bye().unwrap();
    let ends: Vec<_> = (0..2)
        .map(|_| server.ends().recv_timeout(WAIT).unwrap())
        .collect();
    for end in &ends {
        assert_eq!(end.reason, None, "{end:?}");
    }
    // The first session's frames and the resumed one's add up to every round trip.
    assert_eq!(ends.iter().map(|e| e.frames).sum::<u64>(), rounds as u64);
}

/// KLK §7: the client makes each split as it comes; after each view its meshes are
/// the front a local cut-vertex-only server sent, and a resume goes on from them.
#[test]
fn a_cut_vertex_client_over_tcp_holds_the_sent_front_and_resumes_to_it() {
    let landmarks = landmarks();
    let server = serve(&landmarks);
    let mut client =
        SelectiveStreamClient::connect(server.addr(), hello(Scheme::CutVertex), WAIT).unwrap();
    let sources: Vec<SelectiveSource> = landmarks
        .iter()
        .map(|l| SelectiveSource::new(&l.pm, &l.dag).unwrap())
        .collect();
    let mut sent: Vec<SelectiveServer> = sources
        .iter()
        .map(|s| SelectiveServer::new(s).cut_vertex_only())
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let mut splits = 0;
    for step in 0..60 {
        if step == 30 {
            client.reconnect().unwrap();
        }
        let v = random_view(&mut rng, step, 500);
        client.send_view(&v).unwrap();
        splits += client.receive_batch().unwrap().splits;
        for (k, (source, server)) in sources.iter().zip(&mut sent).enumerate() {
            server
                .refine_at_most(source, &local_view(&v), v.tau, 500)
                .unwrap();
            assert_eq!(
                canonical(client.objects()[k].triangles()),
                canonical(server.sent_triangles(source)),
                "step {step}, landmark {k}"
            );
        }
    }
    assert!(splits > 200, "{splits}");
}

/// Each bad message closes its own session with the reason, logged, and a session
/// beside it goes on.
#[test]
fn bad_selective_sessions_are_refused_by_name_and_others_go_on() {
    let landmarks = landmarks();
    let server = serve(&landmarks);
    let mut good =
        SelectiveStreamClient::connect(server.addr(), hello(Scheme::Selective), WAIT).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let leaf = |path: &[bool]| NodeName {
        tree: 0,
        node: path
            .iter()
            .fold(flaneur::lod::HeapIndex::root(), |n, &r| n.child(r)),
    };
    let cases: Vec<(Message, &str)> = vec![
        (
            Message::View(ViewPacket {
                budget_mode: true,
                ..random_view(&mut rng, 0, 10)
            }),
            "budget mode",
        ),
        (
            Message::Resume {
                next_frame: 0,
                objects: vec![],
            },
            "resumes with RESUME-LEAVES",
        ),
        (
            Message::ResumeLeaves {
                next_frame: 0,
                objects: vec![HeldLeaves {
                    index: 0,
                    leaves: vec![leaf(&[]), leaf(&[false])],
                }],
            },
            "lies below another named node",
        ),
        (
            Message::ResumeLeaves {
                next_frame: 0,
                objects: vec![HeldLeaves {
                    index: 0,
                    leaves: vec![leaf(&[false])],
                }],
            },
            "has no named node above it",
        ),
        (
            Message::ResumeLeaves {
                next_frame: 0,
                objects: vec![HeldLeaves {
                    index: 5,
                    leaves: vec![],
                }],
            },
            "object 5, not in WELCOME's 2",
        ),
    ];
    for (m, why) in cases {
        let mut s = raw_session(&server, hello(Scheme::Selective));
        s.write_all(&m.encode()).unwrap();
        let said = refusal(&mut s);
        assert!(said.contains(why), "{said}");
        let end = server.ends().recv_timeout(WAIT).unwrap();
        assert!(end.reason.unwrap().contains(why));
        // The good session beside it goes on.
        good.refine(&random_view(&mut rng, 1000 + end.frames as u32, 100))
            .unwrap_or_else(|e| panic!("after {why}: {e}"));
    }
    // A client of one scheme does not speak the other.
    let e = SelectiveStreamClient::connect(server.addr(), hello(Scheme::Dag), WAIT).unwrap_err();
    assert!(e.to_string().contains("StreamClient speaks it"), "{e}");
    good.bye().unwrap();
}

/// A generated building: flat-shaded, so every corner and crease is a seam and its
/// splits come in runs, some adding no triangle (ours: placed by their leaves).
fn building() -> flaneur::scene::Mesh {
    citygen::sample_building(600).unwrap()
}

/// A landmark of crease runs streams truly selectively over TCP: after each random
/// view, and across a reconnect, the client's mesh is a local refiner's, triangle for
/// triangle; a cut-vertex-only client's is the front a local server sent.
#[test]
fn a_landmark_of_crease_runs_streams_by_its_leaves_over_tcp() {
    let mesh = building();
    let landmarks = [landmark(7, &mesh)];
    let source = SelectiveSource::new(&landmarks[0].pm, &landmarks[0].dag).unwrap();
    assert_eq!(source.placement(), flaneur::lod::Placement::LeafCorners);
    let server = serve(&landmarks);
    let mut client =
        SelectiveStreamClient::connect(server.addr(), hello(Scheme::Selective), WAIT).unwrap();
    let mut local = Local::new(&landmarks);
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let mut rounds = 0;
    for step in 0..100 {
        if step == 50 {
            client.reconnect().unwrap();
        }
        let v = view_of(&mut rng, &mesh, 100 * step, 20);
        rounds += client.refine(&v).unwrap();
        assert_eq!(meshes(&client), local.select(&v), "step {step}");
    }
    assert!(rounds > 5, "{rounds}");
    let mut cut =
        SelectiveStreamClient::connect(server.addr(), hello(Scheme::CutVertex), WAIT).unwrap();
    let mut sent = SelectiveServer::new(&source).cut_vertex_only();
    for step in 0..40 {
        if step == 20 {
            cut.reconnect().unwrap();
        }
        let v = view_of(&mut rng, &mesh, step, 20);
        cut.send_view(&v).unwrap();
        cut.receive_batch().unwrap();
        sent.refine_at_most(&source, &local_view(&v), v.tau, v.n as usize)
            .unwrap();
        assert_eq!(
            canonical(cut.objects()[0].triangles()),
            canonical(sent.sent_triangles(&source)),
            "step {step}"
        );
    }
}
