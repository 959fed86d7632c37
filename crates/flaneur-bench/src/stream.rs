//! The `stream` experiment (Zheng 2007 Table 5.1, Table 6.1, Fig. 6.6): a landmark
//! streamed from `flaneur_stream`'s server through a loopback link of set round trip,
//! the client sequential (each frame waits for its own batch) or predictive (f frames
//! ahead, `PredictiveClient`), along the scripted orbit of `lod_orbit` at a set frame
//! period. Per walk: frame time, prediction span, unmodified frames, bytes, and every 5
//! frames the accuracy, the share of the reference selective mesh's triangles that the
//! streamed one holds, the reference being the same traversal run locally at the actual
//! view each frame (Zheng §5.4, §6.4).
//!
//! The landmark (our choice, as in `lod_refine`) is a bumpy torus of the Happy Buddha's
//! 1,087,474 triangles. The client does not draw; it waits out the rest of each frame
//! period, standing for T_r. The link is `link`'s relay, which delays each direction by
//! half the round trip.

use std::net::SocketAddr;
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec3;

use crate::link::{Link, LinkSpec};
use crate::lod_orbit::orbit_path;
use crate::plot::{line_plot, LinePlot, Series};
use crate::report::Report;
use crate::walk_setup::check_sweep;
use flaneur::error::{Error, Result};
use flaneur::lod::{
    bumpy_torus, Criteria, Dag, DagConstruction, ProgressiveMesh, RefineParams, Refiner, Traversal,
    View,
};
use flaneur_stream::{
    Hello, Landmark, PredictiveClient, Predictor, Refinement, ServerConfig, StreamClient,
    StreamServer, ViewPacket,
};

/// Zheng's Table 6.1: round trip (ms), prediction span, accuracy.
pub const THESIS_TABLE_6_1: [(u32, usize, f64); 4] = [
    (80, 3, 0.89),
    (170, 6, 0.88),
    (260, 9, 0.85),
    (350, 12, 0.79),
];

/// The settings of the experiment.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StreamBenchConfig {
    /// Triangles of the bumpy torus.
    pub triangles: usize,
    /// Frames of each walk.
    pub frames: usize,
    /// The client's frame period, ms (T_r + T_u; the thesis's frames took 28–30 ms).
    pub frame_ms: f64,
    /// Round trips of the link, ms.
    pub rtts_ms: Vec<u32>,
    /// τ, a fraction of the viewport.
    pub tau: f32,
    /// N.
    pub n: u32,
    /// The triangle budget (the thesis's 60,000).
    pub budget: u32,
    /// The view cone, degrees.
    pub fov_degrees: f32,
    /// The predictive clients walked at each round trip, one per predictor.
    #[serde(skip)]
    pub predictors: Vec<Predictor>,
    /// Walk the sequential client too (most of the experiment's time at long round trips).
    pub sequential: bool,
}

impl Default for StreamBenchConfig {
    fn default() -> StreamBenchConfig {
        StreamBenchConfig {
            triangles: crate::lod_refine::DEFAULT_TRIANGLES,
            frames: crate::lod_refine::DEFAULT_FRAMES,
            frame_ms: 30.0,
            rtts_ms: THESIS_TABLE_6_1.iter().map(|r| r.0).collect(),
            // Where the view asks for about the budget (docs/lod.md).
            tau: 0.0002,
            n: flaneur_stream::protocol::MAX_N,
            budget: flaneur::lod::THESIS_BUDGET as u32,
            fov_degrees: crate::lod_refine::DEFAULT_FOV_DEGREES,
            predictors: vec![Predictor::Linear, Predictor::Quadratic],
            sequential: true,
        }
    }
}

impl StreamBenchConfig {
    /// Checks the sweep and the settings.
    pub fn validate(&self) -> Result<()> {
        if self.frames < 10 || !(self.frame_ms.is_finite() && self.frame_ms > 0.0) {
            return Err(Error::Invalid(format!(
                "stream: {} frames of {} ms; give at least 10 frames of a positive period",
                self.frames, self.frame_ms
            )));
        }
        if !((1..=flaneur_stream::protocol::MAX_N).contains(&self.n)
            && self.tau.is_finite()
            && self.tau > 0.0)
        {
            return Err(Error::Invalid(format!(
                "stream: N = {} and τ = {}; N must be 1 to 500, τ above 0",
                self.n, self.tau
            )));
        }
        if self.predictors.is_empty() && !self.sequential {
            return Err(Error::Invalid(
                "stream: no client to walk (give a predictor, or the sequential client)".into(),
            ));
        }
        check_sweep("round trip", &self.rtts_ms, |_| Ok(()))
    }
}

