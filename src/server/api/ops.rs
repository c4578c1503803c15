//! Routes for operators: liveness, readiness and the API description.

use axum::Json;
use axum::extract::State;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use serde_json::json;

use super::{Answer, AppState, snapshot};
use crate::server::problem::Problem;

/// How long readiness waits for the world's owner to answer.
const READY_WAIT: std::time::Duration = std::time::Duration::from_secs(2);

/// Liveness: the process serves HTTP. Answers without waiting for the world's owner.
pub(super) async fn healthz(State(s): State<AppState>) -> Response {
    Json(json!({"status": "ok", "revision": s.feed.revision()})).into_response()
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
    Ok(Json(json!({
        "status": "ready",
        "revision": w.revision(),
        "queue": s.handle.queue_depth(),
    }))
    .into_response())
}

/// The OpenAPI description, as JSON.
pub(super) async fn openapi() -> Response {
    (
        [(axum::http::header::CONTENT_TYPE, "application/json")],
        crate::server::spec::openapi_json(),
    )
        .into_response()
}
