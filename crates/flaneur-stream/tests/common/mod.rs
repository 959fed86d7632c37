//! What the truly selective and the blocks sessions' tests share: the landmarks'
//! making, the HELLO, and a local refiner whose meshes the clients' must equal.

use std::io::Write;
use std::net::TcpStream;
use std::sync::Arc;
use std::time::Duration;

use flaneur::lod::{
    Dag, DagConstruction, Front, NodeName, ProgressiveMesh, SelectiveSource, Traversal, View,
};
use flaneur_stream::protocol::{receive, Message, MAX_TO_CLIENT};
use flaneur_stream::{Hello, Landmark, RunningServer, Scheme, ViewPacket};
use glam::Vec3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

pub const FOV: f32 = 1.0;
pub const WAIT: Duration = Duration::from_secs(20);

pub fn landmark(id: u64, mesh: &flaneur::scene::Mesh) -> Landmark {
    let pm = ProgressiveMesh::build(mesh).unwrap();
    let dag = Dag::build(&pm, DagConstruction::MiniRedundant).unwrap();
    Landmark {
        id,
        pm: Arc::new(pm),
        dag: Arc::new(dag),
    }
}

pub fn hello(scheme: Scheme) -> Hello {
    Hello {
        traversal: Traversal::Priority,
        fov: FOV,
        budget: None,
        out_of_view: true,
        back_face: true,
        scheme,
    }
}

/// A random view of `mesh` from one to three of its sizes away, looking near its
/// middle, asking for at most `n` splits.
pub fn view_of(
    rng: &mut ChaCha8Rng,
    mesh: &flaneur::scene::Mesh,
    frame: u32,
    n: u32,
) -> ViewPacket {
    let (lo, hi) = mesh.positions.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), &p| (lo.min(Vec3::from(p)), hi.max(Vec3::from(p))),
    );
    let (centre, size) = ((lo + hi) / 2.0, (hi - lo).max_element());
    let mut off = |scale: f32| {
        Vec3::new(
            rng.gen_range(-1.5..1.5),
            rng.gen_range(-1.5..1.5),
            rng.gen_range(-1.5..1.5),
        ) * size
            * scale
    };
    let (eye, aim) = (centre + off(1.0), centre + off(0.2));
    ViewPacket {
        frame,
        eye: eye.to_array(),
        aim: aim.to_array(),
        tau: rng.gen_range(0.0005..0.005),
        budget_mode: false,
        n,
    }
}

pub fn local_view(v: &ViewPacket) -> View {
    let eye = Vec3::from(v.eye);
    View::new(eye, Vec3::from(v.aim) - eye, FOV).unwrap()
}

/// Triangles turned to start at their smallest corner, sorted.
pub fn canonical(mut triangles: Vec<[NodeName; 3]>) -> Vec<[NodeName; 3]> {
    for t in &mut triangles {
        let k = (0..3).min_by_key(|&k| t[k].clone()).unwrap();
        t.rotate_left(k);
    }
    triangles.sort_unstable();
    triangles
}

/// A local refiner of every landmark: its source and its front.
pub struct Local(Vec<(SelectiveSource, Front)>);

impl Local {
    pub fn new(landmarks: &[Landmark]) -> Local {
        Local(
            landmarks
                .iter()
                .map(|l| {
                    let source = SelectiveSource::new(&l.pm, &l.dag).unwrap();
                    let front = source.hierarchy().roots();
                    (source, front)
                })
                .collect(),
        )
    }

    /// Each landmark's mesh for `v`.
    pub fn select(&mut self, v: &ViewPacket) -> Vec<Vec<[NodeName; 3]>> {
        self.0
            .iter_mut()
            .map(|(source, front)| {
                source.select(front, &local_view(v), v.tau).unwrap();
                let h = source.hierarchy();
                let named = front
                    .triangles(h)
                    .iter()
                    .map(|t| t.map(|n| h.name(n)))
                    .collect();
                canonical(named)
            })
            .collect()
    }
}

/// Reads the server's answer to what was sent on `stream`: its REFUSED reason.
pub fn refusal(stream: &mut TcpStream) -> String {
    loop {
        match receive(stream, MAX_TO_CLIENT).unwrap() {
            Some((Message::Refused(why), _)) => return why,
            Some(_) => continue,
            None => panic!("closed without a reason"),
        }
    }
}

/// A session opened by hand: HELLO sent, what follows up to the test.
pub fn raw_session(server: &RunningServer, hello: Hello) -> TcpStream {
    let mut s = TcpStream::connect(server.addr()).unwrap();
    s.set_read_timeout(Some(WAIT)).unwrap();
    s.write_all(&Message::Hello(hello).encode()).unwrap();
    s
}