/// How the client got its batches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClientMode {
    /// Each frame sends its view and waits for its batch (Zheng Fig. 5.1).
    Sequential,
    /// f frames ahead, never waiting (Figs. 6.1–6.5), predicting so.
    Predictive(Predictor),
}

impl ClientMode {
    /// "sequential", "linear" or "quadratic".
    pub fn name(self) -> &'static str {
        match self {
            ClientMode::Sequential => "sequential",
            ClientMode::Predictive(Predictor::Linear) => "linear",
            ClientMode::Predictive(Predictor::Quadratic) => "quadratic",
        }
    }
}

/// One walk's figures.
#[derive(Clone, Debug, serde::Serialize)]
pub struct StreamRow {
    pub rtt_ms: u32,
    #[serde(skip)]
    pub mode: ClientMode,
    pub frames: usize,
    pub mean_frame_ms: f64,
    pub max_frame_ms: f64,
    /// The prediction span at the end, and its mean over the frames.
    pub final_span: usize,
    pub mean_span: f64,
    /// Frames that applied no batch.
    pub unmodified: usize,
    /// The mean accuracy over the measured frames after the first `warm_up`, and over all.
    pub accuracy: f64,
    pub accuracy_all: f64,
    pub warm_up: usize,
    /// The mean accuracy from frame `steady` on, the mesh grown and the orbit at its
    /// steady speed.
    pub accuracy_steady: f64,
    pub steady: usize,
    /// The measured round trip of a batch (T_g), ms, at the end.
    pub round_trip_ms: Option<f64>,
    pub bytes: u64,
    /// Every 5th frame's accuracy: (frame, accuracy).
    pub accuracies: Vec<(usize, f64)>,
}

/// The experiment's rows.
#[derive(Clone, Debug, serde::Serialize)]
pub struct StreamReport {
    pub config: StreamBenchConfig,
    pub model_triangles: usize,
    pub rows: Vec<StreamRow>,
}

/// Frames before the accuracy counts: the thesis's first 50 frames are its warm-up
/// (the mesh growing from the base, §5.4), in its 180-frame paths.
fn warm_up(frames: usize) -> usize {
    frames * 50 / 180
}

/// The frame from which the mesh has grown from its base, whatever the round trip,
/// and the orbit turns at its steady speed (from frame 75 of 180): frame 100 of 180.
fn steady(frames: usize) -> usize {
    frames * 100 / 180
}

/// The experiments' landmark: a bumpy torus of about `triangles` triangles with its
/// progressive mesh and DAG, and the centre and radius of its bounding sphere (the
/// orbit's).
pub fn torus_landmark(triangles: usize) -> Result<(Landmark, Vec3, f32)> {
    let mesh = bumpy_torus(triangles);
    let pm = ProgressiveMesh::build(&mesh)?;
    let dag = Dag::build(&pm, DagConstruction::MiniRedundant)?;
    let (lo, hi) = mesh.bounds();
    let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
    let landmark = Landmark {
        id: 0,
        pm: Arc::new(pm),
        dag: Arc::new(dag),
    };
    Ok((landmark, 0.5 * (lo + hi), 0.5 * (hi - lo).length()))
}

