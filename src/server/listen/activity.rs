//! What one connection is doing: requests in flight, since when it is idle, since when a
//! request head is arriving, and whether it was asked to stop.
//!
//! The connection's own task changes it (hyper reads, calls the service and drops response
//! bodies on that task); the accept loop reads it to choose a connection to evict and asks
//! connections to stop. Times are kept as milliseconds since the connection was accepted.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use tokio::sync::Notify;

/// `head_since` when no request head is arriving.
const NO_HEAD: u64 = u64::MAX;

/// The state of one connection.
#[derive(Debug)]
pub(super) struct Activity {
    /// When the connection was accepted.
    accepted: Instant,
    /// Requests whose answer is not yet completely handed to hyper.
    in_flight: AtomicUsize,
    /// Requests ever started.
    requests: AtomicU64,
    /// Milliseconds after `accepted` when the last request ended (0: since accepted).
    idle_since: AtomicU64,
    /// Milliseconds after `accepted` when the request head being read began: at accept
    /// for the first request, at the first byte for later ones; [`NO_HEAD`] when none is.
    head_since: AtomicU64,
    /// Set once the connection is asked to stop.
    stop: AtomicBool,
    /// Wakes the connection's watchdog when a deadline may have moved earlier or a stop
    /// was asked for.
    wake: Notify,
}

/// What a connection's watchdog waits for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Lapse {
    /// A request head still incomplete after the header timeout: close at once.
    Head,
    /// No request for the idle timeout: close gracefully.
    Idle,
}

impl Activity {
    /// A connection accepted now; its first request head is due within the header timeout.
    pub(super) fn new() -> Arc<Activity> {
        Arc::new(Activity {
            accepted: Instant::now(),
            in_flight: AtomicUsize::new(0),
            requests: AtomicU64::new(0),
            idle_since: AtomicU64::new(0),
            head_since: AtomicU64::new(0),
            stop: AtomicBool::new(false),
            wake: Notify::new(),
        })
    }

    fn now_ms(&self) -> u64 {
        u64::try_from(self.accepted.elapsed().as_millis()).unwrap_or(NO_HEAD - 1)
    }

    fn at(&self, ms: u64) -> Option<Instant> {
        self.accepted.checked_add(Duration::from_millis(ms))
    }

    /// A request's head was read and the service called: in flight until the returned
    /// guard (held by the response body) is dropped.
    pub(super) fn begin_request(self: &Arc<Self>) -> Busy {
        self.in_flight.fetch_add(1, Ordering::AcqRel);
        self.requests.fetch_add(1, Ordering::Relaxed);
        self.head_since.store(NO_HEAD, Ordering::Release);
        Busy(self.clone())
    }

    /// Bytes were read from the client. With no request in flight they begin the next
    /// request head: its header timeout starts now, unless one is already running.
    pub(super) fn bytes_arrived(&self) {
        if self.in_flight.load(Ordering::Acquire) == 0
            && self
                .head_since
                .compare_exchange(NO_HEAD, self.now_ms(), Ordering::AcqRel, Ordering::Acquire)
                .is_ok()
        {
            self.wake.notify_one();
        }
    }

    /// Whether no request is in flight.
    pub(super) fn is_idle(&self) -> bool {
        self.in_flight.load(Ordering::Acquire) == 0
    }

    /// Whether the connection never started a request (nothing was ever answered on it).
    pub(super) fn never_served(&self) -> bool {
        self.requests.load(Ordering::Relaxed) == 0
    }

    /// Since when the connection has had no request in flight (its accept time if it never
    /// had one). Meaningful only while [`Activity::is_idle`].
    pub(super) fn idle_since(&self) -> Instant {
        self.at(self.idle_since.load(Ordering::Acquire))
            .unwrap_or(self.accepted)
    }

    /// The next deadline and what happens there: none while a request is in flight; the
    /// header timeout while a request head is arriving; else, if `idle` is given, the idle
    /// timeout. A deadline too far to represent is none.
    pub(super) fn due(&self, header: Duration, idle: Option<Duration>) -> Option<(Instant, Lapse)> {
        if !self.is_idle() {
            return None;
        }
        match self.head_since.load(Ordering::Acquire) {
            NO_HEAD => {
                let since = self.at(self.idle_since.load(Ordering::Acquire))?;
                Some((since.checked_add(idle?)?, Lapse::Idle))
            }
            head => Some((self.at(head)?.checked_add(header)?, Lapse::Head)),
        }
    }

    /// Asks the connection to stop (evicted, or the server is stopping).
    pub(super) fn request_stop(&self) {
        self.stop.store(true, Ordering::Release);
        self.wake.notify_one();
    }

    /// Whether the connection was asked to stop.
    pub(super) fn stop_requested(&self) -> bool {
        self.stop.load(Ordering::Acquire)
    }

    /// Resolves after a stop was asked for or a deadline may have moved (a permit is kept
    /// if that happened while nobody waited).
    pub(super) async fn changed(&self) {
        self.wake.notified().await;
    }
}

/// A request in flight; dropping it ends the request (the connection may become idle).
#[derive(Debug)]
pub(super) struct Busy(Arc<Activity>);

impl Drop for Busy {
    fn drop(&mut self) {
        let a = &self.0;
        if a.in_flight.fetch_sub(1, Ordering::AcqRel) == 1 {
            a.idle_since.store(a.now_ms(), Ordering::Release);
            a.wake.notify_one();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: Duration = Duration::from_secs(10);
    const IDLE: Duration = Duration::from_secs(60);

    #[test]
    fn the_first_head_is_due_a_header_timeout_after_accept() {
        let a = Activity::new();
        let (at, lapse) = a.due(HEADER, Some(IDLE)).expect("a deadline");
        assert_eq!(lapse, Lapse::Head);
        assert!(at <= Instant::now() + HEADER);
        assert!(a.never_served());
    }

    #[test]
    fn a_request_in_flight_has_no_deadline_and_its_end_starts_the_idle_clock() {
        let a = Activity::new();
        let busy = a.begin_request();
        assert!(!a.is_idle());
        assert_eq!(a.due(HEADER, Some(IDLE)), None);
        // Bytes during a request (a body, a pipelined request) start no head clock.
        a.bytes_arrived();
        drop(busy);
        assert!(a.is_idle());
        assert!(!a.never_served());
        let (_, lapse) = a.due(HEADER, Some(IDLE)).expect("a deadline");
        assert_eq!(lapse, Lapse::Idle);
        assert_eq!(a.due(HEADER, None), None);
        // The next request's first bytes start its header clock.
        a.bytes_arrived();
        let (_, lapse) = a.due(HEADER, Some(IDLE)).expect("a deadline");
        assert_eq!(lapse, Lapse::Head);
    }

    #[test]
    fn a_deadline_beyond_what_an_instant_holds_is_none() {
        let a = Activity::new();
        assert_eq!(a.due(Duration::MAX, Some(IDLE)), None);
    }
}
