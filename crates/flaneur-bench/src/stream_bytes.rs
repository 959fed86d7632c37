//! The `stream-bytes` experiment (Kim–Lee–Kobbelt Figs. 8–9, on Zheng's DAG scheme):
//! what streaming a landmark for one view costs, view-dependent against
//! view-independent. One client asks the stream server for the same view, frame after
//! frame (close to the model, along its side), in free mode under τ with N = 500, until
//! a batch brings nothing: once with the
//! view-dependent criteria (out of view, back-facing), once without them, which
//! refines the whole model to the screen-space error its distance allows, as a
//! view-independent progressive stream does. Reported for each: the bytes and frames
//! to converge, the triangles then, and at a byte cap (their Fig. 9's 0.5 MB) the
//! triangles held and the share of what the view needs (the view-dependent converged
//! mesh's triangles) that they cover. Then the same for Kim–Lee–Kobbelt's truly
//! selective schemes (`lod::selective`) over sessions of their own with the same
//! server, and El-Sana's blocks over the same hierarchy in process; their share at the
//! cap is of the truly selective view-dependent mesh.

use std::path::Path;
use std::time::Duration;

use glam::Vec3;

use crate::report::Report;
use flaneur::error::{Error, Result};
use std::collections::HashSet;

use flaneur::lod::{
    BlockClient, BlockServer, CompactMesh, NodeName, SelectiveSource, Traversal, View,
};
use flaneur_stream::protocol::MAX_N;
use flaneur_stream::selective_wire::encode_vsplits;
use flaneur_stream::{
    Hello, Scheme, SelectiveStreamClient, ServerConfig, StreamClient, StreamServer, ViewPacket,
};

/// The settings of the experiment.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct StreamBytesConfig {
    pub triangles: usize,
    pub tau: f32,
    /// The byte cap the meshes are compared at (Kim–Lee–Kobbelt Fig. 9: 0.5 MB).
    pub cap: usize,
}

impl Default for StreamBytesConfig {
    fn default() -> StreamBytesConfig {
        StreamBytesConfig {
            triangles: crate::lod_refine::DEFAULT_TRIANGLES,
            tau: 0.001,
            cap: 500_000,
        }
    }
}

/// One way of streaming, to convergence.
#[derive(Clone, Debug, serde::Serialize)]
pub struct StreamBytesRow {
    pub scheme: &'static str,
    /// Frames and batch bytes until a batch brought nothing.
    pub frames: usize,
    pub bytes: usize,
    /// Triangles of the mesh then.
    pub triangles: usize,
    /// Bytes, triangles and the share of the view's triangles held at the first batch
    /// past the cap (the converged figures when it never passed it).
    pub cap_bytes: usize,
    pub cap_triangles: usize,
    pub cap_share: f64,
}

/// Both ways.
#[derive(Clone, Debug, serde::Serialize)]
pub struct StreamBytesReport {
    pub config: StreamBytesConfig,
    pub model_triangles: usize,
    pub rows: Vec<StreamBytesRow>,
}

/// The most frames one stream may take to converge.
const MAX_FRAMES: u32 = 100_000;

/// One stream to convergence: the mesh then, the frames and bytes it took, and the mesh
/// and bytes at the first batch past the cap.
struct Converged {
    mesh: CompactMesh,
    frames: u32,
    bytes: usize,
    at_cap: Option<(CompactMesh, usize)>,
}

