//! The stream client the walk and the window draw landmarks with (`--stream`).

use anyhow::{Context, Result};

/// A predictive stream session with the server at `addr`, refining under `tau`, as
/// the landmarks a walk draws; and where its figures are kept.
pub fn stream_landmarks(
    addr: &str,
    tau: f32,
) -> Result<(
    flaneur_stream::StreamedLandmarks,
    std::sync::Arc<std::sync::Mutex<flaneur_stream::StreamFigures>>,
)> {
    let default = flaneur::geom::Camera::new(glam::Vec3::ZERO, 0.0, 0.0)?;
    let hello = flaneur_stream::Hello {
        traversal: flaneur::lod::Traversal::Priority,
        fov: default.fov_x.max(default.fov_y),
        budget: Some(flaneur::lod::THESIS_BUDGET as u32),
        out_of_view: true,
        back_face: true,
        scheme: flaneur_stream::Scheme::Dag,
    };
    let refinement = flaneur_stream::Refinement {
        tau,
        n: flaneur_stream::protocol::MAX_N,
        initial_span: 1,
        predictor: flaneur_stream::Predictor::Quadratic,
    };
    let client = flaneur_stream::PredictiveClient::connect(
        addr,
        hello,
        refinement,
        std::time::Duration::from_secs(30),
    )
    .with_context(|| format!("connecting to the stream server at {addr}"))?;
    Ok(flaneur_stream::StreamedLandmarks::new(client))
}
