//! The HTTP surface: routes, request parsing and answers. Writes become [`Edit`]s sent to
//! the world's owner; reads work on a snapshot.
//!
//! Each route is marked with the role it needs (`reads`, `writes`, `admin` below); with
//! tokens configured, a request without the role is refused before its handler runs.

pub mod appearance;
pub mod body;
pub mod camera_solution;
pub mod extract;
mod feed;
mod mesh;
mod model;
mod named;
mod ops;
mod perception;
pub mod precondition;
mod recognition;
pub mod spatial;
pub mod whole_numbers;

use std::sync::Arc;

use axum::extract::{DefaultBodyLimit, FromRef};
use axum::http::StatusCode;
use axum::http::header::ETAG;
use axum::middleware::from_fn_with_state;
use axum::response::{IntoResponse, Response};
use axum::routing::{MethodRouter, get, post};
use axum::{Json, Router};
use serde::Serialize;

use super::actor::{Applied, Handle};
use super::auth::{Guard, Role, Tokens, guard};
use super::events::Feed;
use super::metrics::Metrics;
use super::problem::Problem;
use crate::edit::{Edit, Outcome};
use crate::model::World;
use crate::model::camera::{Camera, Light};
use precondition::etag;

/// The largest request body accepted by default, in bytes (a polyhedron upload is the
/// big one).
pub const MAX_REQUEST_BYTES: usize = 64 * 1024 * 1024;

/// What every handler can reach.
#[derive(Clone)]
pub struct AppState {
    /// The world's owner.
    pub handle: Handle,
    /// Recent changes and the live change stream.
    pub feed: Arc<Feed>,
    /// The bearer tokens routes are guarded with.
    pub tokens: Arc<Tokens>,
    /// The server's metrics.
    pub metrics: Arc<Metrics>,
    /// Scenes and turns for renderings.
    pub appearance: Arc<appearance::Appearance>,
    /// The spatial index queries share.
    pub spatial: Arc<crate::server::index::SpatialAccess>,
    /// Turns for camera solutions: one per core.
    pub solves: Arc<tokio::sync::Semaphore>,
}

impl FromRef<AppState> for Handle {
    fn from_ref(s: &AppState) -> Handle {
        s.handle.clone()
    }
}

impl FromRef<AppState> for Arc<Feed> {
    fn from_ref(s: &AppState) -> Arc<Feed> {
        s.feed.clone()
    }
}

/// `r` admitting only callers whose token holds at least `need` (everyone when no
/// tokens are configured).
fn guarded(r: MethodRouter<AppState>, tokens: &Arc<Tokens>, need: Role) -> MethodRouter<AppState> {
    r.route_layer(from_fn_with_state(Guard::new(tokens.clone(), need), guard))
}

