//! Serving one connection: hyper's HTTP/1.1 over the socket, watched by a watchdog that
//! enforces the header and idle timeouts and carries out a stop.

use std::sync::Arc;
use std::time::{Duration, Instant};

use axum::Router;
use hyper::server::conn::http1;
use hyper_util::rt::TokioIo;
use tokio::net::TcpStream;
use tokio::time::sleep_until;
use tracing::debug;

use super::activity::Lapse;
use super::error_body::ErrorBodies;
use super::head_clock::HeadClock;
use super::table::Entry;
use super::tracking::Tracking;

/// What every connection is served with.
pub(super) struct Shared {
    /// The application.
    pub router: Router,
    /// hyper's HTTP/1.1 settings.
    pub http: http1::Builder,
    /// How long a request head may take, from accept (the first) or from its first byte.
    pub header_timeout: Duration,
    /// How long a connection may wait with no request in flight before the next one.
    pub idle_timeout: Duration,
    /// The most bytes of a request head, named in 431 answers.
    pub max_head: usize,
}

/// Serves `stream` until the client closes it, a timeout lapses, or a stop asked through
/// `entry` is carried out; the place in the table is freed at the end.
///
/// - A request head not complete `header_timeout` after it began: the connection is
///   dropped at once (hyper would do the same: there is no request to answer).
/// - No request in flight for `idle_timeout`: hyper's graceful shutdown, which closes an
///   idle connection at once.
/// - A stop (eviction, server shutdown): a connection that never started a request is
///   dropped at once (nothing was asked of it, and hyper would keep waiting for a head it
///   began to receive); any other is shut down gracefully: the request in flight is
///   answered, then the connection closes.
pub(super) async fn serve(stream: TcpStream, shared: Arc<Shared>, entry: Entry) {
    let activity = entry.activity.clone();
    let io = ErrorBodies::new(
        HeadClock::new(stream, activity.clone()),
        activity.clone(),
        shared.max_head,
    );
    let service = Tracking::new(shared.router.clone(), activity.clone());
    let conn = shared.http.serve_connection(TokioIo::new(io), service);
    tokio::pin!(conn);
    let mut graceful = false;
    loop {
        let idle = (!graceful).then_some(shared.idle_timeout);
        let due = activity.due(shared.header_timeout, idle);
        let lapse = async {
            match due {
                Some((at, _)) => sleep_until(at.into()).await,
                None => std::future::pending().await,
            }
        };
        tokio::select! {
            served = conn.as_mut() => {
                if let Err(error) = served {
                    debug!(%error, "connection ended with an error");
                }
                break;
            }
            () = activity.changed() => {
                if activity.stop_requested() && !graceful {
                    if activity.is_idle() && activity.never_served() {
                        break;
                    }
                    conn.as_mut().graceful_shutdown();
                    graceful = true;
                }
            }
            () = lapse => {
                // Things may have moved while sleeping: act only on a deadline still due.
                match activity.due(shared.header_timeout, idle) {
                    Some((at, Lapse::Head)) if at <= Instant::now() => {
                        debug!("no complete request head within the header timeout; closing");
                        break;
                    }
                    Some((at, Lapse::Idle)) if at <= Instant::now() => {
                        debug!("idle past the idle timeout; closing");
                        conn.as_mut().graceful_shutdown();
                        graceful = true;
                    }
                    _ => {}
                }
            }
        }
    }
    drop(entry);
}