/// Streams the landmark for one view until it converges.
fn stream_to_convergence(
    server: std::net::SocketAddr,
    hello: Hello,
    view: ViewPacket,
    cap: usize,
) -> Result<Converged> {
    let bad = |e: flaneur_stream::StreamError| Error::Invalid(format!("stream-bytes: {e}"));
    let mut client = StreamClient::connect(server, hello, Duration::from_secs(60)).map_err(bad)?;
    let (mut bytes, mut at_cap) = (0, None);
    for frame in 0..MAX_FRAMES {
        client
            .send_view(&ViewPacket { frame, ..view })
            .map_err(bad)?;
        let batch = client.receive_batch().map_err(bad)?;
        bytes += batch.bytes;
        if bytes >= cap && at_cap.is_none() {
            at_cap = Some((client.objects()[0].mesh().clone(), bytes));
        }
        if batch.splits + batch.collapses == 0 {
            let mesh = client.objects()[0].mesh().clone();
            client.bye().map_err(bad)?;
            return Ok(Converged {
                mesh,
                frames: frame + 1,
                bytes,
                at_cap,
            });
        }
    }
    Err(Error::Invalid(format!(
        "stream-bytes: the stream did not converge in {MAX_FRAMES} frames"
    )))
}

/// Builds the landmark, serves it on loopback, and streams it for one view both ways.
pub fn run(cfg: &StreamBytesConfig, mut progress: impl FnMut(&str)) -> Result<StreamBytesReport> {
    if !(cfg.tau > 0.0 && cfg.tau < 1.0) || cfg.cap == 0 {
        return Err(Error::Invalid(format!(
            "stream-bytes: τ = {} and a cap of {} bytes; give τ within (0, 1) and a cap above 0",
            cfg.tau, cfg.cap
        )));
    }
    progress("building the landmark's progressive mesh and DAG");
    let (landmark, centre, radius) = crate::stream::torus_landmark(cfg.triangles)?;
    let model_triangles = landmark.triangles();
    let (pm, dag) = (landmark.pm.clone(), landmark.dag.clone());
    let server = StreamServer::bind("127.0.0.1:0", vec![landmark], ServerConfig::default())
        .and_then(|s| s.spawn())
        .map_err(|e| Error::Invalid(format!("stream-bytes: {e}")))?;
    // Close to the model, looking along its side: much of it out of view or facing
    // away, as a walker near a landmark sees it.
    let eye = centre + radius * Vec3::new(0.0, 0.25, 1.1);
    let aim = centre + radius * Vec3::new(0.6, 0.0, 0.6);
    let view = ViewPacket {
        frame: 0,
        eye: eye.to_array(),
        aim: aim.to_array(),
        tau: cfg.tau,
        budget_mode: false,
        n: MAX_N,
    };
    let hello = |culling: bool| Hello {
        traversal: Traversal::Priority,
        fov: crate::lod_refine::DEFAULT_FOV_DEGREES.to_radians(),
        budget: None,
        out_of_view: culling,
        back_face: culling,
        scheme: Scheme::Dag,
    };
    let mut rows = Vec::new();
    let mut needed: Option<CompactMesh> = None;
    for (scheme, culling) in [("view-dependent", true), ("view-independent", false)] {
        progress(&format!("streaming {scheme}"));
        let Converged {
            mesh,
            frames,
            bytes,
            at_cap,
        } = stream_to_convergence(server.addr(), hello(culling), view, cfg.cap)?;
        let reference = needed.get_or_insert_with(|| mesh.clone());
        let (cap_mesh, cap_bytes) = at_cap.unwrap_or((mesh.clone(), bytes));
        rows.push(StreamBytesRow {
            scheme,
            frames: frames as usize,
            bytes,
            triangles: mesh.triangle_count(),
            cap_bytes,
            cap_triangles: cap_mesh.triangle_count(),
            cap_share: cap_mesh.shared_with(reference),
        });
    }
    let mut needed: Option<HashSet<[NodeName; 3]>> = None;
    for (name, scheme, culling) in [
        ("truly-selective view-dependent", Scheme::Selective, true),
        ("truly-selective view-independent", Scheme::Selective, false),
        ("truly-selective cut-vertex-only", Scheme::CutVertex, true),
    ] {
        progress(&format!("streaming {name}"));
        let hello = Hello {
            scheme,
            ..hello(culling)
        };
        rows.push(stream_selective(
            server.addr(),
            hello,
            view,
            cfg,
            name,
            &mut needed,
        )?);
    }
    progress("streaming El-Sana's blocks, in process");
    let source = SelectiveSource::new(&pm, &dag)?;
    let fov = crate::lod_refine::DEFAULT_FOV_DEGREES.to_radians();
    let eye = glam::Vec3::from(view.eye);
    let local = View::new(eye, glam::Vec3::from(view.aim) - eye, fov)?;
    rows.push(stream_blocks(&source, &local, cfg, &mut needed)?);
    Ok(StreamBytesReport {
        config: cfg.clone(),
        model_triangles,
        rows,
    })
}

