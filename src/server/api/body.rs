//! Request bodies: read within the size limit, and parsed off the async workers when
//! they are large.
//!
//! A body is read into one buffer, sized from its `Content-Length`. A declared length
//! over the limit is refused (413) on that alone: nothing of it is kept, though up to
//! the limit of it is read and dropped first, so that a client that writes its whole
//! body before it reads the answer still gets the answer rather than a broken
//! connection. A body without a declared length grows its buffer up to the limit and is
//! refused past it.
//!
//! A body of at most [`INLINE_BYTES`] is parsed where it was read. A larger one first
//! waits for a turn ([`Bodies`]: a few at once, one per core), and is read and parsed
//! within it, the parse on a blocking thread. So at most one large body per turn is held
//! in memory at a time, further large requests queue with their bytes still in the
//! connection, and the async workers stay free to answer everything else. (A client that
//! sends a large body slowly holds its turn meanwhile; the request time limit bounds
//! that.)
//!
//! JSON is parsed with axum's own reader ([`axum::Json::from_bytes`]), so answers to
//! malformed bodies are as before; a list refused for its length while it was read
//! (see [`crate::server::dto::bounded`]) is answered 413 `too-large`.

use super::whole_numbers::whole_numbers;
use std::sync::Arc;

use axum::body::Body;
use axum::extract::Request;
use axum::http::header::{CONTENT_LENGTH, CONTENT_TYPE};
use axum::http::{HeaderMap, StatusCode};
use futures_util::StreamExt as _;
use serde::de::DeserializeOwned;
use tokio::sync::{OwnedSemaphorePermit, Semaphore};

use crate::edit::command::bounded::{Exceeded, watch};
use crate::server::problem::Problem;

/// Bodies up to this many bytes are parsed on the async worker that read them; larger
/// ones on a blocking thread, in a turn.
pub const INLINE_BYTES: usize = 256 * 1024;

/// The size limit on request bodies and the turns large bodies take. Installed on the
/// router as an extension; cloning shares the turns.
#[derive(Clone, Debug)]
pub struct Bodies {
    limit: usize,
    turns: Arc<Semaphore>,
}

impl Bodies {
    /// Bodies of at most `limit` bytes, `turns` (at least one) large ones at a time.
    pub fn new(limit: usize, turns: usize) -> Self {
        Bodies {
            limit,
            turns: Arc::new(Semaphore::new(turns.max(1))),
        }
    }

    /// Bodies of at most `limit` bytes, one large one per core at a time.
    pub fn for_this_machine(limit: usize) -> Self {
        let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
        Bodies::new(limit, cores)
    }

    /// The largest body accepted, in bytes.
    pub fn limit(&self) -> usize {
        self.limit
    }

    /// The body gate of the router `req` came through.
    ///
    /// # Errors
    /// 500 when the router has none (a router built without [`super::router`]).
    pub fn of(req: &Request) -> Result<Bodies, Problem> {
        req.extensions()
            .get::<Bodies>()
            .cloned()
            .ok_or_else(|| Problem::internal("the router has no request body gate"))
    }

    /// Reads `req`'s body and runs `parse` on it: inline for a small body, on a blocking
    /// thread in a turn for a large one (see the module's notes).
    ///
    /// # Errors
    /// 413 (`Connection: close`) for a body over the limit, 400 for one that could not be
    /// read, 503 when the server is shutting down; or `parse`'s problem.
    pub async fn parse<R, F>(&self, req: Request, parse: F) -> Result<R, Problem>
    where
        R: Send + 'static,
        F: FnOnce(&[u8]) -> Result<R, Problem> + Send + 'static,
    {
        let declared = declared_length(req.headers());
        let (bytes, turn) = self.read(req.into_body(), declared).await?;
        match turn {
            None => parse(&bytes),
            Some(turn) => tokio::task::spawn_blocking(move || {
                let parsed = parse(&bytes);
                drop(bytes);
                drop(turn);
                parsed
            })
            .await
            .map_err(Problem::internal)?,
        }
    }

    /// The body's bytes, and the turn taken if it is large.
    ///
    /// Postcondition: `bytes.len() <= limit`; a turn is held exactly when the body is (or
    /// was declared) longer than [`INLINE_BYTES`].
    async fn read(
        &self,
        body: Body,
        declared: Option<u64>,
    ) -> Result<(Vec<u8>, Option<OwnedSemaphorePermit>), Problem> {
        let mut turn = None;
        let mut bytes = match declared {
            Some(n) if n > self.limit as u64 => {
                self.drop_up_to_limit(body).await;
                return Err(self.too_large());
            }
            Some(n) => {
                // At most the limit, so it fits a usize.
                let n = n as usize;
                if n > INLINE_BYTES {
                    turn = Some(self.turn().await?);
                }
                Vec::with_capacity(n)
            }
            None => Vec::new(),
        };
        let mut chunks = body.into_data_stream();
        while let Some(chunk) = chunks.next().await {
            let chunk = chunk.map_err(|e| {
                Problem::bad_request(format!("the request body could not be read: {e}"))
            })?;
            let len = bytes.len().saturating_add(chunk.len());
            if len > self.limit {
                return Err(self.too_large());
            }
            if turn.is_none() && len > INLINE_BYTES {
                turn = Some(self.turn().await?);
            }
            bytes.extend_from_slice(&chunk);
        }
        Ok((bytes, turn))
    }

    /// Reads and drops `body` until it ends, fails or `limit` bytes have been read.
    async fn drop_up_to_limit(&self, body: Body) {
        let mut chunks = body.into_data_stream();
        let mut seen = 0usize;
        while seen <= self.limit {
            match chunks.next().await {
                Some(Ok(chunk)) => seen = seen.saturating_add(chunk.len()),
                _ => break,
            }
        }
    }

