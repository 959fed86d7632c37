//! A stream session as a walk's landmarks (`flaneur walk --stream`): the walk draws
//! the city's ordinary objects as ever and its landmarks from the predictive client's
//! selective meshes, which the server's batches change (Zheng 2007 ch. 5–6). Each frame
//! the walk tells the client where the viewer is ([`RemoteRefinements::frame`]), the
//! client applies the oldest batch that has arrived and sends its predicted views, and
//! the renderer uploads the ranges the batches changed.
//!
//! The session's figures (batches, bytes, round trip, prediction span) are kept where
//! the caller can read them during and after the walk ([`StreamFigures`]).
//!
//! A session that breaks (the server restarted, the network dropped) does not stop the
//! walk: the landmarks are drawn as they stand while the client reconnects and resumes
//! from the meshes it holds, at once and then every [`RETRY_AFTER`]; the figures count
//! the frames drawn so and keep the last failure.

use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use flaneur::geom::Camera;
use flaneur::walk::lod_select::RefinedView;
use flaneur::walk::RemoteRefinements;

use crate::predictive::PredictiveClient;

/// What a walk's stream session did so far.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StreamFigures {
    /// Frames the walk asked the client for.
    pub frames: u64,
    /// Frames that applied a batch.
    pub modified: u64,
    /// Views sent.
    pub views: u64,
    /// Bytes of the batches applied, and the largest.
    pub bytes: u64,
    pub largest_batch: usize,
    /// The measured round trip (a moving average), once a batch has come.
    pub round_trip: Option<Duration>,
    /// The prediction span f, in frames.
    pub span: usize,
    /// Times the session was resumed on a new connection.
    pub reconnects: u64,
    /// Frames drawn while the session was broken (the landmarks as they stood).
    pub broken_frames: u64,
    /// The last failure of the session, in words.
    pub last_failure: Option<String>,
}

/// How long a broken session waits before it tries to reconnect again.
pub const RETRY_AFTER: Duration = Duration::from_secs(1);

/// A predictive stream client as the objects a walk draws from elsewhere.
pub struct StreamedLandmarks {
    client: PredictiveClient,
    /// Each streamed object's place in the session, by its id.
    index: HashMap<u64, usize>,
    figures: Arc<Mutex<StreamFigures>>,
    /// The batches of the last second: when each came and its bytes.
    recent: VecDeque<(Instant, usize)>,
    /// When the session broke and the last reconnection failed; `None` while it runs.
    broken_since: Option<Instant>,
}

impl StreamedLandmarks {
    /// The landmarks of `client`'s session (its objects' ids are the database's), and
    /// where its figures are kept.
    pub fn new(client: PredictiveClient) -> (StreamedLandmarks, Arc<Mutex<StreamFigures>>) {
        let index = client
            .objects()
            .iter()
            .enumerate()
            .map(|(i, o)| (o.id, i))
            .collect();
        let figures = Arc::new(Mutex::new(StreamFigures::default()));
        let landmarks = StreamedLandmarks {
            client,
            index,
            figures: figures.clone(),
            recent: VecDeque::new(),
            broken_since: None,
        };
        (landmarks, figures)
    }
}

impl StreamedLandmarks {
    /// The stream client, as the batches so far left it.
    pub fn client(&self) -> &PredictiveClient {
        &self.client
    }

    /// Tries to resume the broken session on a new connection; whether it did.
    fn resume(&mut self, s: &mut StreamFigures) -> bool {
        match self.client.reconnect() {
            Ok(()) => {
                s.reconnects += 1;
                self.broken_since = None;
                true
            }
            Err(e) => {
                s.last_failure = Some(format!("reconnecting: {e}"));
                self.broken_since = Some(Instant::now());
                false
            }
        }
    }
}

impl RemoteRefinements for StreamedLandmarks {
    fn refines(&self, id: u64) -> bool {
        self.index.contains_key(&id)
    }

    fn frame(&mut self, camera: &Camera) -> flaneur::Result<()> {
        let figures = self.figures.clone();
        let mut s = figures.lock().unwrap_or_else(|p| p.into_inner());
        s.frames += 1;
        if let Some(since) = self.broken_since {
            // Drawn as they stand until a reconnection, tried every RETRY_AFTER, works.
            if since.elapsed() < RETRY_AFTER || !self.resume(&mut s) {
                s.broken_frames += 1;
                return Ok(());
            }
        }
        let eye = camera.position;
        let f = match self.client.frame(eye, eye + camera.forward()) {
            Ok(f) => f,
            Err(e) => {
                s.last_failure = Some(e.to_string());
                s.broken_frames += 1;
                self.broken_since = Some(Instant::now());
                self.resume(&mut s);
                return Ok(());
            }
        };
        s.modified += u64::from(f.modified);
        s.views += f.sent as u64;
        s.bytes += f.bytes as u64;
        s.largest_batch = s.largest_batch.max(f.bytes);
        s.round_trip = f.round_trip;
        s.span = f.span;
        let now = Instant::now();
        if f.modified {
            self.recent.push_back((now, f.bytes));
        }
        while self
            .recent
            .front()
            .is_some_and(|(at, _)| now.duration_since(*at) > Duration::from_secs(1))
        {
            self.recent.pop_front();
        }
        Ok(())
    }

    fn status(&self) -> Option<String> {
        let s = self.figures.lock().unwrap_or_else(|p| p.into_inner());
        if self.broken_since.is_some() {
            return Some(format!(
                "broken, reconnecting: {}",
                s.last_failure.as_deref().unwrap_or("?")
            ));
        }
        let per_second: usize = self.recent.iter().map(|(_, b)| b).sum();
        let last = self.recent.back().map_or(0, |(_, b)| *b);
        Some(format!(
            "round trip {}, span {}, last batch {:.1} KiB, {} batches in the last second, \
             {:.1} KiB/s",
            s.round_trip
                .map_or("-".into(), |t| format!("{:.1} ms", t.as_secs_f64() * 1e3)),
            s.span,
            last as f64 / 1024.0,
            self.recent.len(),
            per_second as f64 / 1024.0
        ))
    }

    fn triangles(&self, id: u64) -> usize {
        self.index
            .get(&id)
            .map_or(0, |&i| self.client.objects()[i].mesh().triangle_count())
    }

    fn refined(&mut self, id: u64) -> Option<RefinedView<'_>> {
        let &i = self.index.get(&id)?;
        let object = &mut self.client.objects_mut()[i];
        let pending = object.take_changes();
        Some(RefinedView {
            pending,
            capacity: object.capacity(),
            mesh: object.mesh(),
        })
    }
}
