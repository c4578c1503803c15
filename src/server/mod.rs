//! The server: the owner of the world, the journal that makes its writes durable, the
//! change feed, and the HTTP/JSON API in front of them.
//!
//! ```text
//! HTTP request ─> api (auth, limits, parse, validate, map errors)
//!                  │ writes: Edit ─mpsc─> actor (single owner of the World)
//!                  │                        ├ applies, journals the group in one commit
//!                  │                        └ acknowledges, publishes Changes to the feed
//!                  └ reads: actor hands out Arc<World> snapshots; heavy reads run on them
//!                          in spawn_blocking
//! ```

pub mod actor;
pub mod api;
pub mod auth;
pub mod background;
pub mod changes;
pub mod demo;
pub mod dto;
pub mod durable;
pub mod events;
pub mod index;
pub mod limits;
pub mod listen;
pub mod metrics;
pub mod problem;
pub mod request;
pub mod spec;
pub mod viewer;

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use axum::Router;
use axum::extract::{Request, State};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use tokio::net::TcpListener;
use tokio::sync::Semaphore;
use tower_http::trace::{DefaultMakeSpan, DefaultOnResponse, TraceLayer};
use tracing::Level;

use crate::model::World;
use actor::{ActorConfig, Journal};
use auth::Tokens;
use changes::Change;
use events::Feed;
use metrics::Metrics;
use problem::Problem;

/// Limits that keep one client, or many, from exhausting the server.
#[derive(Debug, Clone, Copy)]
pub struct Limits {
    /// The largest request body, in bytes.
    pub max_request_bytes: usize,
    /// How long a request may take before it is answered 503 (the change stream is not
    /// bounded by it once its headers are sent).
    pub request_timeout: Duration,
    /// Requests handled at once; more are answered 503 with `Retry-After` at once.
    pub max_in_flight: usize,
    /// The world owner's queue and group-commit size.
    pub actor: ActorConfig,
    /// Changes kept in memory for `GET /v1/world/changes` and stream catch-up.
    pub history: usize,
    /// The largest image appearance draws, in pixels.
    pub max_render_pixels: u64,
    /// How long a request line and headers may take to arrive, from accept for a
    /// connection's first request and from the first byte for later ones; a connection
    /// still short of a complete head then is closed.
    pub header_timeout: Duration,
    /// How long a kept-alive connection may wait with no request in flight before it is
    /// closed (a response still streaming, such as the change stream, is in flight).
    pub idle_timeout: Duration,
    /// Connections served at once, lowered to fit the open-file limit (less
    /// [`listen::RESERVED_DESCRIPTORS`]); a connection past it closes the longest idle one
    /// or, if none is idle, is answered 503.
    pub max_connections: usize,
    /// How long a stop waits for connections to finish before dropping them.
    pub shutdown_deadline: Duration,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_request_bytes: api::MAX_REQUEST_BYTES,
            request_timeout: Duration::from_secs(60),
            max_in_flight: 4096,
            actor: ActorConfig::default(),
            history: 100_000,
            max_render_pixels: api::appearance::MAX_RENDER_PIXELS,
            header_timeout: Duration::from_secs(10),
            idle_timeout: Duration::from_secs(60),
            max_connections: 1024,
            shutdown_deadline: Duration::from_secs(10),
        }
    }
}

/// Everything a server is built with besides its world and journal.
#[derive(Clone)]
pub struct Options {
    /// Limits on requests and the owner's queue.
    pub limits: Limits,
    /// Bearer tokens; none means every caller may do everything (loopback only, see
    /// [`auth::check_bind`]).
    pub tokens: Arc<Tokens>,
    /// Where counts and timings go.
    pub metrics: Arc<Metrics>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            limits: Limits::default(),
            tokens: Arc::new(Tokens::none()),
            metrics: Arc::new(Metrics::new()),
        }
    }
}

/// A built application: the router and the feed its event streams follow.
pub struct App {
    /// The HTTP routes with every layer.
    pub router: Router,
    /// The change feed (closed at shutdown so event streams end).
    pub feed: Arc<Feed>,
    /// The world owner's thread: it ends once the router (and every handle) is dropped,
    /// after the journal's final snapshot.
    pub owner: std::thread::JoinHandle<()>,
    /// How connections are accepted, kept and ended.
    pub connections: listen::Settings,
}

