//! The `stream-blocks` experiment (El-Sana's client-server paper, Table 1): a walk past
//! a landmark streamed by each scheme over loopback TCP, through a link of set round
//! trip, and what a frame costs on average: the triangles drawn, the split and merge
//! operations, the bytes sent and the time the frame's refinement took.
//!
//! The walk is `lod_orbit`'s orbit of the bumpy torus, at a set frame period (the rest
//! of each frame, standing for drawing, is slept, and is the server's idle time). The
//! schemes, each its own session with one server:
//! - Zheng's DAG scheme, sequential (each frame waits for its batch; free mode under τ,
//!   N = 500): its operations are the DAG nodes a batch collapses and splits;
//! - Kim–Lee–Kobbelt's truly selective scheme, the client refining on its own and
//!   asking only for the splits it lacks;
//! - El-Sana's blocks, the client keeping every block, the server never predicting;
//! - the same with the server's idle-time prediction (a second server);
//! - and with a bounded cache on the client too.
//!
//! The truly selective schemes' operations are the vertex splits and collapses the
//! client made (`SelectiveClient::operations`).

use std::net::SocketAddr;
use std::path::Path;
use std::time::{Duration, Instant};

use crate::link::{Link, LinkSpec};
use crate::lod_orbit::orbit_path;
use crate::report::Report;
use flaneur::error::{Error, Result};
use flaneur::lod::{Traversal, View};
use flaneur_stream::protocol::MAX_N;
use flaneur_stream::{
    BlockStreamClient, Hello, Landmark, RunningServer, Scheme, SelectiveStreamClient, ServerConfig,
    StreamClient, StreamError, StreamServer, ViewPacket,
};

/// El-Sana's Table 1: dataset, triangles, and per frame the triangles (K), split/merge
/// operations (K), blocks sent (KB) and time (ms).
pub const EL_SANA_TABLE_1: [(&str, u32, f64, f64, f64, f64); 4] = [
    ("Dragon", 300_000, 72.0, 1.6, 0.5, 240.0),
    ("Terrain", 522_000, 80.0, 1.8, 0.6, 230.0),
    ("Palace", 760_000, 83.0, 2.3, 0.64, 243.0),
    ("VR-City", 1_250_000, 91.0, 2.6, 0.68, 260.0),
];

/// The settings of the experiment.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StreamBlocksConfig {
    /// Triangles of the bumpy torus.
    pub triangles: usize,
    /// Frames of the walk.
    pub frames: usize,
    /// The frame period, ms: what a frame's refinement leaves of it is slept.
    pub frame_ms: f64,
    /// The link's round trip, ms (0: straight to the server).
    pub rtt_ms: u32,
    /// τ, a fraction of the viewport.
    pub tau: f32,
    /// Levels of a block.
    pub levels: u8,
    /// Blocks the bounded cache keeps beyond those the mesh uses.
    pub cache_blocks: usize,
    /// Blocks a prediction asks for.
    pub predict_blocks: usize,
    /// The server's wait after an answer before it predicts, ms.
    pub idle_ms: u64,
    /// The view cone's full angle, degrees.
    pub fov_degrees: f32,
}

impl Default for StreamBlocksConfig {
    fn default() -> StreamBlocksConfig {
        StreamBlocksConfig {
            triangles: crate::lod_refine::DEFAULT_TRIANGLES,
            frames: 180,
            frame_ms: 30.0,
            rtt_ms: 80,
            // About 70,000 triangles a frame, as El-Sana's datasets drew 72,000–91,000.
            tau: 0.0002,
            levels: 2,
            cache_blocks: 2_000,
            predict_blocks: 64,
            idle_ms: 5,
            fov_degrees: crate::lod_refine::DEFAULT_FOV_DEGREES,
        }
    }
}

impl StreamBlocksConfig {
    /// An `Err` naming the first setting out of range.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: String| Err(Error::Invalid(format!("stream-blocks: {what}")));
        if self.frames < 2 || self.triangles < 100 {
            return bad(format!(
                "{} frames of a {}-triangle torus: give at least 2 frames and 100 triangles",
                self.frames, self.triangles
            ));
        }
        if !(self.tau > 0.0 && self.tau < 1.0) {
            return bad(format!("τ = {}: give it within (0, 1)", self.tau));
        }
        if !(self.frame_ms.is_finite() && self.frame_ms >= 0.0) {
            return bad(format!("a frame period of {} ms", self.frame_ms));
        }
        if self.levels == 0 {
            return bad("blocks of 0 levels: give at least 1".into());
        }
        if !(self.fov_degrees > 0.0 && self.fov_degrees < 180.0) {
            return bad(format!(
                "a field of view of {}°: give it within (0°, 180°)",
                self.fov_degrees
            ));
        }
        Ok(())
    }
}

