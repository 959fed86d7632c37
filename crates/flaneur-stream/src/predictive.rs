//! Latency hidden by prediction — Zheng 2007 ch. 5–6: the client's getting of updates
//! (PGU) runs on a thread of its own beside its rendering (PRD), and each frame sends the
//! view predicted for the frame its batch will arrive at, E' = E_c + f·(E_c − E_p) (and
//! A' for the aim-at point, §6.2; or ours of second order, [`Predictor`]), so that every
//! frame finds the batch for its own view already there.
//!
//! - **The prediction span** f = ⌈T_g / (T_r + T_u)⌉ (eq. 6.3.1): T_g is measured per
//!   batch from its request to its arrival, T_r + T_u is the caller's frame period (the
//!   time between two calls of [`PredictiveClient::frame`]); both smoothed, f updated
//!   every [`ADJUST_EVERY`] frames. T_g's first measure is the session's greeting (HELLO
//!   to WELCOME, a round trip), so f is set at the second frame, once the period is
//!   known, rather than a round trip and ten frames later (ours).
//! - **f requests in flight** (Fig. 6.1): at the start the current view goes out f times
//!   (RENDER-WAN, Fig. 6.2); then a frame that applied a batch sends one request, so a
//!   late batch makes frames unmodified without adding requests, and its delay is
//!   recovered within f + x frames (Fig. 6.4). When f grows, the frame that finds it so
//!   sends the extra requests at once; when it shrinks, frames send nothing until the
//!   requests in flight are down to the new f (Fig. 6.5). Both come out of one rule: a
//!   frame sends while fewer than f requests are in flight, and an unmodified frame
//!   never sends.
//! - **One batch a frame** (§5.2.1): a frame applies at most one batch, the oldest.
//! - **The alarm level** L = B − 2·N·f (§6.2): budget mode is asked for as soon as an
//!   object's triangles pass L, f frames before the budget itself could be passed.
//!
//! The request sent at frame i whose batch comes back behind the k batches already in
//! flight is applied at frame i + k + 1 (if on time), so it carries the view predicted
//! for that frame: the span of each prediction is the number of frames ahead its batch
//! will be applied.

use std::collections::VecDeque;
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::sync::mpsc;
use std::thread;
use std::time::{Duration, Instant};

use glam::Vec3;

use crate::client::StreamedObject;
use crate::error::StreamError;
use crate::prediction::Predictor;
use crate::protocol::{
    receive, send, Hello, Message, ObjectUpdates, ViewPacket, MAX_N, MAX_TO_CLIENT,
};
use crate::StreamClient;

/// Frames between two updates of the prediction span.
pub const ADJUST_EVERY: u32 = 10;
/// The longest prediction span.
pub const MAX_SPAN: usize = 64;

/// What a predictive client asks of each traversal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refinement {
    /// τ, a fraction of the viewport.
    pub tau: f32,
    /// N, 1 to [`MAX_N`].
    pub n: u32,
    /// The first prediction span, before any round trip is measured.
    pub initial_span: usize,
    /// How views are predicted.
    pub predictor: Predictor,
}

/// What one frame did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PredictiveFrame {
    /// A batch was applied (an unmodified frame applied none).
    pub modified: bool,
    /// Requests sent this frame.
    pub sent: usize,
    /// The prediction span after the frame.
    pub span: usize,
    /// Requests in flight after the frame.
    pub in_flight: usize,
    /// Time to apply the batch (T_u).
    pub update: Duration,
    /// The time from a request to its batch (T_g), smoothed.
    pub round_trip: Option<Duration>,
    /// The applied batch's own time from its request to its arrival.
    pub batch_round_trip: Option<Duration>,
    /// The batch's bytes.
    pub bytes: usize,
    /// Budget mode was asked for in this frame's requests.
    pub budget_mode: bool,
}

/// A batch as the getting-updates thread hands it over.
struct Arrived {
    frame: u32,
    objects: Vec<ObjectUpdates>,
    bytes: usize,
    at: Instant,
}

/// The batches that arrive on `stream`, read on a thread of their own until the
/// connection ends or fails (the failure sent last).
fn get_updates(
    stream: &TcpStream,
) -> Result<mpsc::Receiver<Result<Arrived, StreamError>>, StreamError> {
    stream.set_read_timeout(None)?;
    let mut reader = stream.try_clone()?;
    let (tx, batches) = mpsc::channel();
    thread::Builder::new()
        .name("stream-get-updates".into())
        .spawn(move || loop {
            let got = match receive(&mut reader, MAX_TO_CLIENT) {
                Ok(Some((Message::Batch { frame, objects }, bytes))) => Ok(Arrived {
                    frame,
                    objects,
                    bytes,
                    at: Instant::now(),
                }),
                Ok(Some((Message::Refused(why), _))) => Err(StreamError::Refused(why)),
                Ok(Some((other, _))) => Err(StreamError::Malformed(format!(
                    "a {other:?} where a batch was due"
                ))),
                Ok(None) => return,
                Err(e) => Err(e),
            };
            let stop = got.is_err();
            if tx.send(got).is_err() || stop {
                return;
            }
        })?;
    Ok(batches)
}

