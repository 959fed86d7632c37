//! The client of a truly selective session (Kim–Lee–Kobbelt): per landmark the part of
//! the vertex hierarchy it was sent and its mesh over it. Under the selective scheme it
//! refines and coarsens on its own for each view ([`SelectiveStreamClient::select`])
//! and asks the server only when the view wants a split it was not sent; under the
//! cut-vertex-only scheme (KLK §7) it makes each split as it comes and never refines
//! on its own.
//!
//! A packet that does not fit what the client holds (a split of a node it was not
//! sent, or was sent twice; cut vertices that do not bound a fan of its mesh) is an
//! error naming it; after one, connect again. A client whose connection broke resumes
//! on a new one ([`SelectiveStreamClient::reconnect`]) by naming its leaves.

use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::time::Duration;

use glam::Vec3;

use crate::client::open;
use crate::error::StreamError;
use crate::exchange::Exchange;
use crate::protocol::{
    send, HeldLeaves, Hello, Message, ObjectVsplits, Scheme, SelectiveObject, ViewPacket,
    MAX_RESUME,
};
use flaneur::lod::{CutVertexClient, NodeName, SelectiveClient, View};

/// One landmark as a truly selective client holds it.
#[derive(Clone, Debug)]
pub struct SelectiveLandmark {
    pub id: u64,
    held: Held,
    /// Splits a cut-vertex-only client made (each as it came).
    made: u64,
}

#[derive(Clone, Debug)]
enum Held {
    Selective(SelectiveClient),
    CutVertex(CutVertexClient),
}

impl SelectiveLandmark {
    /// Its mesh's triangles, corners as node names.
    pub fn triangles(&self) -> Vec<[NodeName; 3]> {
        match &self.held {
            Held::Selective(c) => c.triangles(),
            Held::CutVertex(c) => c.triangles(),
        }
    }

    /// The nodes it holds whose split it was not sent (what a resume names).
    pub fn leaves(&self) -> Vec<NodeName> {
        match &self.held {
            Held::Selective(c) => c.leaves(),
            Held::CutVertex(c) => c.leaves(),
        }
    }

    /// The vertex splits and collapses the client made so far (El-Sana's split and
    /// merge operations); a cut-vertex-only client makes each split as it comes, and
    /// never collapses.
    pub fn operations(&self) -> (u64, u64) {
        match &self.held {
            Held::Selective(c) => c.operations(),
            Held::CutVertex(_) => (self.made, 0),
        }
    }

    fn receive(&mut self, o: &ObjectVsplits) -> Result<(), StreamError> {
        match &mut self.held {
            Held::Selective(c) => c.receive(&o.packets)?,
            Held::CutVertex(c) => {
                c.receive(&o.packets)?;
                self.made += o.packets.len() as u64;
            }
        }
        Ok(())
    }
}

/// What one VSPLITS brought.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VsplitsReport {
    pub frame: u32,
    /// Vertex splits, over every landmark.
    pub splits: usize,
    /// The message's bytes on the wire.
    pub bytes: usize,
}

/// A session of a truly selective scheme with a stream server.
///
/// ```
/// use std::sync::Arc;
/// use std::time::Duration;
/// use flaneur::lod::{Dag, DagConstruction, ProgressiveMesh, Traversal};
/// use flaneur_stream::{Hello, Landmark, Scheme, SelectiveStreamClient, ServerConfig, StreamServer, ViewPacket};
///
/// let pm = ProgressiveMesh::build(&flaneur::scene::bunny())?;
/// let dag = Dag::build(&pm, DagConstruction::MiniRedundant)?;
/// let bunny = Landmark { id: 1, pm: Arc::new(pm), dag: Arc::new(dag) };
/// let server = StreamServer::bind("127.0.0.1:0", vec![bunny], ServerConfig::default())?.spawn()?;
///
/// let hello = Hello { traversal: Traversal::Priority, fov: 1.0, budget: None,
///                     out_of_view: true, back_face: true, scheme: Scheme::Selective };
/// let mut client = SelectiveStreamClient::connect(server.addr(), hello, Duration::from_secs(5))?;
/// let base = client.objects()[0].triangles().len();
/// let view = ViewPacket { frame: 0, eye: [0.0, 0.1, 0.4], aim: [0.0, 0.1, 0.0], tau: 0.001,
///                         budget_mode: false, n: 500 };
/// // Ask until the client holds what the view wants.
/// let rounds = client.refine(&view)?;
/// assert!(rounds > 0);
/// assert!(client.objects()[0].triangles().len() > base);
/// client.bye()?;
/// # Ok::<(), flaneur_stream::StreamError>(())
/// ```
#[derive(Debug)]
pub struct SelectiveStreamClient {
    exchange: Exchange,
    objects: Vec<SelectiveLandmark>,
    server: SocketAddr,
    hello: Hello,
    timeout: Duration,
}

impl SelectiveStreamClient {
    /// Connects, says `hello` (of the selective or the cut-vertex-only scheme), and
    /// takes the server's base meshes; `timeout` bounds each wait for the server.
    pub fn connect(
        addr: impl ToSocketAddrs,
        hello: Hello,
        timeout: Duration,
    ) -> Result<SelectiveStreamClient, StreamError> {
        let stream = TcpStream::connect(addr)?;
        let server = stream.peer_addr()?;
        let (stream, welcome) = greet(stream, hello, timeout)?;
        let objects = welcome
            .into_iter()
            .map(|o| SelectiveLandmark {
                id: o.id,
                made: 0,
                held: match hello.scheme {
                    Scheme::CutVertex => Held::CutVertex(CutVertexClient::new(o.base)),
                    _ => Held::Selective(SelectiveClient::new(o.base).with_criteria(
                        flaneur::lod::Criteria {
                            out_of_view: hello.out_of_view,
                            back_face: hello.back_face,
                        },
                    )),
                },
            })
            .collect();
        Ok(SelectiveStreamClient {
            exchange: Exchange::new(stream),
            objects,
            server,
            hello,
            timeout,
        })
    }

