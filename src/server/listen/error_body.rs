//! hyper's own error answers with a problem body.
//!
//! When a request head cannot be parsed, hyper answers by itself, before the application
//! sees anything, and with an empty body: `400 Bad Request` (a malformed request line or
//! header), `431 Request Header Fields Too Large` (a head over the limit) or `414 URI Too
//! Long`; then it closes the connection. `hyper::server::conn::http1::Builder` has no hook
//! for these, so the connection's socket is wrapped: a write that is exactly such an
//! answer, made while no request of the application is in flight, is replaced by the same
//! status as `application/problem+json`. hyper's answer is recognized strictly: one of the
//! three status lines, then only the header lines `content-length: 0`, `date: ...` and
//! `connection: close` (the first required), then the blank line ending the write. An
//! application answer never has that shape (its error bodies are never empty), so nothing
//! else is touched. An error answer written together with the end of a previous answer (a
//! malformed request pipelined behind a good one) does not match and goes out as hyper
//! wrote it.

use std::io;
use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context, Poll, ready};

use axum::http::StatusCode;
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};

use super::activity::Activity;
use super::raw;
use crate::server::problem::Problem;

/// The longest write that can be one of hyper's error answers (status line, three short
/// headers, blank line).
const LONGEST: usize = 256;

/// `inner`, whose writes of hyper's bodiless error answers are given problem bodies;
/// reads pass through.
pub(super) struct ErrorBodies<S> {
    inner: S,
    activity: Arc<Activity>,
    /// The limit on a request head, named in the 431 answer's detail.
    max_head: usize,
    /// A replacement answer not yet wholly written, and how much of it was.
    pending: Option<(Vec<u8>, usize)>,
}

impl<S> ErrorBodies<S> {
    /// Wraps `inner`, the socket of the connection `activity` describes; request heads on
    /// it are limited to `max_head` bytes.
    pub(super) fn new(inner: S, activity: Arc<Activity>, max_head: usize) -> Self {
        ErrorBodies {
            inner,
            activity,
            max_head,
            pending: None,
        }
    }
}

impl<S: AsyncWrite + Unpin> ErrorBodies<S> {
    /// Writes what is left of a replacement answer. Ready once nothing is pending.
    fn poll_pending(&mut self, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        while let Some((answer, written)) = &mut self.pending {
            if *written == answer.len() {
                self.pending = None;
                break;
            }
            let n = ready!(Pin::new(&mut self.inner).poll_write(cx, &answer[*written..]))?;
            if n == 0 {
                return Poll::Ready(Err(io::ErrorKind::WriteZero.into()));
            }
            *written += n;
        }
        Poll::Ready(Ok(()))
    }

    /// If `bytes` (a whole write) is one of hyper's error answers, made while the
    /// application has no request in flight, queues its replacement and says so.
    fn replace(&mut self, bytes: &[u8]) -> bool {
        if !self.activity.is_idle() {
            return false;
        }
        match with_problem_body(bytes, self.max_head) {
            Some(answer) => {
                self.pending = Some((answer, 0));
                true
            }
            None => false,
        }
    }
}

/// The answer to send instead of `bytes` if `bytes` is exactly one of hyper's bodiless
/// error answers; `None` for anything else.
fn with_problem_body(bytes: &[u8], max_head: usize) -> Option<Vec<u8>> {
    if bytes.len() > LONGEST {
        return None;
    }
    let head = bytes.strip_suffix(b"\r\n\r\n")?;
    let text = std::str::from_utf8(head).ok()?;
    let mut lines = text.split("\r\n");
    let problem = match lines.next()? {
        "HTTP/1.1 400 Bad Request" => Problem::bad_request(
            "the request is not well-formed HTTP/1.1: its request line or a header cannot be parsed",
        ),
        "HTTP/1.1 431 Request Header Fields Too Large" => Problem::new(
            StatusCode::REQUEST_HEADER_FIELDS_TOO_LARGE,
            "header-too-large",
            "Request header fields too large",
            format!("the request line and headers take more than {max_head} bytes"),
        ),
        "HTTP/1.1 414 URI Too Long" => Problem::new(
            StatusCode::URI_TOO_LONG,
            "uri-too-long",
            "URI too long",
            "the request target is too long",
        ),
        _ => return None,
    };
    let mut date = None;
    let (mut length, mut close) = (false, false);
    for line in lines {
        match line {
            "content-length: 0" if !length => length = true,
            "connection: close" if !close => close = true,
            _ => match line.strip_prefix("date: ") {
                Some(value)
                    if date.is_none() && value.bytes().all(|b| (b' '..=b'~').contains(&b)) =>
                {
                    date = Some(line);
                }
                _ => return None,
            },
        }
    }
    if !length {
        return None;
    }
    let extra = date.map(|d| format!("{d}\r\n")).unwrap_or_default();
    Some(raw::answer(&problem, extra.as_bytes()))
}

