//! The server's side: each input is the bytes a client sends in one session (HELLO,
//! VIEWs, BYE, or anything else), served to its end with the output thrown away. Any
//! input must end the session with a reason or without one, never a panic.

#![no_main]

use std::net::SocketAddr;
use std::sync::{Arc, OnceLock};

use flaneur::lod::{bumpy_torus, Dag, DagConstruction, ProgressiveMesh};
use flaneur_stream::{Landmark, ServerConfig, StreamServer};
use libfuzzer_sys::fuzz_target;

/// A server of one small landmark (a torus of about 1,000 triangles, so that each
/// input's traversals take microseconds), built once.
fn server() -> &'static StreamServer {
    static SERVER: OnceLock<StreamServer> = OnceLock::new();
    SERVER.get_or_init(|| {
        let pm = ProgressiveMesh::build(&bumpy_torus(1_000)).expect("a progressive mesh");
        let dag = Dag::build(&pm, DagConstruction::MiniRedundant).expect("a DAG");
        let torus = Landmark {
            id: 1,
            pm: Arc::new(pm),
            dag: Arc::new(dag),
        };
        StreamServer::bind("127.0.0.1:0", vec![torus], ServerConfig::default())
            .expect("a server bound on loopback")
    })
}

fuzz_target!(|data: &[u8]| {
    let peer = SocketAddr::from(([127, 0, 0, 1], 9));
    server().serve(data, std::io::sink(), peer);
});