/// Streams the landmark for `view` over a truly selective session until the client's
/// mesh is what the view asks for (the selective scheme), or until a VSPLITS brings
/// nothing (cut-vertex-only, whose client does not refine on its own), each VSPLITS
/// counted as it came over the wire. `needed` is the first row's converged mesh, that
/// the share at the cap is of.
fn stream_selective(
    server: std::net::SocketAddr,
    hello: Hello,
    view: ViewPacket,
    cfg: &StreamBytesConfig,
    name: &'static str,
    needed: &mut Option<HashSet<[NodeName; 3]>>,
) -> Result<StreamBytesRow> {
    let bad = |e: flaneur_stream::StreamError| Error::Invalid(format!("stream-bytes: {name}: {e}"));
    let mut client =
        SelectiveStreamClient::connect(server, hello, Duration::from_secs(60)).map_err(bad)?;
    let mesh = |client: &SelectiveStreamClient| canonical(client.objects()[0].triangles());
    let (mut frames, mut bytes, mut at_cap) = (0, 0, None);
    let mut v = view;
    while client.select(&v).map_err(bad)? {
        if v.frame >= MAX_FRAMES {
            return Err(Error::Invalid(format!(
                "stream-bytes: {name} did not converge in {MAX_FRAMES} frames"
            )));
        }
        client.send_view(&v).map_err(bad)?;
        let got = client.receive_batch().map_err(bad)?;
        v.frame += 1;
        frames += 1;
        bytes += got.bytes;
        if got.splits == 0 {
            if hello.scheme == Scheme::Selective {
                return Err(Error::Invalid(format!(
                    "stream-bytes: {name}: the server had nothing for what the client lacks"
                )));
            }
            break;
        }
        if bytes >= cfg.cap && at_cap.is_none() {
            client.select(&v).map_err(bad)?;
            at_cap = Some((mesh(&client), bytes));
        }
    }
    let converged = mesh(&client);
    client.bye().map_err(bad)?;
    Ok(selective_row(
        name,
        (frames, bytes),
        converged,
        at_cap,
        needed,
    ))
}

/// The levels of the blocks the El-Sana row streams.
pub const BLOCK_LEVELS: u32 = 2;

/// Streams the landmark for `view` by El-Sana's blocks over the vertex hierarchy, in
/// process: the client asks for the blocks its view wants a split from and those below
/// splits that reached a block's last level, until it asks for none; each answer
/// counted as its blocks would go on the wire (a name and a vsplit batch each).
fn stream_blocks(
    source: &SelectiveSource,
    view: &View,
    cfg: &StreamBytesConfig,
    needed: &mut Option<HashSet<[NodeName; 3]>>,
) -> Result<StreamBytesRow> {
    let mut server = BlockServer::new(source, BLOCK_LEVELS)?;
    let mut client = BlockClient::new(source.base(), BLOCK_LEVELS);
    let (mut frames, mut bytes, mut at_cap) = (0, 0, None);
    loop {
        let down = client.select(view, cfg.tau)?;
        if down.needed.is_empty() && down.ahead.is_empty() {
            break;
        }
        let tops: Vec<NodeName> = down.needed.into_iter().chain(down.ahead).collect();
        let blocks = server.send(source, &tops)?;
        frames += 1;
        bytes += blocks
            .iter()
            .map(|b| {
                6 + (b.top.node.bits() as usize).div_ceil(8) + encode_vsplits(&b.packets).len()
            })
            .sum::<usize>();
        client.receive(&blocks)?;
        if bytes >= cfg.cap && at_cap.is_none() {
            client.select(view, cfg.tau)?;
            at_cap = Some((canonical(client.client().triangles()), bytes));
        }
    }
    let mesh = canonical(client.client().triangles());
    Ok(selective_row(
        "El-Sana blocks (2 levels) in process",
        (frames, bytes),
        mesh,
        at_cap,
        needed,
    ))
}

