//! The server: the actor that owns the world, and the HTTP/JSON API in front of it.
//!
//! ```text
//! HTTP request ─> api (parse, validate, map errors)
//!                  │ writes: Edit ─mpsc─> actor (single owner of the World) ─> reply + revision
//!                  └ reads: actor hands out Arc<World> snapshots; heavy reads run on them
//!                          in spawn_blocking
//! ```

pub mod actor;
pub mod api;
pub mod auth;
pub mod demo;
pub mod dto;
pub mod edit;
pub mod limits;
pub mod metrics;
pub mod problem;
pub mod spec;

use std::net::SocketAddr;

use axum::Router;
use tokio::net::TcpListener;
use tower_http::trace::{DefaultMakeSpan, DefaultOnResponse, TraceLayer};
use tracing::Level;

use crate::model::World;

/// The full application: the API router over a fresh actor owning `world`, with one log
/// line per request.
pub fn app(world: World) -> Router {
    let one_line_per_request = TraceLayer::new_for_http()
        .make_span_with(DefaultMakeSpan::new().level(Level::INFO))
        .on_request(())
        .on_response(DefaultOnResponse::new().level(Level::INFO))
        .on_body_chunk(())
        .on_eos(());
    api::router(actor::spawn(world)).layer(one_line_per_request)
}

/// Binds `addr` and serves `world` until `shutdown` resolves; in-flight requests finish
/// first. Returns the bound address through `bound` as soon as it is listening.
pub async fn serve(
    addr: SocketAddr,
    world: World,
    bound: impl FnOnce(SocketAddr),
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    let listener = TcpListener::bind(addr).await?;
    bound(listener.local_addr()?);
    axum::serve(listener, app(world))
        .with_graceful_shutdown(shutdown)
        .await
}