    /// Waits for a turn to read and parse a large body.
    async fn turn(&self) -> Result<OwnedSemaphorePermit, Problem> {
        self.turns
            .clone()
            .acquire_owned()
            .await
            .map_err(|_| Problem::unavailable())
    }

    /// 413 for a body over the limit, answered without reading the rest of it.
    fn too_large(&self) -> Problem {
        Problem::new(
            StatusCode::PAYLOAD_TOO_LARGE,
            "too-large",
            "Request body too large",
            format!(
                "the request body is larger than {} bytes, the most accepted",
                self.limit
            ),
        )
        .unread()
    }
}

/// The `Content-Length` the request declares, if it declares one that is a number.
fn declared_length(headers: &HeaderMap) -> Option<u64> {
    headers
        .get(CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.trim().parse().ok())
}

/// Whether the request says its body is JSON (`application/json` or `application/*+json`).
pub fn is_json(headers: &HeaderMap) -> bool {
    headers
        .get(CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .map(|v| {
            let essence = v
                .split(';')
                .next()
                .unwrap_or("")
                .trim()
                .to_ascii_lowercase();
            essence == "application/json"
                || (essence.starts_with("application/") && essence.ends_with("+json"))
        })
        .unwrap_or(false)
}

/// 415 for a body that is not declared JSON, answered before it is read.
pub fn not_json() -> Problem {
    Problem::new(
        StatusCode::UNSUPPORTED_MEDIA_TYPE,
        "unsupported-media-type",
        "Unsupported media type",
        "send the body as JSON with Content-Type: application/json",
    )
    .unread()
}

/// 413 for a list refused for its length while it was read.
fn exceeded_problem(e: Exceeded) -> Problem {
    Problem::new(
        StatusCode::PAYLOAD_TOO_LARGE,
        "too-large",
        "Body too large",
        e.to_string(),
    )
}

/// `bytes` parsed as one JSON value of type `T`, whole numbers written `2.0` read as
/// integers (see [`whole_numbers`]).
///
/// # Errors
/// 413 `too-large` when a bounded list in `T` went past its bound; otherwise the problem
/// axum's JSON reader answers (400 for malformed JSON or a value that is no `T`).
pub fn from_json<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, Problem> {
    let bytes = whole_numbers(bytes);
    match watch(|| axum::Json::<T>::from_bytes(&bytes)) {
        (Ok(axum::Json(value)), _) => Ok(value),
        (Err(_), Some(exceeded)) => Err(exceeded_problem(exceeded)),
        (Err(rejection), None) => Err(Problem::from(rejection)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::server::request::CreateBody;

    fn request(content_length: Option<usize>, body: Vec<u8>) -> Request {
        let mut b = axum::http::Request::builder().method("POST").uri("/");
        if let Some(n) = content_length {
            b = b.header(CONTENT_LENGTH, n);
        }
        b.body(Body::from(body)).expect("a request")
    }

    fn read(gate: &Bodies, req: Request) -> Result<(Vec<u8>, bool), Problem> {
        let rt = tokio::runtime::Builder::new_current_thread()
            .build()
            .expect("a runtime");
        rt.block_on(async {
            let declared = declared_length(req.headers());
            let (bytes, turn) = gate.read(req.into_body(), declared).await?;
            Ok((bytes, turn.is_some()))
        })
    }

    #[test]
    fn a_declared_length_over_the_limit_is_refused_unread() {
        let gate = Bodies::new(10, 1);
        let p = read(&gate, request(Some(11), vec![b' '; 11])).expect_err("refused");
        assert_eq!(
            (p.status, p.kind, p.unread),
            (StatusCode::PAYLOAD_TOO_LARGE, "too-large", true)
        );
    }

    #[test]
    fn an_undeclared_length_is_refused_once_past_the_limit() {
        let gate = Bodies::new(10, 1);
        let p = read(&gate, request(None, vec![b' '; 11])).expect_err("refused");
        assert_eq!(p.status, StatusCode::PAYLOAD_TOO_LARGE);
        let (bytes, turn) = read(&gate, request(None, vec![b'x'; 10])).expect("read");
        assert_eq!((bytes.len(), turn), (10, false));
    }

    #[test]
    fn only_a_large_body_takes_a_turn() {
        let gate = Bodies::new(1 << 20, 1);
        let small = read(&gate, request(Some(4), b"null".to_vec())).expect("read");
        assert_eq!(small, (b"null".to_vec(), false));
        let n = INLINE_BYTES + 1;
        let (bytes, turn) = read(&gate, request(Some(n), vec![b' '; n])).expect("read");
        assert_eq!((bytes.len(), turn), (n, true));
        let (_, turn) = read(&gate, request(None, vec![b' '; n])).expect("read");
        assert!(turn);
        // The turns were given back.
        assert_eq!(gate.turns.available_permits(), 1);
    }

    #[test]
    fn too_many_faces_are_too_large_and_bad_json_is_a_bad_request() {
        let mut text = String::from(r#"{"shape":{"type":"polyhedron","vertices":[],"faces":["#);
        for _ in 0..=crate::server::request::MAX_BODY_FACES {
            text.push_str("[],");
        }
        let p = from_json::<CreateBody>(text.as_bytes()).expect_err("refused");
        assert_eq!(
            (p.status, p.kind),
            (StatusCode::PAYLOAD_TOO_LARGE, "too-large")
        );
        assert!(p.detail.contains("faces"), "{}", p.detail);
        let p = from_json::<CreateBody>(b"{\"shape\":").expect_err("refused");
        assert_eq!((p.status, p.kind), (StatusCode::BAD_REQUEST, "bad-request"));
    }
}
