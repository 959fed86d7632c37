//! The stream client: it holds only each object's selective mesh (Zheng 2007 §8.2.1),
//! in the compact arrays a renderer draws (§4.5), and the vertex splits of the nodes it
//! has split, which a later collapse undoes. It sends views and applies the batches
//! the server answers with.
//!
//! Every batch is checked before it changes a mesh: a collapse of a node the client
//! never split, a split of one it holds split, an object the session does not have, a
//! batch for another frame than the one asked, each is an error naming it. A vertex
//! split that does not fit the mesh is refused by the mesh itself
//! ([`CompactMesh::apply_split`]). After an error the session's meshes are no longer
//! the server's: connect again.
//!
//! A client whose connection broke, or whose server stalled, reconnects and resumes
//! ([`StreamClient::reconnect`]): it tells a new session the nodes it holds split, and
//! the server goes on from the meshes the client holds, whatever batches were lost.

use std::collections::HashMap;
use std::io;
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::Duration;

use crate::error::StreamError;
use crate::exchange::Exchange;
use crate::protocol::{
    receive, send, HeldNodes, Hello, Message, NodeSplit, ObjectUpdates, Scheme, ViewPacket,
    WelcomeObject, MAX_RESUME, MAX_TO_CLIENT,
};
use flaneur::lod::{CompactMesh, MeshChanges};

/// The most vertex splits a client makes room for in one object: its mesh's ID maps
/// take 12 bytes a split, so a hostile WELCOME cannot make it reserve more than about
/// 800 MiB an object.
pub const MAX_SPLITS: u32 = 1 << 26;

/// One object as the client holds it.
#[derive(Debug)]
pub struct StreamedObject {
    pub id: u64,
    /// Vertex splits of its progressive mesh, as WELCOME said.
    splits: u32,
    /// The most vertices and triangles its mesh may reach.
    capacity: (usize, usize),
    mesh: CompactMesh,
    /// The nodes split, with the runs they applied.
    held: HashMap<u32, NodeSplit>,
}

impl StreamedObject {
    /// The selective mesh, as the batches so far made it.
    pub fn mesh(&self) -> &CompactMesh {
        &self.mesh
    }

    /// The ranges of the mesh's arrays the batches changed since the last call, for a
    /// renderer to upload; taken.
    pub fn take_changes(&mut self) -> MeshChanges {
        self.mesh.take_changes()
    }

    /// The most vertices and triangles its mesh may reach (the full mesh's: each vertex
    /// split adds a vertex and at most two triangles), to size a renderer's buffers once.
    pub fn capacity(&self) -> (usize, usize) {
        self.capacity
    }

    /// The DAG nodes it holds split, in order: what a RESUME tells a new session.
    pub fn held_nodes(&self) -> Vec<u32> {
        let mut nodes: Vec<u32> = self.held.keys().copied().collect();
        nodes.sort_unstable();
        nodes
    }

    /// Applies this object's part of a batch: its collapses, then its splits.
    pub(crate) fn apply(&mut self, updates: ObjectUpdates) -> Result<(), StreamError> {
        for node in updates.collapses {
            self.collapse(node)?;
        }
        for split in updates.splits {
            self.split(split)?;
        }
        Ok(())
    }

    fn collapse(&mut self, node: u32) -> Result<(), StreamError> {
        let split = self.held.remove(&node).ok_or_else(|| {
            StreamError::Malformed(format!(
                "object {}: a collapse of node {node}, which this client never split",
                self.id
            ))
        })?;
        for (i, s) in split.run.iter().enumerate().rev() {
            self.mesh.apply_collapse(split.first as usize + i, s)?;
        }
        Ok(())
    }

    fn split(&mut self, split: NodeSplit) -> Result<(), StreamError> {
        if self.held.contains_key(&split.node) {
            return Err(StreamError::Malformed(format!(
                "object {}: a split of node {}, which this client holds split",
                self.id, split.node
            )));
        }
        for (i, s) in split.run.iter().enumerate() {
            self.mesh.apply_split(split.first as usize + i, s)?;
        }
        self.held.insert(split.node, split);
        Ok(())
    }
}

