//! The `stream-crowd` experiment (ours; the scale the stream issue asks for): many
//! predictive clients on one stream server at once, each walking its own orbit of the
//! landmark at 30 Hz. Server side: the CPU its session threads used, each session's
//! memory, the time to answer a view and the traversal's share of it (p50, p95, p99),
//! the most front nodes a traversal evaluated (the constant-time traversal's bound, 2N);
//! client side: every batch's round trip (p50, p95, p99), and the unmodified frames
//! after the warm-up of the worst-served client (a starved client would have many).
//!
//! Clients and server share this process, over loopback: the session threads' CPU is
//! read from `/proc/self/task/*/schedstat` (the server names them `stream-<peer>`) just
//! before the clients end their sessions.

use std::path::Path;
use std::sync::{Arc, Barrier};
use std::time::{Duration, Instant};

use glam::Quat;

use crate::lod_orbit::orbit_path;
use crate::report::Report;
use flaneur::error::{Error, Result};
use flaneur::lod::Traversal;
use flaneur_stream::{Hello, PredictiveClient, Predictor, Refinement, ServerConfig, StreamServer};

/// The settings of the experiment.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StreamCrowdConfig {
    pub clients: usize,
    pub triangles: usize,
    pub frames: usize,
    /// Each client's frame period, ms.
    pub frame_ms: f64,
    pub tau: f32,
    pub n: u32,
    pub budget: u32,
    /// The sessions' traversal (the priority-oriented one by default, as in `bench
    /// stream`; the constant-time one for its bound).
    #[serde(serialize_with = "traversal_name")]
    pub traversal: Traversal,
}

fn traversal_name<S: serde::Serializer>(
    t: &Traversal,
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    s.serialize_str(t.name())
}

impl Default for StreamCrowdConfig {
    fn default() -> StreamCrowdConfig {
        StreamCrowdConfig {
            clients: 32,
            triangles: crate::lod_refine::DEFAULT_TRIANGLES,
            frames: crate::lod_refine::DEFAULT_FRAMES,
            frame_ms: 1000.0 / 30.0,
            tau: 0.0002,
            n: flaneur_stream::protocol::MAX_N,
            budget: flaneur::lod::THESIS_BUDGET as u32,
            traversal: Traversal::Priority,
        }
    }
}

/// What the crowd did.
#[derive(Clone, Debug, serde::Serialize)]
pub struct StreamCrowdReport {
    pub config: StreamCrowdConfig,
    pub model_triangles: usize,
    /// CPU seconds the session threads used, and the walk's wall seconds.
    pub server_cpu_s: f64,
    pub wall_s: f64,
    /// Each session's own memory at its end, bytes: mean and largest.
    pub memory_mean: f64,
    pub memory_max: usize,
    /// Bytes the sessions share besides the landmark's progressive mesh and DAG (each
    /// DAG node's record, made once).
    pub shared_memory: usize,
    /// Time to answer a view, ms: p50, p95, p99, max over every session.
    pub answer_ms: [f64; 4],
    /// The traversals' share of it, ms: p50, p95, p99, max.
    pub traversal_ms: [f64; 4],
    /// The most front nodes one traversal evaluated for one view, over every session.
    pub most_evaluated: usize,
    /// Nodes split and collapsed a view, and bytes a batch, over every session (El-Sana
    /// Table 1's operations and bytes a frame).
    pub operations_per_view: f64,
    pub bytes_per_batch: f64,
    /// Triangles a client's selective mesh held at the end, mean.
    pub triangles_held: f64,
    /// Every batch's round trip, ms: p50, p95, p99, max over every client.
    pub round_trip_ms: [f64; 4],
    /// Unmodified frames after the warm-up: the fewest, the mean, the most of a client.
    pub unmodified: [f64; 3],
    pub warm_up: usize,
    /// Clients whose session failed, with the first error.
    pub failed: usize,
    pub first_error: Option<String>,
}

/// `xs` as "a / b / c / d", each to `digits` decimals.
fn slashed(xs: &[f64; 4], digits: usize) -> String {
    xs.map(|x| format!("{x:.digits$}")).join(" / ")
}