/// A stream client that hides the round trip by prediction.
pub struct PredictiveClient {
    writer: TcpStream,
    /// Where the server is and how long to wait for it, to reconnect.
    server: SocketAddr,
    timeout: Duration,
    /// Whether the next frame tops the requests up (after a reconnection, none is in
    /// flight and no batch will come to make the frame a modified one).
    resumed: bool,
    batches: mpsc::Receiver<Result<Arrived, StreamError>>,
    objects: Vec<StreamedObject>,
    hello: Hello,
    refinement: Refinement,
    span: usize,
    /// Requests in flight: their target frame and when they were sent.
    in_flight: VecDeque<(u32, Instant)>,
    last_target: Option<u32>,
    /// The client's frame counter.
    frame: u32,
    /// The last three frames' eye and aim-at point, newest first.
    now: Option<(Vec3, Vec3)>,
    before: Option<(Vec3, Vec3)>,
    earlier: Option<(Vec3, Vec3)>,
    round_trip: Option<f64>,
    /// Whether f was measured once: until then it is measured every frame.
    span_measured: bool,
    period: Option<f64>,
    last_call: Option<Instant>,
}

impl PredictiveClient {
    /// Connects and says `hello`; `timeout` bounds the wait for WELCOME.
    pub fn connect(
        addr: impl ToSocketAddrs,
        hello: Hello,
        refinement: Refinement,
        timeout: Duration,
    ) -> Result<PredictiveClient, StreamError> {
        if !((1..=MAX_N).contains(&refinement.n)
            && refinement.tau.is_finite()
            && refinement.tau > 0.0)
        {
            return Err(StreamError::Malformed(format!(
                "a refinement of N = {} and τ = {}: N must be 1 to {MAX_N}, τ above 0",
                refinement.n, refinement.tau
            )));
        }
        let parts = StreamClient::connect(addr, hello, timeout)?.into_parts();
        let (stream, objects, server, timeout) =
            (parts.stream, parts.objects, parts.server, parts.timeout);
        let batches = get_updates(&stream)?;
        Ok(PredictiveClient {
            writer: stream,
            server,
            timeout,
            resumed: false,
            batches,
            objects,
            hello,
            refinement,
            span: refinement.initial_span.clamp(1, MAX_SPAN),
            in_flight: VecDeque::new(),
            last_target: None,
            frame: 0,
            now: None,
            before: None,
            earlier: None,
            // The greeting was a round trip: T_g's first measure, so that f is right as
            // soon as the frame period is known.
            round_trip: Some(parts.greeting.as_secs_f64()),
            span_measured: false,
            period: None,
            last_call: None,
        })
    }

    /// Connects to the server again, on a new connection, and resumes the session
    /// from the meshes this client holds (RESUME): after the connection broke (a
    /// [`PredictiveClient::frame`] that failed), or the server restarted. The requests
    /// in flight are forgotten; the next frame sends the span's worth again, predicted
    /// as ever. An `Err`, the client as it was, when the server cannot be reached or now
    /// streams other objects.
    pub fn reconnect(&mut self) -> Result<(), StreamError> {
        let next_frame = self.last_target.map_or(0, |t| t.saturating_add(1));
        let peer = (self.server, self.hello, self.timeout);
        let stream = crate::client::resume_session(peer, &self.objects, next_frame)?;
        self.batches = get_updates(&stream)?;
        self.writer = stream;
        self.in_flight.clear();
        self.resumed = true;
        Ok(())
    }

    /// The session's objects, as the batches so far made them.
    pub fn objects(&self) -> &[StreamedObject] {
        &self.objects
    }

    /// The session's objects, to take their changes ([`StreamedObject::take_changes`]).
    pub fn objects_mut(&mut self) -> &mut [StreamedObject] {
        &mut self.objects
    }