/// A new session with the server at `server`, resumed from `objects` as the client
/// holds them (RESUME), its next VIEW's frame at least `next_frame`; the connection.
/// An `Err` when the server cannot be reached, or streams other objects now.
pub(crate) fn resume_session(
    (server, hello, timeout): (SocketAddr, Hello, Duration),
    objects: &[StreamedObject],
    next_frame: u32,
) -> Result<TcpStream, StreamError> {
    let stream = TcpStream::connect_timeout(&server, timeout)?;
    let (mut stream, welcome) = greet(stream, hello, timeout)?;
    let same = welcome.len() == objects.len()
        && welcome
            .iter()
            .zip(objects)
            .all(|(w, o)| w.id == o.id && w.splits == o.splits);
    if !same {
        return Err(StreamError::Malformed(
            "the server now streams other objects than this session's: connect afresh".into(),
        ));
    }
    let held = objects
        .iter()
        .enumerate()
        .filter(|(_, o)| !o.held.is_empty())
        .map(|(index, o)| HeldNodes {
            index: index as u32,
            nodes: o.held_nodes(),
        })
        .collect();
    let resume = Message::Resume {
        next_frame,
        objects: held,
    };
    let bytes = resume.encode();
    if bytes.len() - 4 > MAX_RESUME {
        return Err(StreamError::Malformed(format!(
            "a RESUME of {} bytes, above the {MAX_RESUME} a server reads: connect afresh",
            bytes.len() - 4
        )));
    }
    io::Write::write_all(&mut stream, &bytes)?;
    Ok(stream)
}

/// Opens a session of Zheng's scheme on `stream`: HELLO, then the server's WELCOME.
fn greet(
    stream: TcpStream,
    hello: Hello,
    timeout: Duration,
) -> Result<(TcpStream, Vec<WelcomeObject>), StreamError> {
    if hello.scheme != Scheme::Dag {
        return Err(StreamError::Malformed(format!(
            "a HELLO of the {:?} scheme: this client speaks Zheng's DAG scheme \
             (SelectiveStreamClient speaks the truly selective ones)",
            hello.scheme
        )));
    }
    match open(stream, hello, timeout)? {
        (stream, Message::Welcome(objects)) => Ok((stream, objects)),
        (_, other) => Err(StreamError::Malformed(format!(
            "the server answered HELLO with {other:?}"
        ))),
    }
}

/// Sends HELLO on `stream`, `timeout` bounding each wait from then on, and reads the
/// server's answer (a REFUSED is an `Err` with its reason).
pub(crate) fn open(
    mut stream: TcpStream,
    hello: Hello,
    timeout: Duration,
) -> Result<(TcpStream, Message), StreamError> {
    stream.set_read_timeout(Some(timeout))?;
    stream.set_nodelay(true)?;
    send(&mut stream, &Message::Hello(hello))?;
    match receive(&mut stream, MAX_TO_CLIENT)? {
        Some((Message::Refused(why), _)) => Err(StreamError::Refused(why)),
        Some((answer, _)) => Ok((stream, answer)),
        None => Err(StreamError::Refused("closed before WELCOME".into())),
    }
}

/// What one batch did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BatchReport {
    pub frame: u32,
    /// Nodes collapsed and split, over every object.
    pub collapses: usize,
    pub splits: usize,
    /// The batch's bytes on the wire.
    pub bytes: usize,
    /// The bytes of its largest object's part ([`ObjectUpdates::wire_len`](crate::protocol::ObjectUpdates::wire_len)).
    pub largest_object: usize,
}

/// A session with a stream server.
#[derive(Debug)]
pub struct StreamClient {
    exchange: Exchange,
    objects: Vec<StreamedObject>,
    /// What a reconnection needs: the server, the HELLO, the wait bound.
    server: SocketAddr,
    hello: Hello,
    timeout: Duration,
    /// The time from HELLO to WELCOME: the session's first round trip.
    greeting: Duration,
}