/// The router over a running owner and its change feed.
///
/// Unguarded: `/healthz`, `/readyz`, `/openapi.json`, and the viewer (`/` and
/// `/viewer/{file}`: the page asks for a token itself). Everything else needs a token
/// (when tokens are configured) of the role its marker names: [`Role::Read`] for
/// `reads`, [`Role::Write`] for `writes`, [`Role::Admin`] for `admin`.
pub fn router(state: AppState, max_request_bytes: usize) -> Router {
    use model::*;
    let tokens = state.tokens.clone();
    let reads = |r| guarded(r, &tokens, Role::Read);
    let writes = |r| guarded(r, &tokens, Role::Write);
    let admin = |r| guarded(r, &tokens, Role::Admin);
    Router::new()
        .route("/healthz", get(ops::healthz))
        .route("/readyz", get(ops::readyz))
        .route("/openapi.json", get(ops::openapi))
        .route("/", get(crate::server::viewer::index))
        .route("/viewer/{file}", get(crate::server::viewer::asset))
        .route("/metrics", reads(get(ops::metrics)))
        .route("/v1/admin/snapshot", admin(post(ops::snapshot_now)))
        .route("/v1/world", reads(get(world)))
        .route("/v1/world/changes", reads(get(feed::changes)))
        .route("/v1/world/events", reads(get(feed::events)))
        .route("/v1/world/mesh", reads(get(mesh::export_world)))
        .route(
            "/v1/bodies",
            reads(get(list_bodies)).merge(writes(post(create_body))),
        )
        .route(
            "/v1/bodies/{id}",
            reads(get(get_body))
                .merge(writes(axum::routing::patch(patch_body).delete(delete_body))),
        )
        .route("/v1/bodies/import", writes(post(mesh::import)))
        .route("/v1/bodies/{id}/topology", reads(get(topology)))
        .route("/v1/bodies/{id}/mesh", reads(get(mesh::export_body)))
        .route("/v1/bodies/{id}/euler", writes(post(euler)))
        .route("/v1/bodies/{id}/transform", writes(post(transform)))
        .route("/v1/bodies/{id}/sweep", writes(post(sweep)))
        .route("/v1/bodies/{id}/dual", writes(post(dual)))
        .route("/v1/bodies/{id}/evert", writes(post(evert)))
        .route("/v1/bodies/{id}/copy", writes(post(copy)))
        .route("/v1/bodies/{id}/boolean", writes(post(boolean)))
        .route("/v1/cameras", reads(get(named::list::<Camera>)))
        .route(
            "/v1/cameras/{name}/image",
            reads(get(appearance::camera_image)),
        )
        .route("/v1/appearance", reads(post(appearance::appearance)))
        .route(
            "/v1/camera-solution",
            reads(post(camera_solution::camera_solution)),
        )
        .route("/v1/recognition", reads(post(recognition::recognition)))
        .route("/v1/perception", writes(post(perception::perception)))
        .route(
            "/v1/cameras/{name}",
            reads(get(named::get_one::<Camera>)).merge(writes(
                axum::routing::put(named::put::<Camera>).delete(named::delete::<Camera>),
            )),
        )
        .route(
            "/v1/spatial/sphere",
            reads(get(spatial::sphere).post(spatial::sphere)),
        )
        .route(
            "/v1/spatial/box",
            reads(get(spatial::aabb).post(spatial::aabb)),
        )
        .route(
            "/v1/spatial/nearest",
            reads(get(spatial::nearest).post(spatial::nearest)),
        )
        .route(
            "/v1/spatial/ray",
            reads(get(spatial::ray).post(spatial::ray)),
        )
        .route("/v1/lights", reads(get(named::list::<Light>)))
        .route(
            "/v1/lights/{name}",
            reads(get(named::get_one::<Light>)).merge(writes(
                axum::routing::put(named::put::<Light>).delete(named::delete::<Light>),
            )),
        )
        .fallback(not_found)
        .layer(axum::extract::Extension(HeavyReads::for_this_machine()))
        .layer(axum::extract::Extension(body::Bodies::for_this_machine(
            max_request_bytes,
        )))
        .layer(DefaultBodyLimit::max(max_request_bytes))
        .with_state(state)
}

type Answer = Result<Response, Problem>;

/// The gate heavy reads (topology dumps) pass: one permit per core but one, at least one.
#[derive(Clone)]
struct HeavyReads(Arc<tokio::sync::Semaphore>);

impl HeavyReads {
    fn for_this_machine() -> Self {
        let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
        HeavyReads(Arc::new(tokio::sync::Semaphore::new(
            cores.saturating_sub(1).max(1),
        )))
    }
}

/// A write's answer: the outcome's fields and the revision.
#[derive(Serialize)]
struct Written {
    #[serde(flatten)]
    outcome: Outcome,
    revision: u64,
}

/// Applies `edit` if the world is at `expected`; answers `status` with the outcome, the
/// revision and its `ETag`.
async fn write(h: &Handle, edit: Edit, expected: Option<u64>, status: StatusCode) -> Answer {
    let Applied { outcome, revision } = h.apply_if(edit, expected).await?;
    Ok((
        status,
        [(ETAG, etag(revision))],
        Json(Written { outcome, revision }),
    )
        .into_response())
}

/// A snapshot of the durable world.
async fn snapshot(h: &Handle) -> Result<Arc<World>, Problem> {
    h.snapshot().await.map_err(|_| Problem::unavailable())
}

/// A JSON read answer at revision `revision`, with its `ETag`.
fn read_answer(revision: u64, body: impl Serialize) -> Response {
    ([(ETAG, etag(revision))], Json(body)).into_response()
}

/// Faces, edges and vertices in all the world's bodies (constant time).
fn world_size(w: &World) -> (usize, usize, usize) {
    let s = w.size();
    (s.faces, s.edges, s.vertices)
}

async fn not_found() -> Problem {
    Problem::not_found("no such route; see /openapi.json")
}