/// A truly selective stream's row: `frames` and `bytes` to converge on `mesh`, the mesh
/// and bytes at the first batch past the cap (the converged ones when it never passed
/// it), and the share of `needed` (set by the first row) held then.
fn selective_row(
    scheme: &'static str,
    (frames, bytes): (usize, usize),
    mesh: HashSet<[NodeName; 3]>,
    at_cap: Option<(HashSet<[NodeName; 3]>, usize)>,
    needed: &mut Option<HashSet<[NodeName; 3]>>,
) -> StreamBytesRow {
    let reference = needed.get_or_insert_with(|| mesh.clone());
    let (cap_mesh, cap_bytes) = at_cap.unwrap_or((mesh.clone(), bytes));
    let held = cap_mesh.intersection(reference).count();
    StreamBytesRow {
        scheme,
        frames,
        bytes,
        triangles: mesh.len(),
        cap_bytes,
        cap_triangles: cap_mesh.len(),
        cap_share: held as f64 / reference.len().max(1) as f64,
    }
}

/// Triangles turned to start at their smallest corner: the same triangle whatever its
/// rotation.
fn canonical(triangles: Vec<[NodeName; 3]>) -> HashSet<[NodeName; 3]> {
    triangles
        .into_iter()
        .map(|mut t| {
            let k = (0..3).min_by_key(|&k| t[k].clone()).unwrap_or(0);
            t.rotate_left(k);
            t
        })
        .collect()
}

impl Report for StreamBytesReport {
    fn name(&self) -> &'static str {
        "stream-bytes"
    }

    fn to_csv(&self) -> String {
        let mut out =
            String::from("scheme,frames,bytes,triangles,cap_bytes,cap_triangles,cap_share\n");
        for r in &self.rows {
            out += &format!(
                "{},{},{},{},{},{},{:.4}\n",
                r.scheme, r.frames, r.bytes, r.triangles, r.cap_bytes, r.cap_triangles, r.cap_share
            );
        }
        out
    }

    fn markdown(&self) -> String {
        let mut md = format!(
            "# stream-bytes — view-dependent against view-independent streaming \
             (Kim–Lee–Kobbelt Figs. 8–9)\n\n\
             A {}-triangle torus streamed for one view (τ = {} %, N = {}, free mode) until a \
             batch brings nothing; at the cap, the share of the view-dependent converged \
             mesh's triangles held.\n\n\
             | scheme | frames | bytes to converge | triangles | bytes at the cap | triangles then | share of the view's then |\n\
             |---|---|---|---|---|---|---|\n",
            self.model_triangles,
            100.0 * self.config.tau,
            MAX_N
        );
        for r in &self.rows {
            md += &format!(
                "| {} | {} | {} | {} | {} | {} | {:.1} % |\n",
                r.scheme,
                r.frames,
                r.bytes,
                r.triangles,
                r.cap_bytes,
                r.cap_triangles,
                100.0 * r.cap_share
            );
        }
        md += "\nEvery row but the last is one session with the same stream server over \
               loopback, its answers' bytes as they came over the wire (the truly selective \
               client asks only while its view wants a split it lacks; the cut-vertex-only one \
               until an answer brings nothing); the last streams El-Sana's blocks in process, \
               each answer counted as its blocks would be encoded. No row counts the base mesh. Kim–Lee–Kobbelt's \
               Fig. 8: 177,120 bytes and 4,534 faces view-dependent against 827,688 bytes and \
               68,884 faces view-independent (their truly selective scheme).\n";
        md
    }

    fn plot(&self, _dir: &Path) -> Result<()> {
        Ok(())
    }
}