/// Builds the application over `world`, made durable by `journal`, with `recent`
/// changes (oldest first, ending at the world's revision) as the initial history.
pub fn build<J: Journal>(
    world: World,
    journal: J,
    recent: Vec<Change>,
    options: Options,
) -> std::io::Result<App> {
    let Options {
        limits,
        tokens,
        metrics,
    } = options;
    let feed = Feed::new(limits.history, world.revision(), recent);
    let observer: Arc<dyn actor::Observer> = metrics.clone();
    let (handle, owner) = actor::spawn(world, journal, feed.clone(), observer, limits.actor)?;
    let state = api::AppState {
        handle,
        feed: feed.clone(),
        tokens,
        metrics: metrics.clone(),
        appearance: Arc::new(api::appearance::Appearance::new(limits.max_render_pixels)),
        spatial: Arc::new(index::SpatialAccess::new(metrics.clone())),
        solves: Arc::new(Semaphore::new(
            std::thread::available_parallelism().map_or(2, |n| n.get()),
        )),
    };
    let one_line_per_request = TraceLayer::new_for_http()
        .make_span_with(DefaultMakeSpan::new().level(Level::INFO))
        .on_request(())
        .on_response(DefaultOnResponse::new().level(Level::INFO))
        .on_body_chunk(())
        .on_eos(());
    let connections = listen::Settings::new(&limits, Some(metrics.clone()));
    let in_flight = Arc::new(Semaphore::new(limits.max_in_flight.max(1)));
    let router = api::router(state, limits.max_request_bytes)
        .layer(middleware::from_fn_with_state(
            limits.request_timeout,
            time_limit,
        ))
        .layer(middleware::from_fn_with_state(in_flight, shed_load))
        .layer(middleware::from_fn_with_state(metrics, metrics::track))
        .layer(one_line_per_request);
    Ok(App {
        router,
        feed,
        owner,
        connections,
    })
}

/// The application over `world` held in memory only (nothing survives a restart).
pub fn in_memory(world: World, limits: Limits) -> std::io::Result<App> {
    let options = Options {
        limits,
        ..Options::default()
    };
    build(world, actor::InMemory, Vec::new(), options)
}

/// Answers 503 with `Retry-After` at once when `max_in_flight` requests are already
/// being handled, so a flood cannot grow memory without bound.
async fn shed_load(State(permits): State<Arc<Semaphore>>, req: Request, next: Next) -> Response {
    match permits.try_acquire_owned() {
        Ok(permit) => {
            let res = next.run(req).await;
            drop(permit);
            res
        }
        Err(_) => {
            Problem::busy("too many requests are in flight; try again shortly", 1).into_response()
        }
    }
}

/// Answers 503 when a request takes longer than the limit.
async fn time_limit(State(limit): State<Duration>, req: Request, next: Next) -> Response {
    let is_write = !matches!(
        *req.method(),
        axum::http::Method::GET | axum::http::Method::HEAD
    );
    match tokio::time::timeout(limit, next.run(req)).await {
        Ok(res) => res,
        Err(_) => {
            let detail = if is_write {
                format!(
                    "no answer within {} s; the write may still be applied: see /v1/world/changes",
                    limit.as_secs_f64()
                )
            } else {
                format!("no answer within {} s", limit.as_secs_f64())
            };
            problem::refused_unread(
                Problem::new(
                    axum::http::StatusCode::SERVICE_UNAVAILABLE,
                    "timeout",
                    "Request timed out",
                    detail,
                )
                .retry_after(1)
                .into_response(),
            )
        }
    }
}

/// Binds `addr` and serves `app` until `shutdown` resolves; then stops within the
/// application's connection limits (see [`serve_on`]).
/// Returns the bound address through `bound` as soon as it is listening.
pub async fn serve(
    addr: SocketAddr,
    app: App,
    bound: impl FnOnce(SocketAddr),
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    let listener = TcpListener::bind(addr).await?;
    bound(listener.local_addr()?);
    serve_on(listener, app, shutdown).await
}

/// Serves `app` on a bound `listener` until `shutdown` resolves, within its connection
/// limits ([`listen::serve`]). Then: accepting ends, event streams end, requests in flight
/// are answered and idle connections close; connections still open after the shutdown
/// deadline are dropped; the world's owner closes its journal last.
pub async fn serve_on(
    listener: TcpListener,
    app: App,
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    let App {
        router,
        feed,
        owner,
        connections,
    } = app;
    let served = listen::serve(listener, router, connections, async move {
        shutdown.await;
        feed.close();
    })
    .await;
    // The router is gone: the owner finishes its queue, closes its journal and stops.
    let _ = tokio::task::spawn_blocking(move || owner.join()).await;
    served
}
