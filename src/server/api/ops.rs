//! Routes for operators: liveness, readiness, metrics, snapshots on request and the API
//! description.

use axum::Json;
use axum::extract::State;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};

use super::precondition::Unused;
use super::{Answer, AppState, snapshot, world_size};
use crate::server::actor::CheckpointError;
use crate::server::dto::{Health, Ready};
use crate::server::metrics;
use crate::server::problem::Problem;

/// How long readiness waits for the world's owner to answer.
const READY_WAIT: std::time::Duration = std::time::Duration::from_secs(2);

/// Liveness: the process serves HTTP. Answers without waiting for the world's owner.
pub(super) async fn healthz(State(s): State<AppState>) -> Response {
    Json(Health {
        status: "ok",
        revision: s.feed.revision(),
    })
    .into_response()
}

/// Readiness: the world's owner answers promptly and its storage works.
pub(super) async fn readyz(State(s): State<AppState>) -> Answer {
    if let Some(why) = s.handle.storage_failure() {
        return Err(Problem::new(
            StatusCode::SERVICE_UNAVAILABLE,
            "storage-failed",
            "Storage failed",
            why,
        ));
    }
    let w = tokio::time::timeout(READY_WAIT, snapshot(&s.handle))
        .await
        .map_err(|_| Problem::busy("the world's owner did not answer within 2 s", 1))??;
    Ok(Json(Ready {
        status: "ready",
        revision: w.revision(),
        queue: s.handle.queue_depth(),
    })
    .into_response())
}

/// `GET /metrics`: Prometheus (OpenMetrics) text, with the world's size measured now.
pub(super) async fn metrics(State(s): State<AppState>) -> Answer {
    let w = snapshot(&s.handle).await?;
    let (f, e, v) = world_size(&w);
    s.metrics.set_world(w.revision(), w.body_count(), f, e, v);
    s.metrics
        .set_queue_depth(i64::try_from(s.handle.queue_depth()).unwrap_or(i64::MAX));
    Ok((
        [(axum::http::header::CONTENT_TYPE, metrics::CONTENT_TYPE)],
        s.metrics.render(),
    )
        .into_response())
}

/// `POST /v1/admin/snapshot`: writes a snapshot file of the world now (copy it for a
/// backup) and answers its revision, path and size.
pub(super) async fn snapshot_now(State(s): State<AppState>, _unused: Unused) -> Answer {
    match s.handle.checkpoint().await {
        Ok(c) => Ok(Json(c).into_response()),
        Err(e @ CheckpointError::InMemory) => Err(Problem::new(
            StatusCode::CONFLICT,
            "in-memory",
            "No storage",
            e.to_string(),
        )),
        Err(e @ CheckpointError::Storage(_)) => Err(Problem::new(
            StatusCode::INTERNAL_SERVER_ERROR,
            "storage-failed",
            "Storage failed",
            e.to_string(),
        )),
        Err(CheckpointError::Stopped) => Err(Problem::unavailable()),
    }
}

/// The OpenAPI description, as JSON.
pub(super) async fn openapi() -> Response {
    (
        [(axum::http::header::CONTENT_TYPE, "application/json")],
        crate::server::spec::openapi_json(),
    )
        .into_response()
}
