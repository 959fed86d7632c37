//! A stream session as a walk's landmarks (`flaneur walk --stream`): the walk draws
//! the city's ordinary objects as ever and its landmarks from the predictive client's
//! selective meshes, which the server's batches change (Zheng 2007 ch. 5–6). Each frame
//! the walk tells the client where the viewer is ([`RemoteRefinements::frame`]), the
//! client applies the oldest batch that has arrived and sends its predicted views, and
//! the renderer uploads the ranges the batches changed.
//!
//! The session's figures (batches, bytes, round trip, prediction span) are kept where
//! the caller can read them during and after the walk ([`StreamFigures`]).

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
}

/// A predictive stream client as the objects a walk draws from elsewhere.
pub struct StreamedLandmarks {
    client: PredictiveClient,
    /// Each streamed object's place in the session, by its id.
    index: HashMap<u64, usize>,
    figures: Arc<Mutex<StreamFigures>>,
    /// The batches of the last second: when each came and its bytes.
    recent: VecDeque<(Instant, usize)>,
    last: StreamFigures,
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
            last: StreamFigures::default(),
        };
        (landmarks, figures)
    }
}

impl RemoteRefinements for StreamedLandmarks {
    fn refines(&self, id: u64) -> bool {
        self.index.contains_key(&id)
    }

    fn frame(&mut self, camera: &Camera) -> flaneur::Result<()> {
        let eye = camera.position;
        let f = self
            .client
            .frame(eye, eye + camera.forward())
            .map_err(|e| flaneur::Error::Invalid(format!("stream session: {e}")))?;
        let mut s = self.figures.lock().unwrap_or_else(|p| p.into_inner());
        s.frames += 1;
        s.modified += u64::from(f.modified);
        s.views += f.sent as u64;
        s.bytes += f.bytes as u64;
        s.largest_batch = s.largest_batch.max(f.bytes);
        s.round_trip = f.round_trip;
        s.span = f.span;
        self.last = s.clone();
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
        let s = &self.last;
        let per_second: usize = self.recent.iter().map(|(_, b)| b).sum();
        Some(format!(
            "round trip {}, span {}, {} batches in the last second, {:.1} KiB/s",
            s.round_trip
                .map_or("-".into(), |t| format!("{:.1} ms", t.as_secs_f64() * 1e3)),
            s.span,
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
