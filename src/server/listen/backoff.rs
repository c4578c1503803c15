//! What the accept loop does after `accept` fails.
//!
//! Running out of descriptors or memory (`EMFILE`, `ENFILE`, `ENOBUFS`, `ENOMEM`) fails
//! every accept until something is closed: the loop pauses (50 ms, doubling up to 1 s)
//! instead of spinning, and warns at most every few seconds. An error of one connection
//! (`ECONNABORTED`, `ECONNRESET`, ...) concerns that connection only and is passed over.

use std::io;
use std::time::{Duration, Instant};

use tracing::{debug, warn};

/// The first pause after a resource error.
const FIRST: Duration = Duration::from_millis(50);
/// The longest pause.
const LONGEST: Duration = Duration::from_secs(1);
/// The least time between two warnings.
const WARN_EVERY: Duration = Duration::from_secs(5);

/// The accept loop's state after errors.
#[derive(Debug)]
pub(super) struct Backoff {
    /// The next pause.
    pause: Duration,
    /// When the last warning was logged.
    warned: Option<Instant>,
    /// Resource errors since the last warning.
    unreported: u64,
}

impl Backoff {
    /// No error seen yet.
    pub(super) fn new() -> Backoff {
        Backoff {
            pause: FIRST,
            warned: None,
            unreported: 0,
        }
    }

    /// An accept succeeded: the next resource error pauses briefly again.
    pub(super) fn succeeded(&mut self) {
        self.pause = FIRST;
    }

    /// `error` failed an accept: how long to pause before accepting again (`None`: go on
    /// at once, the error was one connection's).
    pub(super) fn failed(&mut self, error: &io::Error) -> Option<Duration> {
        if !is_resource_error(error) {
            debug!(%error, "accept failed for one connection");
            return None;
        }
        self.unreported += 1;
        let now = Instant::now();
        if self
            .warned
            .is_none_or(|t| now.duration_since(t) >= WARN_EVERY)
        {
            warn!(
                %error,
                errors = self.unreported,
                pause_ms = self.pause.as_millis() as u64,
                "cannot accept connections (out of descriptors or memory); pausing"
            );
            self.warned = Some(now);
            self.unreported = 0;
        }
        let pause = self.pause;
        self.pause = (self.pause * 2).min(LONGEST);
        Some(pause)
    }
}

/// Whether `error` means the process or system is out of a resource (descriptors, buffers,
/// memory) rather than that one connection failed.
fn is_resource_error(error: &io::Error) -> bool {
    matches!(
        error.raw_os_error(),
        Some(libc::EMFILE | libc::ENFILE | libc::ENOBUFS | libc::ENOMEM)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resource_errors_pause_longer_each_time_up_to_a_second() {
        let mut b = Backoff::new();
        let emfile = io::Error::from_raw_os_error(libc::EMFILE);
        let pauses: Vec<u128> = (0..8)
            .map(|_| b.failed(&emfile).expect("a pause").as_millis())
            .collect();
        assert_eq!(pauses, [50, 100, 200, 400, 800, 1000, 1000, 1000]);
        b.succeeded();
        assert_eq!(b.failed(&emfile), Some(FIRST));
    }

    #[test]
    fn one_connections_errors_do_not_pause() {
        let mut b = Backoff::new();
        for code in [libc::ECONNABORTED, libc::ECONNRESET, libc::EPROTO] {
            assert_eq!(b.failed(&io::Error::from_raw_os_error(code)), None);
        }
    }
}