/// A session as a client that takes it over gets it.
pub(crate) struct Parts {
    pub(crate) stream: TcpStream,
    pub(crate) objects: Vec<StreamedObject>,
    pub(crate) server: SocketAddr,
    pub(crate) timeout: Duration,
    pub(crate) greeting: Duration,
}

impl StreamClient {
    /// Connects, says `hello`, and takes the server's objects; `timeout` bounds each
    /// wait for the server.
    pub fn connect(
        addr: impl ToSocketAddrs,
        hello: Hello,
        timeout: Duration,
    ) -> Result<StreamClient, StreamError> {
        let stream = TcpStream::connect(addr)?;
        let server = stream.peer_addr()?;
        let said = std::time::Instant::now();
        let (stream, welcome) = greet(stream, hello, timeout)?;
        let greeting = said.elapsed();
        let objects = welcome
            .into_iter()
            .map(|o| {
                if o.splits > MAX_SPLITS {
                    return Err(StreamError::Malformed(format!(
                        "object {}: {} vertex splits, above the {MAX_SPLITS} a client holds",
                        o.id, o.splits
                    )));
                }
                let splits = o.splits as usize;
                Ok(StreamedObject {
                    id: o.id,
                    splits: o.splits,
                    capacity: (
                        o.base.positions.len() + splits,
                        o.base.triangle_count() + 2 * splits,
                    ),
                    mesh: CompactMesh::from_base(&o.base, o.splits as usize)?,
                    held: HashMap::new(),
                })
            })
            .collect::<Result<Vec<_>, StreamError>>()?;
        Ok(StreamClient {
            exchange: Exchange::new(stream),
            objects,
            server,
            hello,
            timeout,
            greeting,
        })
    }

    /// Connects to the server again, on a new connection, and resumes the session
    /// from the meshes this client holds (RESUME): after a broken connection, or to
    /// give up on a batch that does not come. A view sent and not answered is
    /// forgotten; the next VIEW's frame must still be above it. An `Err`, the client
    /// left as it was, when the server cannot be reached or now streams other objects.
    pub fn reconnect(&mut self) -> Result<(), StreamError> {
        let peer = (self.server, self.hello, self.timeout);
        let stream = resume_session(peer, &self.objects, self.exchange.next_frame())?;
        self.exchange.resume_on(stream);
        Ok(())
    }

    /// The session's objects, in the server's order.
    pub fn objects(&self) -> &[StreamedObject] {
        &self.objects
    }

    /// Sends `view`; its batch is [`StreamClient::receive_batch`]'s. One view is
    /// pending at a time (Zheng Fig. 5.3b: no request until the last was answered).
    pub fn send_view(&mut self, view: &ViewPacket) -> Result<(), StreamError> {
        self.exchange.send_view(view)
    }

    /// Waits for the pending view's batch and applies it.
    pub fn receive_batch(&mut self) -> Result<BatchReport, StreamError> {
        let (m, bytes) = self.exchange.answer(|m: &Message| match m {
            Message::Batch { frame, .. } => Some(*frame),
            _ => None,
        })?;
        let Message::Batch { frame, objects } = m else {
            unreachable!("the exchange returns a batch")
        };
        let mut report = BatchReport {
            frame,
            bytes,
            ..Default::default()
        };
        for o in objects {
            let object = self.objects.get_mut(o.index as usize).ok_or_else(|| {
                StreamError::Malformed(format!("updates for object {}, not in WELCOME", o.index))
            })?;
            report.largest_object = report.largest_object.max(o.wire_len());
            report.collapses += o.collapses.len();
            report.splits += o.splits.len();
            object.apply(o)?;
        }
        Ok(report)
    }

    /// The connection, the objects and where the server is, for a client that takes
    /// the session over.
    pub(crate) fn into_parts(self) -> Parts {
        Parts {
            stream: self.exchange.stream,
            objects: self.objects,
            server: self.server,
            timeout: self.timeout,
            greeting: self.greeting,
        }
    }

    /// Ends the session.
    pub fn bye(mut self) -> Result<(), StreamError> {
        send(&mut self.exchange.stream, &Message::Bye)?;
        Ok(())
    }
}