/// One scheme's walk, averaged per frame.
#[derive(Clone, Debug, serde::Serialize)]
pub struct StreamBlocksRow {
    pub scheme: &'static str,
    pub frames: usize,
    /// Triangles of the landmark's mesh after the frame's refinement.
    pub triangles: f64,
    /// Split and merge operations.
    pub operations: f64,
    /// Bytes received from the server (answers and predictions).
    pub bytes: f64,
    /// Round trips (views or switches answered).
    pub round_trips: f64,
    /// The frame's refinement, ms: mean, 95th percentile, largest.
    pub time_ms: f64,
    pub time_p95_ms: f64,
    pub time_max_ms: f64,
    /// Over the walk (the schemes of blocks): blocks received in answers, predicted
    /// blocks taken and discarded, blocks dropped from the cache.
    pub blocks: usize,
    pub predicted_kept: usize,
    pub predicted_discarded: usize,
    pub dropped: usize,
}

/// Every scheme's walk.
#[derive(Clone, Debug, serde::Serialize)]
pub struct StreamBlocksReport {
    pub config: StreamBlocksConfig,
    pub model_triangles: usize,
    pub rows: Vec<StreamBlocksRow>,
}

/// What one frame of a scheme did.
#[derive(Default)]
struct Frame {
    triangles: usize,
    operations: u64,
    bytes: usize,
    round_trips: usize,
}

fn stream_error(e: StreamError) -> Error {
    Error::Invalid(format!("stream-blocks: {e}"))
}

/// A scheme's session, frame by frame.
enum Session {
    Dag(StreamClient),
    Selective(SelectiveStreamClient),
    Blocks(BlockStreamClient),
}

impl Session {
    fn connect(addr: SocketAddr, hello: Hello, cache: Option<usize>) -> Result<Session> {
        let timeout = Duration::from_secs(60);
        Ok(match hello.scheme {
            Scheme::Dag => {
                Session::Dag(StreamClient::connect(addr, hello, timeout).map_err(stream_error)?)
            }
            Scheme::Blocks => {
                let mut c =
                    BlockStreamClient::connect(addr, hello, timeout).map_err(stream_error)?;
                if let Some(blocks) = cache {
                    c = c.with_capacity(blocks);
                }
                Session::Blocks(c)
            }
            _ => Session::Selective(
                SelectiveStreamClient::connect(addr, hello, timeout).map_err(stream_error)?,
            ),
        })
    }

    /// Refines the landmark for `v`, whose frame is at least the last one's plus the
    /// round trips it took.
    fn frame(&mut self, v: &ViewPacket, row: &mut StreamBlocksRow) -> Result<Frame> {
        let mut f = Frame::default();
        match self {
            Session::Dag(c) => {
                c.send_view(v).map_err(stream_error)?;
                let b = c.receive_batch().map_err(stream_error)?;
                f.operations = (b.collapses + b.splits) as u64;
                f.bytes = b.bytes;
                f.round_trips = 1;
                f.triangles = c.objects()[0].mesh().triangle_count();
            }
            Session::Selective(c) => {
                let before = c.objects()[0].operations();
                let mut v = *v;
                while c.select(&v).map_err(stream_error)? {
                    c.send_view(&v).map_err(stream_error)?;
                    let got = c.receive_batch().map_err(stream_error)?;
                    f.bytes += got.bytes;
                    f.round_trips += 1;
                    v.frame += 1;
                    if got.splits == 0 {
                        return Err(Error::Invalid(
                            "stream-blocks: the server had nothing for what the client lacks"
                                .into(),
                        ));
                    }
                }
                let after = c.objects()[0].operations();
                f.operations = after.0 + after.1 - before.0 - before.1;
                f.triangles = c.objects()[0].triangles().len();
            }
            Session::Blocks(c) => {
                let before = c.objects()[0].operations();
                let got = c.select(v).map_err(stream_error)?;
                let after = c.objects()[0].operations();
                f.operations = after.0 + after.1 - before.0 - before.1;
                f.bytes = got.bytes;
                f.round_trips = got.round_trips;
                f.triangles = c.objects()[0].triangles().len();
                row.blocks += got.blocks;
                row.predicted_kept += got.predicted_kept;
                row.predicted_discarded += got.predicted_discarded;
                row.dropped = c.objects()[0].dropped();
            }
        }
        Ok(f)
    }

