//! The answer to a connection arriving when every place is taken by a busy connection:
//! `503` problem+json with `Retry-After: 1` and `Connection: close`, then the close.
//!
//! The answer is written at once, without reading the request; the socket is then shut for
//! writing and what the client sent is read and discarded for a moment, so the close does
//! not reset the connection before the client has read the answer. A refusal takes at most
//! [`LINGER`], and at most [`MOST_AT_ONCE`] are under way: beyond that a connection is
//! closed without an answer, so a flood cannot hold more descriptors through refusals.

use std::future::{Future, poll_fn};
use std::io;
use std::pin::Pin;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::TcpStream;

use super::raw;
use crate::server::metrics::Metrics;
use crate::server::problem::Problem;

/// The longest one refusal takes.
const LINGER: Duration = Duration::from_secs(1);
/// The most refusals under way at once.
const MOST_AT_ONCE: usize = 32;

/// Refusals under way, and where they are counted.
#[derive(Debug)]
pub(super) struct Refusals {
    under_way: Arc<AtomicUsize>,
    metrics: Option<Arc<Metrics>>,
}

/// One refusal under way; dropping it makes room for another.
struct UnderWay(Arc<AtomicUsize>);

impl Drop for UnderWay {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::AcqRel);
    }
}

impl Refusals {
    /// None under way; each refusal is counted in `metrics`.
    pub(super) fn new(metrics: Option<Arc<Metrics>>) -> Refusals {
        Refusals {
            under_way: Arc::new(AtomicUsize::new(0)),
            metrics,
        }
    }

    /// The refusal of `stream`, to be run as a task; `None` (and `stream` closed at once)
    /// when [`MOST_AT_ONCE`] are already under way.
    pub(super) fn refuse(
        &self,
        stream: TcpStream,
    ) -> Option<impl Future<Output = ()> + Send + 'static> {
        if let Some(m) = &self.metrics {
            m.refuse_connection();
        }
        if self.under_way.fetch_add(1, Ordering::AcqRel) >= MOST_AT_ONCE {
            self.under_way.fetch_sub(1, Ordering::AcqRel);
            return None;
        }
        let slot = UnderWay(self.under_way.clone());
        Some(async move {
            let _ = tokio::time::timeout(LINGER, answer(stream)).await;
            drop(slot);
        })
    }
}

/// Writes the 503 answer, shuts the socket for writing and discards what the client sends
/// until it closes.
async fn answer(mut stream: TcpStream) -> io::Result<()> {
    let problem = Problem::busy(
        "too many open connections, each with a request in flight; try again shortly",
        1,
    );
    let answer = raw::answer(&problem, b"");
    let mut written = 0;
    while written < answer.len() {
        let n = poll_fn(|cx| Pin::new(&mut stream).poll_write(cx, &answer[written..])).await?;
        if n == 0 {
            return Err(io::ErrorKind::WriteZero.into());
        }
        written += n;
    }
    poll_fn(|cx| Pin::new(&mut stream).poll_shutdown(cx)).await?;
    let mut sink = [0u8; 4096];
    loop {
        let mut buf = ReadBuf::new(&mut sink);
        poll_fn(|cx| Pin::new(&mut stream).poll_read(cx, &mut buf)).await?;
        if buf.filled().is_empty() {
            return Ok(());
        }
    }
}