/// Builds the landmark, serves it on loopback and walks the orbit through a link at each
/// round trip, sequential then predictive. `progress` is told each walk as it starts.
pub fn run(cfg: &StreamBenchConfig, mut progress: impl FnMut(&str)) -> Result<StreamReport> {
    cfg.validate()?;
    progress("building the landmark's progressive mesh and DAG");
    let (landmark, centre, radius) = torus_landmark(cfg.triangles)?;
    let model_triangles = landmark.triangles();
    let fov = cfg.fov_degrees.to_radians();
    let views = orbit_path(centre, radius, cfg.frames, fov)?;
    let server = StreamServer::bind(
        "127.0.0.1:0",
        vec![landmark.clone()],
        ServerConfig::default(),
    )
    .map_err(stream_error)?
    .spawn()
    .map_err(stream_error)?;
    let mut rows = Vec::new();
    for &rtt_ms in &cfg.rtts_ms {
        let modes = cfg
            .sequential
            .then_some(ClientMode::Sequential)
            .into_iter()
            .chain(cfg.predictors.iter().map(|&p| ClientMode::Predictive(p)));
        for mode in modes {
            progress(&format!("{} client, {rtt_ms} ms round trip", mode.name()));
            let link = Link::start(
                server.addr(),
                LinkSpec {
                    rtt: Duration::from_millis(u64::from(rtt_ms)),
                    mbit: None,
                },
            )
            .map_err(|e| Error::Invalid(format!("stream: starting the link: {e}")))?;
            rows.push(walk(
                cfg,
                &landmark,
                link.addr(),
                &views,
                centre,
                mode,
                rtt_ms,
            )?);
        }
    }
    Ok(StreamReport {
        config: cfg.clone(),
        model_triangles,
        rows,
    })
}

fn stream_error(e: flaneur_stream::StreamError) -> Error {
    match e {
        flaneur_stream::StreamError::Engine(e) => e,
        e => Error::Invalid(format!("stream: {e}")),
    }
}

/// One walk of the orbit through the link at `addr`.
fn walk(
    cfg: &StreamBenchConfig,
    landmark: &Landmark,
    addr: SocketAddr,
    views: &[View],
    centre: Vec3,
    mode: ClientMode,
    rtt_ms: u32,
) -> Result<StreamRow> {
    let hello = Hello {
        traversal: Traversal::Priority,
        fov: cfg.fov_degrees.to_radians(),
        budget: Some(cfg.budget),
        out_of_view: true,
        back_face: true,
        scheme: flaneur_stream::Scheme::Dag,
    };
    let params = RefineParams {
        traversal: hello.traversal,
        tau: cfg.tau,
        budget: Some(cfg.budget as usize),
        max_work: cfg.n as usize,
        criteria: Criteria::default(),
    };
    let mut reference = Refiner::new(&landmark.pm, &landmark.dag)?;
    let timeout = Duration::from_secs(30);
    let aim_of = |v: &View| v.eye + v.look * (centre - v.eye).length().max(1e-3);
    let period = Duration::from_secs_f64(cfg.frame_ms / 1e3);
    let (mut sequential, mut predictive) = (None, None);
    match mode {
        ClientMode::Sequential => {
            sequential = Some(StreamClient::connect(addr, hello, timeout).map_err(stream_error)?)
        }
        ClientMode::Predictive(predictor) => {
            let refinement = Refinement {
                tau: cfg.tau,
                n: cfg.n,
                initial_span: 1,
                predictor,
            };
            predictive = Some(
                PredictiveClient::connect(addr, hello, refinement, timeout)
                    .map_err(stream_error)?,
            )
        }
    }
    let mut row = StreamRow {
        rtt_ms,
        mode,
        frames: views.len(),
        mean_frame_ms: 0.0,
        max_frame_ms: 0.0,
        final_span: 0,
        mean_span: 0.0,
        unmodified: 0,
        accuracy: 0.0,
        accuracy_all: 0.0,
        warm_up: warm_up(views.len()),
        accuracy_steady: 0.0,
        steady: steady(views.len()),
        round_trip_ms: None,
        bytes: 0,
        accuracies: Vec::new(),
    };
    let mut next = Instant::now();
    let mut span_sum = 0usize;
    for (f, v) in views.iter().enumerate() {
        let started = Instant::now();
        let aim = aim_of(v);
        if let Some(c) = sequential.as_mut() {
            let view = ViewPacket {
                frame: f as u32,
                eye: v.eye.to_array(),
                aim: aim.to_array(),
                tau: cfg.tau,
                budget_mode: true,
                n: cfg.n,
            };
            c.send_view(&view).map_err(stream_error)?;
            row.bytes += c.receive_batch().map_err(stream_error)?.bytes as u64;
            row.final_span = 0;
        }
        if let Some(c) = predictive.as_mut() {
            let got = c.frame(v.eye, aim).map_err(stream_error)?;
            row.unmodified += usize::from(!got.modified);
            row.bytes += got.bytes as u64;
            row.final_span = got.span;
            row.round_trip_ms = got.round_trip.map(|d| d.as_secs_f64() * 1e3);
            span_sum += got.span;
        }
        // The reference: the same traversal at the actual view, locally.
        let actual = View::new(v.eye, aim - v.eye, v.fov)?;
        reference.refine(&actual, &params)?;
        if f % 5 == 0 {
            let streamed = match (&sequential, &predictive) {
                (Some(c), _) => c.objects()[0].mesh(),
                (_, Some(c)) => c.objects()[0].mesh(),
                _ => unreachable!("one client"),
            };
            row.accuracies
                .push((f, streamed.shared_with(reference.mesh())));
        }
        // The rest of the frame period stands for drawing.
        next += period;
        if let Some(wait) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        } else {
            next = Instant::now();
        }
        let ms = started.elapsed().as_secs_f64() * 1e3;
        row.mean_frame_ms += ms / views.len() as f64;
        row.max_frame_ms = row.max_frame_ms.max(ms);
    }
    row.mean_span = span_sum as f64 / views.len() as f64;
    let mean = |a: &[(usize, f64)]| a.iter().map(|x| x.1).sum::<f64>() / a.len().max(1) as f64;
    let from = |first: usize| -> Vec<(usize, f64)> {
        row.accuracies
            .iter()
            .copied()
            .filter(|&(f, _)| f >= first)
            .collect()
    };
    row.accuracy = mean(&from(row.warm_up));
    row.accuracy_steady = mean(&from(row.steady));
    row.accuracy_all = mean(&row.accuracies);
    if let Some(c) = sequential {
        let _ = c.bye();
    }
    if let Some(c) = predictive {
        let _ = c.bye();
    }
    Ok(row)
}