    /// The session's landmarks, in the server's order.
    pub fn objects(&self) -> &[SelectiveLandmark] {
        &self.objects
    }

    /// The view a VIEW packet stands for, as the server reads it.
    fn view(&self, v: &ViewPacket) -> Result<View, StreamError> {
        let eye = Vec3::from(v.eye);
        Ok(View::new(eye, Vec3::from(v.aim) - eye, self.hello.fov)?)
    }

    /// Brings every landmark's mesh to `view` with what the client holds; whether the
    /// view wants splits the client was not sent (then a VIEW should go). A client of
    /// the cut-vertex-only scheme does not refine on its own: always `true`.
    pub fn select(&mut self, v: &ViewPacket) -> Result<bool, StreamError> {
        let view = self.view(v)?;
        let mut lacks = false;
        for o in &mut self.objects {
            match &mut o.held {
                Held::Selective(c) => lacks |= !c.select(&view, v.tau)?.is_empty(),
                Held::CutVertex(_) => lacks = true,
            }
        }
        Ok(lacks)
    }

    /// Sends `view`; its answer is [`SelectiveStreamClient::receive_batch`]'s. One
    /// view is pending at a time.
    pub fn send_view(&mut self, view: &ViewPacket) -> Result<(), StreamError> {
        self.exchange.send_view(view)
    }

    /// Waits for the pending view's VSPLITS and takes its packets.
    pub fn receive_batch(&mut self) -> Result<VsplitsReport, StreamError> {
        let (m, bytes) = self.exchange.answer(|m: &Message| match m {
            Message::Vsplits { frame, .. } => Some(*frame),
            _ => None,
        })?;
        let Message::Vsplits { frame, objects } = m else {
            unreachable!("the exchange returns a VSPLITS")
        };
        let mut report = VsplitsReport {
            frame,
            bytes,
            ..Default::default()
        };
        for o in &objects {
            let object = self.objects.get_mut(o.index as usize).ok_or_else(|| {
                StreamError::Malformed(format!(
                    "splits for object {}, not in SELECTIVE-WELCOME",
                    o.index
                ))
            })?;
            report.splits += o.packets.len();
            object.receive(o)?;
        }
        Ok(report)
    }

    /// Asks for `view` until the client holds what it wants (selective scheme), or
    /// once (cut-vertex-only, whose meshes change only by what comes): the round trips
    /// it took. The next frames' views must have frames above `view`'s.
    pub fn refine(&mut self, view: &ViewPacket) -> Result<usize, StreamError> {
        let mut rounds = 0;
        let mut v = *view;
        v.frame = v.frame.max(self.exchange.next_frame());
        while self.select(&v)? {
            self.send_view(&v)?;
            let got = self.receive_batch()?;
            rounds += 1;
            v.frame += 1;
            match self.hello.scheme {
                Scheme::CutVertex if got.splits < view.n as usize => break,
                Scheme::Selective if got.splits == 0 => {
                    return Err(StreamError::Malformed(format!(
                        "the server sent no split for frame {}, which wants some",
                        got.frame
                    )))
                }
                _ => {}
            }
        }
        Ok(rounds)
    }

    /// Connects to the server again and resumes from the leaves this client holds
    /// (RESUME-LEAVES). A view sent and not answered is forgotten. An `Err`, the client
    /// left as it was, when the server cannot be reached or streams other landmarks.
    pub fn reconnect(&mut self) -> Result<(), StreamError> {
        let stream = TcpStream::connect_timeout(&self.server, self.timeout)?;
        let (mut stream, welcome) = greet(stream, self.hello, self.timeout)?;
        let same = welcome.len() == self.objects.len()
            && welcome.iter().zip(&self.objects).all(|(w, o)| w.id == o.id);
        if !same {
            return Err(StreamError::Malformed(
                "the server now streams other landmarks than this session's: connect afresh".into(),
            ));
        }
        let resume = Message::ResumeLeaves {
            next_frame: self.exchange.next_frame(),
            objects: self
                .objects
                .iter()
                .enumerate()
                .map(|(index, o)| HeldLeaves {
                    index: index as u32,
                    leaves: o.leaves(),
                })
                .collect(),
        };
        let bytes = resume.encode();
        if bytes.len() - 4 > MAX_RESUME {
            return Err(StreamError::Malformed(format!(
                "a RESUME-LEAVES of {} bytes, above the {MAX_RESUME} a server reads: \
                 connect afresh",
                bytes.len() - 4
            )));
        }
        std::io::Write::write_all(&mut stream, &bytes)?;
        self.exchange.resume_on(stream);
        Ok(())
    }

    /// Ends the session.
    pub fn bye(mut self) -> Result<(), StreamError> {
        send(&mut self.exchange.stream, &Message::Bye)?;
        Ok(())
    }
}

/// Opens a truly selective session on `stream`: HELLO, then SELECTIVE-WELCOME.
fn greet(
    stream: TcpStream,
    hello: Hello,
    timeout: Duration,
) -> Result<(TcpStream, Vec<SelectiveObject>), StreamError> {
    if hello.scheme == Scheme::Dag {
        return Err(StreamError::Malformed(
            "a HELLO of Zheng's DAG scheme: StreamClient speaks it".into(),
        ));
    }
    match open(stream, hello, timeout)? {
        (stream, Message::SelectiveWelcome(objects)) => Ok((stream, objects)),
        (_, other) => Err(StreamError::Malformed(format!(
            "the server answered a truly selective HELLO with {other:?}"
        ))),
    }
}
