//! The papers' client-server view-dependent rendering (Zheng 2007 ch. 5–6 and §8.2;
//! Kim–Lee–Kobbelt's truly selective streaming; El-Sana's server of one thread per
//! client and his view-dependence blocks): a server that holds each landmark's
//! progressive mesh and DAG once, read-only, and per client the fronts and counters of
//! its traversal; a client that holds only its selective meshes and applies the
//! batches of edge collapses and vertex splits the server answers its views with, or
//! (the truly selective schemes and the blocks) refines on its own from the part of the
//! vertex hierarchy it was sent.
//!
//! `protocol` is the wire format (versioned, length-prefixed, its byte layout in its
//! documentation); `landmark` what a server streams; `server` the sessions; `client`
//! the selective meshes' side of Zheng's scheme, and `predictive` the client that hides
//! the round trip by prediction (Zheng ch. 5–6); `selective_client` the side of
//! Kim–Lee–Kobbelt's truly selective schemes, whose packets `selective_wire` encodes;
//! `block_client` the side of El-Sana's view-dependence blocks (the client asks for
//! whole blocks by name, the server predicts on idle time);
//! `wire` the bounded field reader every decoder uses; `walk_source` a session as the
//! landmarks a walk draws (`flaneur walk --stream`).
//!
//! ```
//! use std::sync::Arc;
//! use std::time::Duration;
//! use flaneur::lod::{Dag, DagConstruction, ProgressiveMesh, Traversal};
//! use flaneur_stream::{Hello, Landmark, Scheme, ServerConfig, StreamClient, StreamServer, ViewPacket};
//!
//! let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
//! let dag = Dag::build(&pm, DagConstruction::MiniRedundant)?;
//! let bunny = Landmark { id: 1, pm: Arc::new(pm), dag: Arc::new(dag) };
//! let server = StreamServer::bind("127.0.0.1:0", vec![bunny], ServerConfig::default())?.spawn()?;
//!
//! let hello = Hello { traversal: Traversal::Priority, fov: 1.0, budget: Some(60_000),
//!                     out_of_view: true, back_face: true, scheme: Scheme::Dag };
//! let mut client = StreamClient::connect(server.addr(), hello, Duration::from_secs(5))?;
//! let base = client.objects()[0].mesh().triangle_count();
//! let view = ViewPacket { frame: 0, eye: [0.0, 0.1, 0.4], aim: [0.0, 0.1, 0.0], tau: 0.001,
//!                         budget_mode: true, n: 500 };
//! client.send_view(&view)?;
//! let batch = client.receive_batch()?;
//! assert!(batch.splits > 0);
//! assert!(client.objects()[0].mesh().triangle_count() > base);
//! client.bye()?;
//! # Ok::<(), flaneur_stream::StreamError>(())
//! ```

mod block_client;
mod client;
mod error;
mod exchange;
mod landmark;
mod prediction;
mod predictive;
pub mod protocol;
mod selective_client;
pub mod selective_wire;
mod server;
mod walk_source;
mod wire;

pub use block_client::{BlockLandmark, BlockStreamClient, SwitchReport};
pub use client::{BatchReport, StreamClient, StreamedObject, MAX_SPLITS};
pub use error::StreamError;
pub use landmark::Landmark;
pub use prediction::Predictor;
pub use predictive::{PredictiveClient, PredictiveFrame, Refinement, ADJUST_EVERY, MAX_SPAN};
pub use protocol::{HeldLeaves, HeldNodes, Hello, Message, Scheme, ViewPacket};
pub use selective_client::{SelectiveLandmark, SelectiveStreamClient, VsplitsReport};
pub use server::{RunningServer, ServerConfig, SessionEnd, StreamServer, MIN_SESSION_BUDGET};
pub use walk_source::{StreamFigures, StreamedLandmarks, RETRY_AFTER};