/// What one client's walk saw.
#[derive(Default)]
struct Walked {
    trips: Vec<f64>,
    unmodified: usize,
    batches: u64,
    batch_bytes: u64,
    triangles: usize,
}

/// p50, p95, p99 and the largest of `xs`.
fn spread(mut xs: Vec<f64>) -> [f64; 4] {
    if xs.is_empty() {
        return [0.0; 4];
    }
    xs.sort_by(f64::total_cmp);
    let at = |q: f64| xs[((xs.len() - 1) as f64 * q).round() as usize];
    [at(0.5), at(0.95), at(0.99), xs[xs.len() - 1]]
}

/// CPU seconds of this process's threads whose names start with `prefix`.
fn threads_cpu_seconds(prefix: &str) -> f64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return 0.0;
    };
    tasks
        .flatten()
        .filter(|t| {
            std::fs::read_to_string(t.path().join("comm")).is_ok_and(|c| c.starts_with(prefix))
        })
        .filter_map(|t| std::fs::read_to_string(t.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .sum::<f64>()
        / 1e9
}

/// Runs the crowd: one server, `clients` predictive clients, each on its own thread
/// walking the orbit turned by its share of a circle.
pub fn run(cfg: &StreamCrowdConfig, mut progress: impl FnMut(&str)) -> Result<StreamCrowdReport> {
    if cfg.clients == 0 || cfg.frames < 10 || !(cfg.frame_ms.is_finite() && cfg.frame_ms > 0.0) {
        return Err(Error::Invalid(format!(
            "stream-crowd: {} clients of {} frames at {} ms; give at least one client and 10 \
             frames of a positive period",
            cfg.clients, cfg.frames, cfg.frame_ms
        )));
    }
    progress("building the landmark's progressive mesh and DAG");
    let (landmark, centre, radius) = crate::stream::torus_landmark(cfg.triangles)?;
    let model_triangles = landmark.triangles();
    let fov = crate::lod_refine::DEFAULT_FOV_DEGREES.to_radians();
    let views = Arc::new(orbit_path(centre, radius, cfg.frames, fov)?);
    // Every walker of the crowd is served: the server's default cap is for a public
    // server, not for an experiment that asks for more clients on purpose.
    let config = ServerConfig {
        max_sessions: cfg.clients.max(1),
        ..ServerConfig::default()
    };
    let server = StreamServer::bind("127.0.0.1:0", vec![landmark], config)
        .map_err(|e| Error::Invalid(format!("stream-crowd: {e}")))?;
    let shared_memory = server.shared_memory();
    let server = server
        .spawn()
        .map_err(|e| Error::Invalid(format!("stream-crowd: {e}")))?;
    let addr = server.addr();
    let warm_up = cfg.frames * 50 / 180;
    progress(&format!("{} clients walking", cfg.clients));
    // All walk, then the server's threads are read, then all say goodbye.
    let walked = Arc::new(Barrier::new(cfg.clients + 1));
    let read = Arc::new(Barrier::new(cfg.clients + 1));
    let started = Instant::now();
    let handles: Vec<_> = (0..cfg.clients)
        .map(|k| {
            let (views, walked, read, cfg) =
                (views.clone(), walked.clone(), read.clone(), cfg.clone());
            std::thread::spawn(move || {
                let turn =
                    Quat::from_rotation_y(std::f32::consts::TAU * k as f32 / cfg.clients as f32);
                let walk = || -> std::result::Result<(PredictiveClient, Walked), String> {
                    let hello = Hello {
                        traversal: cfg.traversal,
                        fov,
                        budget: Some(cfg.budget),
                        out_of_view: true,
                        back_face: true,
                        scheme: flaneur_stream::Scheme::Dag,
                    };
                    let refinement = Refinement {
                        tau: cfg.tau,
                        n: cfg.n,
                        initial_span: 1,
                        predictor: Predictor::Quadratic,
                    };
                    let mut c =
                        PredictiveClient::connect(addr, hello, refinement, Duration::from_secs(60))
                            .map_err(|e| e.to_string())?;
                    let period = Duration::from_secs_f64(cfg.frame_ms / 1e3);
                    let mut w = Walked::default();
                    let mut next = Instant::now();
                    for (f, v) in views.iter().enumerate() {
                        let eye = centre + turn * (v.eye - centre);
                        let aim = eye + turn * v.look * (centre - v.eye).length().max(1e-3);
                        let got = c.frame(eye, aim).map_err(|e| e.to_string())?;
                        if let Some(t) = got.batch_round_trip {
                            w.trips.push(t.as_secs_f64() * 1e3);
                        }
                        w.unmodified += usize::from(f >= warm_up && !got.modified);
                        w.batches += u64::from(got.modified);
                        w.batch_bytes += got.bytes as u64;
                        next += period;
                        match next.checked_duration_since(Instant::now()) {
                            Some(wait) => std::thread::sleep(wait),
                            None => next = Instant::now(),
                        }
                    }
                    w.triangles = c.objects().iter().map(|o| o.mesh().triangle_count()).sum();
                    Ok((c, w))
                };
                let result = walk();
                walked.wait();
                read.wait();
                result.map(|(c, w)| {
                    let _ = c.bye();
                    w
                })
            })
        })
        .collect();
    walked.wait();
    let wall_s = started.elapsed().as_secs_f64();
    let server_cpu_s = threads_cpu_seconds("stream-127");
    read.wait();
    let (mut trips, mut unmodified, mut failed, mut first_error) =
        (Vec::new(), Vec::new(), 0, None);
    let (mut batches, mut batch_bytes, mut triangles) = (0, 0, Vec::new());
    for h in handles {
        match h.join() {
            Ok(Ok(w)) => {
                trips.extend(w.trips);
                unmodified.push(w.unmodified as f64);
                (batches, batch_bytes) = (batches + w.batches, batch_bytes + w.batch_bytes);
                triangles.push(w.triangles as f64);
            }
            Ok(Err(e)) => {
                failed += 1;
                first_error.get_or_insert(e);
            }
            Err(_) => {
                failed += 1;
                first_error.get_or_insert_with(|| "a client thread panicked".into());
            }
        }
    }
    let mut memories = Vec::new();
    let (mut answers, mut traversals, mut most_evaluated) = (Vec::new(), Vec::new(), 0);
    let (mut operations, mut views) = (0, 0);
    for _ in 0..cfg.clients - failed {
        let end = server
            .ends()
            .recv_timeout(Duration::from_secs(30))
            .map_err(|_| Error::Invalid("stream-crowd: a session never ended".into()))?;
        memories.push(end.memory);
        answers.extend(end.answer_times.iter().map(|t| t.as_secs_f64() * 1e3));
        traversals.extend(end.traversal_times.iter().map(|t| t.as_secs_f64() * 1e3));
        most_evaluated = most_evaluated.max(end.most_evaluated);
        (operations, views) = (operations + end.operations, views + end.frames);
    }
    let unmodified_spread = if unmodified.is_empty() {
        [0.0; 3]
    } else {
        let mean = unmodified.iter().sum::<f64>() / unmodified.len() as f64;
        let (min, max) = unmodified
            .iter()
            .fold((f64::MAX, 0.0f64), |(a, b), &u| (a.min(u), b.max(u)));
        [min, mean, max]
    };
    Ok(StreamCrowdReport {
        config: cfg.clone(),
        model_triangles,
        server_cpu_s,
        wall_s,
        memory_mean: memories.iter().sum::<usize>() as f64 / memories.len().max(1) as f64,
        memory_max: memories.iter().copied().max().unwrap_or(0),
        shared_memory,
        answer_ms: spread(answers),
        traversal_ms: spread(traversals),
        most_evaluated,
        operations_per_view: operations as f64 / views.max(1) as f64,
        bytes_per_batch: batch_bytes as f64 / batches.max(1) as f64,
        triangles_held: triangles.iter().sum::<f64>() / triangles.len().max(1) as f64,
        round_trip_ms: spread(trips),
        unmodified: unmodified_spread,
        warm_up,
        failed,
        first_error,
    })
}

impl Report for StreamCrowdReport {
    fn name(&self) -> &'static str {
        "stream-crowd"
    }

    fn to_csv(&self) -> String {
        let c = &self.config;
        let spread = |xs: &[f64; 4]| xs.map(|x| format!("{x:.3}")).join(",");
        format!(
            "clients,frames,frame_ms,traversal,n,server_cpu_s,wall_s,memory_mean,memory_max,shared_memory,\
             answer_p50_ms,answer_p95_ms,answer_p99_ms,answer_max_ms,\
             traversal_p50_ms,traversal_p95_ms,traversal_p99_ms,traversal_max_ms,most_evaluated,\
             operations_per_view,bytes_per_batch,triangles_held,\
             round_trip_p50_ms,round_trip_p95_ms,round_trip_p99_ms,round_trip_max_ms,\
             unmodified_min,unmodified_mean,unmodified_max,failed\n\
             {},{},{:.2},{},{},{:.3},{:.3},{:.0},{},{},{},{},{},{:.1},{:.0},{:.0},{},{},{:.1},{},{}\n",
            c.clients,
            c.frames,
            c.frame_ms,
            c.traversal.name(),
            c.n,
            self.server_cpu_s,
            self.wall_s,
            self.memory_mean,
            self.memory_max,
            self.shared_memory,
            spread(&self.answer_ms),
            spread(&self.traversal_ms),
            self.most_evaluated,
            self.operations_per_view,
            self.bytes_per_batch,
            self.triangles_held,
            spread(&self.round_trip_ms),
            self.unmodified[0],
            self.unmodified[1],
            self.unmodified[2],
            self.failed
        )
    }

    fn markdown(&self) -> String {
        let c = &self.config;
        format!(
            "# stream-crowd — many clients on one stream server (ours)\n\n\
             {} predictive clients (second-order prediction) on one server over loopback, each \
             walking the {}-frame orbit of a {}-triangle torus turned by its share of a circle, \
             at {:.1} ms frames; the {} traversal, τ = {} %, N = {}, a budget of {}. Clients and \
             server share this machine's cores.\n\n\
             | figure | value |\n|---|---|\n\
             | server CPU (session threads) | {:.2} s in {:.2} s of walking: {:.0} % of one core |\n\
             | memory per session, mean (largest) | {:.1} MiB ({:.1} MiB) |\n\
             | shared by every session: the DAG nodes' records | {:.1} MiB |\n\
             | time to answer a view, p50 / p95 / p99 / max | {} ms |\n\
             | its traversals, p50 / p95 / p99 / max | {} ms |\n\
             | most front nodes one traversal evaluated for a view (2N = {}) | {} |\n\
             | a view's operations (nodes split and collapsed), a batch's bytes, triangles held (El-Sana Table 1: 2.6K, 0.68 KB, 91K) | {:.0}, {:.2} KiB, {:.0} |\n\
             | a batch's round trip, p50 / p95 / p99 / max | {} ms |\n\
             | unmodified frames after frame {}, fewest / mean / most of a client | {} / {:.1} / {} |\n\
             | clients failed | {}{} |\n\n\
             A starved client would show as many unmodified frames; the landmark's progressive \
             mesh and DAG, and each DAG node's record, are held once, so a session's memory is \
             its own fronts, ID maps and selective mesh.\n",
            c.clients,
            c.frames,
            self.model_triangles,
            c.frame_ms,
            c.traversal.name(),
            100.0 * c.tau,
            c.n,
            c.budget,
            self.server_cpu_s,
            self.wall_s,
            100.0 * self.server_cpu_s / self.wall_s.max(1e-9),
            self.memory_mean / 1048576.0,
            self.memory_max as f64 / 1048576.0,
            self.shared_memory as f64 / 1048576.0,
            slashed(&self.answer_ms, 2),
            slashed(&self.traversal_ms, 2),
            2 * c.n,
            self.most_evaluated,
            self.operations_per_view,
            self.bytes_per_batch / 1024.0,
            self.triangles_held,
            slashed(&self.round_trip_ms, 1),
            self.warm_up,
            self.unmodified[0],
            self.unmodified[1],
            self.unmodified[2],
            self.failed,
            self.first_error
                .as_ref()
                .map_or(String::new(), |e| format!(" (first: {e})"))
        )
    }

    fn plot(&self, _dir: &Path) -> Result<()> {
        Ok(())
    }
}