    /// One frame at the viewer's actual `eye` looking at `aim`: applies the oldest batch
    /// that has arrived, if any, and sends the requests the frame should (see the module
    /// comment). Call it once per rendered frame.
    pub fn frame(&mut self, eye: Vec3, aim: Vec3) -> Result<PredictiveFrame, StreamError> {
        let started = Instant::now();
        if let Some(last) = self.last_call.replace(started) {
            let p = started.duration_since(last).as_secs_f64();
            self.period = Some(self.period.map_or(p, |q| 0.8 * q + 0.2 * p));
        }
        self.earlier = self.before;
        self.before = self.now.replace((eye, aim));
        let mut report = PredictiveFrame::default();
        let arrived = match self.batches.try_recv() {
            Ok(got) => Some(got?),
            Err(mpsc::TryRecvError::Empty) => None,
            Err(mpsc::TryRecvError::Disconnected) => {
                return Err(StreamError::Refused("the server closed the session".into()))
            }
        };
        if let Some(batch) = arrived {
            let (target, sent) = self.in_flight.pop_front().ok_or_else(|| {
                StreamError::Malformed(format!("a batch for frame {} never asked", batch.frame))
            })?;
            if batch.frame != target {
                return Err(StreamError::Malformed(format!(
                    "the batch of frame {} where frame {target}'s was due",
                    batch.frame
                )));
            }
            let g = batch.at.duration_since(sent).as_secs_f64();
            report.batch_round_trip = Some(batch.at.duration_since(sent));
            self.round_trip = Some(self.round_trip.map_or(g, |r| 0.8 * r + 0.2 * g));
            let t = Instant::now();
            for o in batch.objects {
                let object = self.objects.get_mut(o.index as usize).ok_or_else(|| {
                    StreamError::Malformed(format!(
                        "updates for object {}, not in WELCOME",
                        o.index
                    ))
                })?;
                object.apply(o)?;
            }
            report.modified = true;
            report.update = t.elapsed();
            report.bytes = batch.bytes;
        }
        let before = self.span;
        if self.frame.is_multiple_of(ADJUST_EVERY) || !self.span_measured {
            self.adjust_span();
        }
        // The start sends f requests (RENDER-WAN); afterwards an unmodified frame sends
        // nothing, a modified one tops the requests in flight up to f, and one that
        // finds f grown sends the extra at once (Fig. 6.5).
        let start = self.frame == 0;
        let grew = self.span > before;
        if start || grew || report.modified || std::mem::take(&mut self.resumed) {
            report.budget_mode = self.alarm();
            while self.in_flight.len() < self.span {
                self.request(report.budget_mode, start)?;
                report.sent += 1;
            }
        }
        report.span = self.span;
        report.in_flight = self.in_flight.len();
        report.round_trip = self.round_trip.map(Duration::from_secs_f64);
        self.frame += 1;
        Ok(report)
    }

    /// f = ⌈T_g / (T_r + T_u)⌉, once both are measured.
    fn adjust_span(&mut self) {
        if let (Some(g), Some(p)) = (self.round_trip, self.period) {
            if p > 0.0 {
                self.span = ((g / p).ceil() as usize).clamp(1, MAX_SPAN);
                self.span_measured = true;
            }
        }
    }

    /// Whether an object's triangles have passed the alarm level L = B − 2·N·f.
    fn alarm(&self) -> bool {
        let Some(budget) = self.hello.budget else {
            return false;
        };
        let margin = 2 * self.refinement.n as usize * self.span;
        let level = (budget as usize).saturating_sub(margin);
        self.objects
            .iter()
            .any(|o| o.mesh().triangle_count() > level)
    }

    /// Sends the view predicted for the frame this request's batch will be applied at.
    fn request(&mut self, budget_mode: bool, start: bool) -> Result<(), StreamError> {
        let ahead = self.in_flight.len() as u32 + 1;
        let target = (self.frame + ahead).max(self.last_target.map_or(0, |t| t + 1));
        let (eye, aim) = self.now.expect("a frame's view is taken first");
        // At the start the motion is not known: the current view stands for the first
        // f frames (§6.2).
        let f = (target - self.frame) as f32;
        let (e, a) = if start {
            (eye, aim)
        } else {
            let p = self.refinement.predictor;
            p.predict(f, (eye, aim), self.before, self.earlier)
        };
        let view = ViewPacket {
            frame: target,
            eye: e.to_array(),
            aim: a.to_array(),
            tau: self.refinement.tau,
            budget_mode,
            n: self.refinement.n,
        };
        send(&mut self.writer, &Message::View(view))?;
        self.in_flight.push_back((target, Instant::now()));
        self.last_target = Some(target);
        Ok(())
    }

    /// Ends the session.
    pub fn bye(mut self) -> Result<(), StreamError> {
        send(&mut self.writer, &Message::Bye)?;
        Ok(())
    }
}