impl<S: AsyncRead + Unpin> AsyncRead for ErrorBodies<S> {
    fn poll_read(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        Pin::new(&mut self.get_mut().inner).poll_read(cx, buf)
    }
}

impl<S: AsyncWrite + Unpin> AsyncWrite for ErrorBodies<S> {
    /// Postcondition: a replacement is reported as `buf.len()` bytes written; the caller's
    /// next write, flush or shutdown first finishes writing it.
    fn poll_write(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        let this = self.get_mut();
        ready!(this.poll_pending(cx))?;
        if this.replace(buf) {
            // Start at once; whatever the socket does not take now is finished later.
            if let Poll::Ready(Err(e)) = this.poll_pending(cx) {
                return Poll::Ready(Err(e));
            }
            return Poll::Ready(Ok(buf.len()));
        }
        Pin::new(&mut this.inner).poll_write(cx, buf)
    }

    fn poll_write_vectored(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        bufs: &[io::IoSlice<'_>],
    ) -> Poll<io::Result<usize>> {
        let this = self.get_mut();
        ready!(this.poll_pending(cx))?;
        let total: usize = bufs.iter().map(|b| b.len()).sum();
        if total <= LONGEST {
            let whole: Vec<u8> = bufs.iter().flat_map(|b| b.iter().copied()).collect();
            if this.replace(&whole) {
                if let Poll::Ready(Err(e)) = this.poll_pending(cx) {
                    return Poll::Ready(Err(e));
                }
                return Poll::Ready(Ok(total));
            }
        }
        Pin::new(&mut this.inner).poll_write_vectored(cx, bufs)
    }

    fn is_write_vectored(&self) -> bool {
        self.inner.is_write_vectored()
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        let this = self.get_mut();
        ready!(this.poll_pending(cx))?;
        Pin::new(&mut this.inner).poll_flush(cx)
    }

    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        let this = self.get_mut();
        ready!(this.poll_pending(cx))?;
        Pin::new(&mut this.inner).poll_shutdown(cx)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DATE: &str = "date: Thu, 01 Jan 2030 00:00:00 GMT";

    fn problem_of(answer: &[u8]) -> (String, serde_json::Value) {
        let text = String::from_utf8(answer.to_vec()).expect("text");
        let (head, body) = text.split_once("\r\n\r\n").expect("a head and a body");
        (
            head.to_owned(),
            serde_json::from_str(body).expect("a JSON body"),
        )
    }

    #[test]
    fn hypers_error_answers_get_problem_bodies_and_keep_their_date() {
        for (line, status) in [
            ("HTTP/1.1 400 Bad Request", 400),
            ("HTTP/1.1 431 Request Header Fields Too Large", 431),
            ("HTTP/1.1 414 URI Too Long", 414),
        ] {
            let hyper = format!("{line}\r\ncontent-length: 0\r\n{DATE}\r\n\r\n");
            let answer = with_problem_body(hyper.as_bytes(), 65_536).expect("replaced");
            let (head, json) = problem_of(&answer);
            assert!(head.starts_with(line), "{head}");
            assert!(head.contains("content-type: application/problem+json"));
            assert!(head.contains("connection: close"));
            assert!(head.contains(DATE));
            assert_eq!(json["status"], status);
        }
        let closing = format!(
            "HTTP/1.1 400 Bad Request\r\nconnection: close\r\ncontent-length: 0\r\n{DATE}\r\n\r\n"
        );
        assert!(with_problem_body(closing.as_bytes(), 65_536).is_some());
    }

    #[test]
    fn anything_else_is_left_alone() {
        for other in [
            // Not one of the three statuses.
            format!("HTTP/1.1 404 Not Found\r\ncontent-length: 0\r\n{DATE}\r\n\r\n"),
            // A body follows, or another header is present.
            format!("HTTP/1.1 400 Bad Request\r\ncontent-length: 2\r\n{DATE}\r\n\r\n{{}}"),
            "HTTP/1.1 400 Bad Request\r\ncontent-type: text/plain\r\ncontent-length: 0\r\n\r\n"
                .to_owned(),
            // No content-length, a repeated header, an unfinished head.
            format!("HTTP/1.1 400 Bad Request\r\n{DATE}\r\n\r\n"),
            "HTTP/1.1 400 Bad Request\r\ncontent-length: 0\r\ncontent-length: 0\r\n\r\n".to_owned(),
            "HTTP/1.1 400 Bad Request\r\ncontent-length: 0\r\n".to_owned(),
            // The bytes of an answer inside a longer write.
            format!("x\r\nHTTP/1.1 400 Bad Request\r\ncontent-length: 0\r\n{DATE}\r\n\r\n"),
        ] {
            assert!(
                with_problem_body(other.as_bytes(), 65_536).is_none(),
                "{other}"
            );
        }
    }
}