/// The plot's file name.
pub const PLOT: &str = "stream-accuracy.png";

impl Report for StreamReport {
    fn name(&self) -> &'static str {
        "stream"
    }

    fn to_csv(&self) -> String {
        let mut s = String::from("rtt_ms,client,frames,mean_frame_ms,max_frame_ms,final_span,mean_span,unmodified,accuracy,accuracy_all,accuracy_steady,round_trip_ms,bytes\n");
        for r in &self.rows {
            s.push_str(&format!(
                "{},{},{},{:.2},{:.2},{},{:.2},{},{:.4},{:.4},{:.4},{},{}\n",
                r.rtt_ms,
                r.mode.name(),
                r.frames,
                r.mean_frame_ms,
                r.max_frame_ms,
                r.final_span,
                r.mean_span,
                r.unmodified,
                r.accuracy,
                r.accuracy_all,
                r.accuracy_steady,
                r.round_trip_ms.map_or(String::new(), |t| format!("{t:.1}")),
                r.bytes
            ));
        }
        s
    }

    fn markdown(&self) -> String {
        let c = &self.config;
        let mut md = format!(
            "# stream — latency hidden by prediction (Zheng 2007 Tables 5.1, 6.1, Fig. 6.6)\n\n\
             A bumpy torus of {} triangles streamed from the stream server through a loopback \
             link; {} frames of the orbit at a {} ms frame period; the priority-oriented \
             traversal, τ = {} % of the viewport, N = {}, a budget of {} triangles. Accuracy: \
             the share of the reference mesh's triangles (the same traversal at the actual \
             view, locally) the streamed mesh holds, every 5 frames, after the first {} frames \
             (the warm-up), from frame {} on (the mesh grown, the orbit at its steady speed) \
             and over all.\n\n\
             | round trip | client | frame ms, mean (max) | span, end (mean) | thesis span | unmodified frames | accuracy | thesis | steady | over all frames | T_g ms | KiB/s |\n\
             |---|---|---|---|---|---|---|---|---|---|---|---|\n",
            self.model_triangles,
            c.frames,
            c.frame_ms,
            100.0 * c.tau,
            c.n,
            c.budget,
            self.rows.first().map_or(0, |r| r.warm_up),
            self.rows.first().map_or(0, |r| r.steady)
        );
        for r in &self.rows {
            let thesis = THESIS_TABLE_6_1.iter().find(|t| t.0 == r.rtt_ms);
            let (span, acc) = match (r.mode, thesis) {
                (ClientMode::Predictive(_), Some(t)) => {
                    (t.1.to_string(), format!("{:.0} %", 100.0 * t.2))
                }
                _ => ("–".into(), "–".into()),
            };
            let secs = r.mean_frame_ms * r.frames as f64 / 1e3;
            md.push_str(&format!(
                "| {} ms | {} | {:.1} ({:.1}) | {} ({:.1}) | {span} | {} | {:.1} % | {acc} | {:.1} % | {:.1} % | {} | {:.0} |\n",
                r.rtt_ms,
                r.mode.name(),
                r.mean_frame_ms,
                r.max_frame_ms,
                r.final_span,
                r.mean_span,
                r.unmodified,
                100.0 * r.accuracy,
                100.0 * r.accuracy_steady,
                100.0 * r.accuracy_all,
                r.round_trip_ms.map_or("–".into(), |t| format!("{t:.0}")),
                r.bytes as f64 / 1024.0 / secs.max(1e-9)
            ));
        }
        md.push_str(
            "\nThe sequential client waits a round trip every frame (Table 5.1's sequential \
             method), so its frame time is the round trip and more, and its mesh is the \
             reference's; the predictive one keeps its frame period and pays in accuracy \
             (Table 6.1). `linear` predicts as Zheng does (first order); `quadratic` is ours, \
             of second order, which follows a turn where the first order leaves it by its \
             tangent. Frame times are wall-clock on this machine; the link adds its round \
             trip to every byte.\n",
        );
        md
    }

    fn plot(&self, dir: &Path) -> Result<()> {
        let series = self
            .rows
            .iter()
            .filter(|r| r.mode != ClientMode::Sequential)
            .map(|r| Series {
                name: format!("{}, {} ms (span {})", r.mode.name(), r.rtt_ms, r.final_span),
                points: r
                    .accuracies
                    .iter()
                    .map(|&(f, a)| (f as f64, 100.0 * a))
                    .collect(),
            })
            .collect();
        line_plot(
            &dir.join(PLOT),
            &LinePlot {
                title: "Accuracy of the predictive client (Fig. 6.6)".into(),
                x_label: "frame".into(),
                y_label: "accuracy (%)".into(),
                series,
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flaneur_stream::{PredictiveClient, Refinement, ServerConfig, StreamServer};

    /// The greeting is the session's first round trip: over a 100 ms link at 20 ms
    /// frames, the span is right at the second frame, which sends the extra requests at
    /// once, where the span measured from batches alone waits for one to come back.
    #[test]
    fn the_span_is_set_from_the_greeting_at_the_second_frame() {
        let (landmark, centre, radius) = torus_landmark(2_000).unwrap();
        let server = StreamServer::bind("127.0.0.1:0", vec![landmark], ServerConfig::default())
            .unwrap()
            .spawn()
            .unwrap();
        let spec = LinkSpec {
            rtt: Duration::from_millis(100),
            mbit: None,
        };
        let link = Link::start(server.addr(), spec).unwrap();
        let hello = Hello {
            traversal: Traversal::Priority,
            fov: 1.0,
            budget: None,
            out_of_view: true,
            back_face: true,
            scheme: flaneur_stream::Scheme::Dag,
        };
        let refinement = Refinement {
            tau: 0.001,
            n: 100,
            initial_span: 1,
            predictor: Predictor::Quadratic,
        };
        let mut client =
            PredictiveClient::connect(link.addr(), hello, refinement, Duration::from_secs(20))
                .unwrap();
        let eye = centre + Vec3::new(0.0, 0.0, 3.0 * radius);
        let first = client.frame(eye, centre).unwrap();
        assert_eq!((first.span, first.sent), (1, 1));
        std::thread::sleep(Duration::from_millis(20));
        let second = client.frame(eye, centre).unwrap();
        assert!(!second.modified, "no batch can have come in 20 ms");
        // The greeting took the link's round trip; the span is that over the period
        // (100 ms over 20 ms frames here, fewer frames if the machine is slow to wake).
        assert!(
            second.round_trip >= Some(Duration::from_millis(100)),
            "{second:?}"
        );
        assert!(second.span >= 2, "{second:?}");
        assert_eq!(second.sent, second.span - 1, "{second:?}");
        assert_eq!(second.in_flight, second.span);
    }
}
