//! Accepting and serving HTTP/1.1 connections within limits.
//!
//! - **Header timeout**: a request head must be complete within it, counted from accept for
//!   the first request and from its first byte for later ones; else the connection is
//!   closed.
//! - **Idle timeout**: a kept-alive connection with no request in flight for that long is
//!   closed. A response still being sent (the change stream) is a request in flight.
//! - **Connection cap**: at most `max_connections`, lowered to fit the open-file limit
//!   (`RLIMIT_NOFILE` less [`RESERVED_DESCRIPTORS`]). A connection arriving at the cap
//!   makes room by closing the connection idle the longest; if every one has a request in
//!   flight, it is answered `503` (problem+json, `Retry-After: 1`) and closed.
//! - **Accept errors**: out of descriptors or memory, the loop pauses (50 ms doubling to
//!   1 s) and warns, rate limited; one connection's error is passed over.
//! - **Stop**: accepting ends, every connection is asked to finish gracefully (requests in
//!   flight are answered, idle connections close), and those still open after the
//!   shutdown deadline are dropped.
//! - **hyper's own answers** to a request head it cannot parse (400, 431, 414) carry a
//!   problem+json body like every other error.

mod activity;
mod backoff;
mod connection;
mod descriptors;
mod error_body;
mod head_clock;
mod raw;
mod refuse;
mod table;
mod tracking;

pub use descriptors::RESERVED_DESCRIPTORS;

use std::future::Future;
use std::io;
use std::sync::Arc;
use std::time::Duration;

use axum::Router;
use hyper::server::conn::http1;
use hyper_util::rt::TokioTimer;
use tokio::net::TcpListener;
use tokio::task::JoinSet;
use tracing::{info, warn};

use super::Limits;
use super::metrics::Metrics;
use backoff::Backoff;
use connection::Shared;
use refuse::Refusals;
use table::Table;

/// The most bytes of a request line and headers; a longer head is answered 431.
pub const MAX_HEAD_BYTES: usize = 64 * 1024;

/// The longest any timeout here is taken to be (longer ones are shortened to it), so that
/// every deadline is a representable instant.
const LONGEST_TIMEOUT: Duration = Duration::from_secs(365 * 24 * 3600);

/// How connections are accepted, kept and ended.
#[derive(Debug, Clone)]
pub struct Settings {
    /// How long a request head may take to arrive completely.
    pub header_timeout: Duration,
    /// How long a connection may stay open with no request in flight.
    pub idle_timeout: Duration,
    /// Connections served at once (before lowering to the open-file limit).
    pub max_connections: usize,
    /// How long a stop waits for connections to finish before dropping them.
    pub shutdown_deadline: Duration,
    /// Where the number of open connections and refusals are reported, if anywhere.
    pub metrics: Option<Arc<Metrics>>,
}

impl Settings {
    /// The connection limits of `limits`, reporting to `metrics`.
    pub fn new(limits: &Limits, metrics: Option<Arc<Metrics>>) -> Settings {
        Settings {
            header_timeout: limits.header_timeout,
            idle_timeout: limits.idle_timeout,
            max_connections: limits.max_connections,
            shutdown_deadline: limits.shutdown_deadline,
            metrics,
        }
    }
}

impl Default for Settings {
    /// [`Limits::default`]'s, reporting nowhere.
    fn default() -> Self {
        Settings::new(&Limits::default(), None)
    }
}

/// A timeout within `1 ms ..= LONGEST_TIMEOUT`.
fn bounded(timeout: Duration) -> Duration {
    timeout.clamp(Duration::from_millis(1), LONGEST_TIMEOUT)
}

/// hyper's HTTP/1.1 settings: keep-alive, heads of at most [`MAX_HEAD_BYTES`], and hyper's
/// own header-read timer as a backstop covering an idle wait and a head together (the
/// watchdog of each connection enforces the two separately).
fn http1_settings(header: Duration, idle: Duration) -> http1::Builder {
    let mut http = http1::Builder::new();
    http.timer(TokioTimer::new())
        .keep_alive(true)
        .max_header_size(MAX_HEAD_BYTES)
        .header_read_timeout(header.saturating_add(idle).min(LONGEST_TIMEOUT));
    http
}

/// Serves `router` on `listener` within `settings` until `shutdown` resolves, then stops:
/// no more accepts, every connection asked to finish gracefully, those still open after
/// the shutdown deadline dropped.
///
/// Postcondition: when it returns, no connection of this listener is open and no task of
/// it is running.
pub async fn serve(
    listener: TcpListener,
    router: Router,
    settings: Settings,
    shutdown: impl Future<Output = ()>,
) -> io::Result<()> {
    let cap = descriptors::connection_cap(settings.max_connections, descriptors::open_file_limit());
    match cap.lowered_by {
        Some(nofile) => warn!(
            requested = settings.max_connections,
            max_connections = cap.connections,
            nofile,
            reserved = RESERVED_DESCRIPTORS,
            "the connection cap is lowered to fit the open-file limit (RLIMIT_NOFILE)"
        ),
        None => info!(max_connections = cap.connections, "connection cap"),
    }
    let header_timeout = bounded(settings.header_timeout);
    let idle_timeout = bounded(settings.idle_timeout);
    let shared = Arc::new(Shared {
        router,
        http: http1_settings(header_timeout, idle_timeout),
        header_timeout,
        idle_timeout,
        max_head: MAX_HEAD_BYTES,
    });
    let table = Table::new(cap.connections, settings.metrics.clone());
    let refusals = Refusals::new(settings.metrics.clone());
    let mut tasks = JoinSet::new();
    let mut backoff = Backoff::new();
    tokio::pin!(shutdown);
    loop {
        tokio::select! {
            () = &mut shutdown => break,
            Some(_) = tasks.join_next() => {}
            accepted = listener.accept() => match accepted {
                Ok((stream, _peer)) => {
                    backoff.succeeded();
                    match table.admit() {
                        Some(entry) => {
                            tasks.spawn(connection::serve(stream, shared.clone(), entry));
                        }
                        None => {
                            if let Some(refusal) = refusals.refuse(stream) {
                                tasks.spawn(refusal);
                            }
                        }
                    }
                }
                Err(error) => {
                    if let Some(pause) = backoff.failed(&error) {
                        tokio::select! {
                            () = &mut shutdown => break,
                            () = tokio::time::sleep(pause) => {}
                        }
                    }
                }
            },
        }
    }
    drop(listener);
    table.stop_all();
    let deadline = bounded(settings.shutdown_deadline);
    let drained = tokio::time::timeout(deadline, async {
        while tasks.join_next().await.is_some() {}
    })
    .await;
    if drained.is_err() {
        warn!(
            open = tasks.len(),
            deadline_s = deadline.as_secs_f64(),
            "connections still open at the shutdown deadline are dropped"
        );
        tasks.shutdown().await;
    }
    Ok(())
}
