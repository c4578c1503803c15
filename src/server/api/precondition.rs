//! Write preconditions: "apply this only if the world is still at revision N".
//!
//! A client gives the revision it last saw either as `If-Match: "N"` (the `ETag` every
//! read answers with) or as `expected_revision: N` in a JSON body. The world's owner
//! checks it atomically with the write and answers 412 when the world has moved on.

use axum::Json;
use axum::body::Bytes;
use axum::extract::{FromRequest, FromRequestParts, Request};
use axum::http::header::{CONTENT_TYPE, IF_MATCH};
use axum::http::request::Parts;
use axum::http::{HeaderMap, HeaderValue, StatusCode};
use serde::de::DeserializeOwned;

use crate::server::problem::Problem;

/// The body field that carries a precondition.
pub const FIELD: &str = "expected_revision";

/// The `ETag` header value for revision `r`.
pub fn etag(r: u64) -> HeaderValue {
    HeaderValue::from_str(&format!("\"{r}\"")).unwrap_or(HeaderValue::from_static("\"0\""))
}

/// The revision named by an `If-Match` header, if any. `*` (any revision) is no
/// precondition.
#[derive(Debug, Clone, Copy, Default)]
pub struct IfMatch(pub Option<u64>);

impl IfMatch {
    /// Parses the header from `headers`.
    ///
    /// Accepts `"N"`, `W/"N"` and a bare `N`; refuses a list or anything else with 400.
    pub fn from_headers(headers: &HeaderMap) -> Result<Self, Problem> {
        let Some(v) = headers.get(IF_MATCH) else {
            return Ok(IfMatch(None));
        };
        let text = v
            .to_str()
            .map_err(|_| Problem::bad_request("If-Match is not text"))?
            .trim();
        if text == "*" {
            return Ok(IfMatch(None));
        }
        let bare = text.strip_prefix("W/").unwrap_or(text);
        let bare = bare
            .strip_prefix('"')
            .and_then(|t| t.strip_suffix('"'))
            .unwrap_or(bare);
        bare.parse::<u64>().map(|r| IfMatch(Some(r))).map_err(|_| {
            Problem::bad_request(format!(
                "If-Match must be one revision as an entity tag, like \"42\"; got {text:?}"
            ))
        })
    }
}

impl<S: Send + Sync> FromRequestParts<S> for IfMatch {
    type Rejection = Problem;
    async fn from_request_parts(parts: &mut Parts, _: &S) -> Result<Self, Self::Rejection> {
        IfMatch::from_headers(&parts.headers)
    }
}

/// A JSON write body of type `T`, with the precondition from `If-Match` or from an
/// `expected_revision` field (removed before `T` is read, so `T` may refuse unknown
/// fields).
#[derive(Debug)]
pub struct WriteJson<T> {
    /// The request.
    pub value: T,
    /// The revision the write expects, if any.
    pub expected: Option<u64>,
}

impl<S, T> FromRequest<S> for WriteJson<T>
where
    S: Send + Sync,
    T: DeserializeOwned,
{
    type Rejection = Problem;

    async fn from_request(req: Request, state: &S) -> Result<Self, Self::Rejection> {
        // Refused before the body is read: the connection cannot be reused.
        let IfMatch(header) = IfMatch::from_headers(req.headers()).map_err(Problem::unread)?;
        if !is_json(req.headers()) {
            return Err(Problem::new(
                StatusCode::UNSUPPORTED_MEDIA_TYPE,
                "unsupported-media-type",
                "Unsupported media type",
                "send the body as JSON with Content-Type: application/json",
            )
            .unread());
        }
        let bytes = Bytes::from_request(req, state)
            .await
            .map_err(body_problem)?;
        // Most writes carry no precondition field: read them straight into `T`.
        let mentions_field = memchr::memmem::find(&bytes, FIELD.as_bytes()).is_some();
        let (value, field) = if mentions_field {
            let Json(mut v) = Json::<serde_json::Value>::from_bytes(&bytes)?;
            let field = match v.as_object_mut().and_then(|o| o.remove(FIELD)) {
                None => None,
                Some(f) => Some(f.as_u64().ok_or_else(|| {
                    Problem::bad_request(format!("{FIELD} must be a revision number"))
                })?),
            };
            let value = serde_json::from_value(v).map_err(|e| {
                Problem::bad_request(format!(
                    "Failed to deserialize the JSON body into the target type: {e}"
                ))
            })?;
            (value, field)
        } else {
            let Json(value) = Json::<T>::from_bytes(&bytes)?;
            (value, None)
        };
        let expected = match (header, field) {
            (Some(h), Some(f)) if h != f => {
                return Err(Problem::bad_request(format!(
                    "If-Match names revision {h} but {FIELD} is {f}"
                )));
            }
            (h, f) => h.or(f),
        };
        Ok(WriteJson { value, expected })
    }
}

/// Whether the request says its body is JSON (`application/json` or `application/*+json`).
fn is_json(headers: &HeaderMap) -> bool {
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

/// A request body a route does not use, read and dropped so the connection can carry
/// the next request (an unread body would make the server close it).
#[derive(Debug)]
pub struct Unused;

impl<S: Send + Sync> FromRequest<S> for Unused {
    type Rejection = Problem;

    async fn from_request(req: Request, state: &S) -> Result<Self, Self::Rejection> {
        Bytes::from_request(req, state)
            .await
            .map(|_| Unused)
            .map_err(body_problem)
    }
}

/// A body that could not be read: 413 when over the limit, else 400.
fn body_problem(r: axum::extract::rejection::BytesRejection) -> Problem {
    if r.status() == StatusCode::PAYLOAD_TOO_LARGE {
        Problem::new(
            StatusCode::PAYLOAD_TOO_LARGE,
            "too-large",
            "Request body too large",
            r.body_text(),
        )
        .unread()
    } else {
        Problem::bad_request(r.body_text())
    }
}