    fn bye(self) {
        // The walk's figures are in; a session that cannot say goodbye changes none.
        let _ = match self {
            Session::Dag(c) => c.bye(),
            Session::Selective(c) => c.bye(),
            Session::Blocks(c) => c.bye(),
        };
    }
}

/// A server on loopback, behind the link when it has a round trip.
struct Served {
    _server: RunningServer,
    _link: Option<Link>,
    addr: SocketAddr,
}

impl Served {
    /// Serves `landmark` with prediction of up to `predict_blocks` blocks (0: none).
    fn start(
        landmark: &Landmark,
        cfg: &StreamBlocksConfig,
        predict_blocks: usize,
    ) -> Result<Served> {
        let config = ServerConfig {
            block_levels: cfg.levels,
            idle: Duration::from_millis(cfg.idle_ms),
            predict_blocks,
            ..ServerConfig::default()
        };
        let server = StreamServer::bind("127.0.0.1:0", vec![landmark.clone()], config)
            .and_then(|s| s.spawn())
            .map_err(stream_error)?;
        let link = (cfg.rtt_ms > 0)
            .then(|| {
                Link::start(
                    server.addr(),
                    LinkSpec {
                        rtt: Duration::from_millis(u64::from(cfg.rtt_ms)),
                        mbit: None,
                    },
                )
            })
            .transpose()
            .map_err(|e| Error::Invalid(format!("stream-blocks: the link: {e}")))?;
        let addr = link.as_ref().map_or(server.addr(), Link::addr);
        Ok(Served {
            _server: server,
            _link: link,
            addr,
        })
    }
}

/// Builds the landmark, serves it on loopback behind the link, and walks the orbit by
/// each scheme. `progress` is told each walk as it starts.
pub fn run(cfg: &StreamBlocksConfig, mut progress: impl FnMut(&str)) -> Result<StreamBlocksReport> {
    cfg.validate()?;
    progress("building the landmark's progressive mesh and DAG");
    let (landmark, centre, radius) = crate::stream::torus_landmark(cfg.triangles)?;
    let model_triangles = landmark.triangles();
    // One server that never predicts, and one that does.
    let quiet = Served::start(&landmark, cfg, 0)?;
    let predicting = Served::start(&landmark, cfg, cfg.predict_blocks)?;
    let fov = cfg.fov_degrees.to_radians();
    let views = orbit_path(centre, radius, cfg.frames, fov)?;
    let hello = |scheme| Hello {
        traversal: Traversal::Priority,
        fov,
        budget: None,
        out_of_view: true,
        back_face: true,
        scheme,
    };
    let mut rows = Vec::new();
    for (name, scheme, server, cache) in [
        ("Zheng DAG (sequential)", Scheme::Dag, &quiet, None),
        (
            "Kim-Lee-Kobbelt truly selective",
            Scheme::Selective,
            &quiet,
            None,
        ),
        ("El-Sana blocks", Scheme::Blocks, &quiet, None),
        (
            "El-Sana blocks (predicted)",
            Scheme::Blocks,
            &predicting,
            None,
        ),
        (
            "El-Sana blocks (predicted; bounded cache)",
            Scheme::Blocks,
            &predicting,
            Some(cfg.cache_blocks),
        ),
    ] {
        progress(&format!("walking: {name}"));
        let session = Session::connect(server.addr, hello(scheme), cache)?;
        rows.push(walk(cfg, session, name, &views, centre)?);
    }
    Ok(StreamBlocksReport {
        config: cfg.clone(),
        model_triangles,
        rows,
    })
}

/// Walks `views` by `session`, paced at the frame period.
fn walk(
    cfg: &StreamBlocksConfig,
    mut session: Session,
    scheme: &'static str,
    views: &[View],
    centre: glam::Vec3,
) -> Result<StreamBlocksRow> {
    let mut row = StreamBlocksRow {
        scheme,
        frames: views.len(),
        triangles: 0.0,
        operations: 0.0,
        bytes: 0.0,
        round_trips: 0.0,
        time_ms: 0.0,
        time_p95_ms: 0.0,
        time_max_ms: 0.0,
        blocks: 0,
        predicted_kept: 0,
        predicted_discarded: 0,
        dropped: 0,
    };
    let period = Duration::from_secs_f64(cfg.frame_ms / 1e3);
    let mut times = Vec::with_capacity(views.len());
    let mut next_frame = 0u32;
    let mut next = Instant::now();
    for v in views {
        let aim = v.eye + v.look * (centre - v.eye).length().max(1e-3);
        let packet = ViewPacket {
            frame: next_frame,
            eye: v.eye.to_array(),
            aim: aim.to_array(),
            tau: cfg.tau,
            budget_mode: false,
            n: MAX_N,
        };
        let started = Instant::now();
        let f = session.frame(&packet, &mut row)?;
        times.push(started.elapsed().as_secs_f64() * 1e3);
        next_frame += f.round_trips.max(1) as u32;
        let n = views.len() as f64;
        row.triangles += f.triangles as f64 / n;
        row.operations += f.operations as f64 / n;
        row.bytes += f.bytes as f64 / n;
        row.round_trips += f.round_trips as f64 / n;
        next += period;
        match next.checked_duration_since(Instant::now()) {
            Some(wait) => std::thread::sleep(wait),
            None => next = Instant::now(),
        }
    }
    session.bye();
    row.time_ms = times.iter().sum::<f64>() / times.len() as f64;
    times.sort_by(f64::total_cmp);
    row.time_p95_ms = times[(times.len() * 95 / 100).min(times.len() - 1)];
    row.time_max_ms = times[times.len() - 1];
    Ok(row)
}

impl Report for StreamBlocksReport {
    fn name(&self) -> &'static str {
        "stream-blocks"
    }

    fn to_csv(&self) -> String {
        let mut out = String::from(
            "scheme,frames,triangles,operations,bytes,round_trips,time_ms,time_p95_ms,\
             time_max_ms,blocks,predicted_kept,predicted_discarded,dropped\n",
        );
        for r in &self.rows {
            out += &format!(
                "{},{},{:.1},{:.1},{:.1},{:.3},{:.3},{:.3},{:.3},{},{},{},{}\n",
                r.scheme,
                r.frames,
                r.triangles,
                r.operations,
                r.bytes,
                r.round_trips,
                r.time_ms,
                r.time_p95_ms,
                r.time_max_ms,
                r.blocks,
                r.predicted_kept,
                r.predicted_discarded,
                r.dropped
            );
        }
        out
    }

    fn markdown(&self) -> String {
        let c = &self.config;
        let mut md = format!(
            "# stream-blocks — a walk's cost per frame by each scheme (El-Sana Table 1)\n\n\
             The {}-frame orbit of a {}-triangle torus at a {} ms frame period, τ = {} %, \
             each scheme its own session with a server over loopback{}. Blocks of {} \
             levels; the bounded cache keeps {} blocks beyond those its mesh uses; the \
             server of the predicted rows predicts up to {} blocks after {} ms idle. Per \
             frame:\n\n\
             | scheme | triangles (K) | split/merge (K) | sent (KB) | round trips | time, mean / p95 / max (ms) | blocks | predicted kept / discarded | dropped |\n\
             |---|---|---|---|---|---|---|---|---|\n",
            c.frames,
            self.model_triangles,
            c.frame_ms,
            100.0 * c.tau,
            if c.rtt_ms > 0 {
                format!(", through a link of {} ms round trip", c.rtt_ms)
            } else {
                String::new()
            },
            c.levels,
            c.cache_blocks,
            c.predict_blocks,
            c.idle_ms
        );
        for r in &self.rows {
            md += &format!(
                "| {} | {:.1} | {:.2} | {:.2} | {:.2} | {:.1} / {:.1} / {:.1} | {} | {} / {} | {} |\n",
                r.scheme,
                r.triangles / 1e3,
                r.operations / 1e3,
                r.bytes / 1e3,
                r.round_trips,
                r.time_ms,
                r.time_p95_ms,
                r.time_max_ms,
                r.blocks,
                r.predicted_kept,
                r.predicted_discarded,
                r.dropped
            );
        }
        md += "\nEl-Sana's Table 1, per frame (his server an SGI Origin 200, the client a \
               Pentium III, over a WAN of at most 1 Mbit/s):\n\n\
               | dataset | triangles | triangles (K) | split/merge (K) | sent (KB) | time (ms) |\n\
               |---|---|---|---|---|---|\n";
        for (name, triangles, k, ops, kb, ms) in EL_SANA_TABLE_1 {
            md += &format!("| {name} | {triangles} | {k} | {ops} | {kb} | {ms} |\n");
        }
        md
    }

    fn plot(&self, _dir: &Path) -> Result<()> {
        Ok(())
    }
}
