//! Errors as RFC 9457 problem details (`application/problem+json`).

use axum::Json;
use axum::extract::rejection::{JsonRejection, PathRejection, QueryRejection};
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Serialize;

use super::actor::WriteError;
use crate::edit::EditError;
use crate::model::WorldError;

/// A problem answer: HTTP status, a stable type slug, a title and a detail.
#[derive(Debug, Clone)]
pub struct Problem {
    /// HTTP status.
    pub status: StatusCode,
    /// Short machine-readable kind, shown as `type` `urn:winged:problem:<kind>`.
    pub kind: &'static str,
    /// Human-readable summary of the kind.
    pub title: &'static str,
    /// What exactly went wrong.
    pub detail: String,
    /// Seconds after which the client may try again (`Retry-After`), for 503s.
    pub retry_after: Option<u64>,
    /// The world's revision, for answers where it matters (412).
    pub revision: Option<u64>,
    /// Whether the answer comes before the request's body was read: then it is sent with
    /// `Connection: close` (see [`refused_unread`]).
    pub unread: bool,
    /// Extension members (RFC 9457 §3.2) beside the standard ones: where in an uploaded
    /// file a defect is, say.
    pub extra: Option<Box<serde_json::Map<String, serde_json::Value>>>,
}

#[derive(Serialize)]
struct Body<'a> {
    #[serde(rename = "type")]
    kind: String,
    title: &'a str,
    status: u16,
    detail: &'a str,
    #[serde(skip_serializing_if = "Option::is_none")]
    revision: Option<u64>,
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    extra: Option<&'a serde_json::Map<String, serde_json::Value>>,
}

impl Problem {
    /// A problem of the given status and kind.
    pub fn new(
        status: StatusCode,
        kind: &'static str,
        title: &'static str,
        detail: impl Into<String>,
    ) -> Self {
        Problem {
            status,
            kind,
            title,
            detail: detail.into(),
            retry_after: None,
            revision: None,
            unread: false,
            extra: None,
        }
    }

    /// The same problem with the extension member `name` set to `value` (the standard
    /// members `type`, `title`, `status`, `detail` and `revision` are not to be named).
    pub fn with_member(mut self, name: &str, value: serde_json::Value) -> Self {
        self.extra
            .get_or_insert_with(Default::default)
            .insert(name.to_owned(), value);
        self
    }

    /// The same problem, telling the client to retry after `seconds`.
    pub fn retry_after(mut self, seconds: u64) -> Self {
        self.retry_after = Some(seconds);
        self
    }

    /// The same problem, answered before the request's body was read (so with
    /// `Connection: close`).
    pub fn unread(mut self) -> Self {
        self.unread = true;
        self
    }

    /// The same problem, carrying the world's revision.
    pub fn with_revision(mut self, revision: u64) -> Self {
        self.revision = Some(revision);
        self
    }

    /// 503: the server is saturated; try again after `seconds`.
    pub fn busy(detail: impl Into<String>, seconds: u64) -> Self {
        Self::new(
            StatusCode::SERVICE_UNAVAILABLE,
            "overloaded",
            "Server overloaded",
            detail,
        )
        .retry_after(seconds)
    }

    /// 400: the request is not well-formed.
    pub fn bad_request(detail: impl Into<String>) -> Self {
        Self::new(
            StatusCode::BAD_REQUEST,
            "bad-request",
            "Bad request",
            detail,
        )
    }

    /// 500: the server failed (a worker thread panicked, an answer could not be encoded).
    pub fn internal(detail: impl std::fmt::Display) -> Self {
        Self::new(
            StatusCode::INTERNAL_SERVER_ERROR,
            "internal",
            "Internal error",
            detail.to_string(),
        )
    }

    /// 404: no such resource.
    pub fn not_found(detail: impl Into<String>) -> Self {
        Self::new(StatusCode::NOT_FOUND, "not-found", "Not found", detail)
    }

    /// 503: the world's owner is gone (shutting down).
    pub fn unavailable() -> Self {
        Self::new(
            StatusCode::SERVICE_UNAVAILABLE,
            "unavailable",
            "Service unavailable",
            "the world is shutting down",
        )
        .retry_after(5)
    }
}

impl Problem {
    /// The JSON body sent with content type `application/problem+json`.
    fn body(&self) -> Body<'_> {
        Body {
            kind: format!("urn:winged:problem:{}", self.kind),
            title: self.title,
            status: self.status.as_u16(),
            detail: &self.detail,
            revision: self.revision,
            extra: self.extra.as_deref(),
        }
    }

    /// The JSON body as bytes, for answers written outside axum (the connection layer's
    /// own refusals, see [`super::listen`]).
    ///
    /// Postcondition: a JSON object with `type`, `title`, `status` and `detail` (and
    /// `revision` when set), the same as the body of [`IntoResponse::into_response`].
    pub fn to_json(&self) -> Vec<u8> {
        // A struct of strings and integers always serializes; the empty fallback is never
        // taken.
        serde_json::to_vec(&self.body()).unwrap_or_default()
    }
}

impl IntoResponse for Problem {
    fn into_response(self) -> Response {
        let mut res = (self.status, Json(self.body())).into_response();
        res.headers_mut().insert(
            header::CONTENT_TYPE,
            HeaderValue::from_static("application/problem+json"),
        );
        if let Some(s) = self.retry_after {
            res.headers_mut()
                .insert(header::RETRY_AFTER, HeaderValue::from(s));
        }
        if self.unread {
            res = refused_unread(res);
        }
        res
    }
}

impl From<JsonRejection> for Problem {
    fn from(r: JsonRejection) -> Self {
        match r {
            JsonRejection::BytesRejection(_) if r.status() == StatusCode::PAYLOAD_TOO_LARGE => {
                Problem::new(
                    StatusCode::PAYLOAD_TOO_LARGE,
                    "too-large",
                    "Request body too large",
                    r.body_text(),
                )
                .unread()
            }
            JsonRejection::MissingJsonContentType(_) => Problem::new(
                StatusCode::UNSUPPORTED_MEDIA_TYPE,
                "unsupported-media-type",
                "Unsupported media type",
                "send the body as JSON with Content-Type: application/json",
            )
            .unread(),
            _ => Problem::bad_request(r.body_text()),
        }
    }
}

impl From<PathRejection> for Problem {
    fn from(r: PathRejection) -> Self {
        Problem::bad_request(r.body_text())
    }
}

impl From<QueryRejection> for Problem {
    fn from(r: QueryRejection) -> Self {
        Problem::bad_request(r.body_text())
    }
}

/// 422 `invalid-name`: a name that breaks the naming rules (see
/// [`crate::model::parts::validate_name`]).
pub fn invalid_name(detail: impl Into<String>) -> Problem {
    unprocessable("invalid-name", "Invalid name", detail.into())
}

/// 422 `out-of-range`: the write would take the world outside its range.
fn out_of_range(detail: String) -> Problem {
    unprocessable("out-of-range", "Outside the world's range", detail)
}

impl From<EditError> for Problem {
    fn from(e: EditError) -> Self {
        let detail = e.to_string();
        if e.is_out_of_range() {
            return out_of_range(detail);
        }
        match e {
            EditError::World(w) => world_problem(w, detail),
            EditError::Unknown { .. } | EditError::NotInBody { .. } => Problem::not_found(detail),
            EditError::TooLarge { .. } => too_large(detail),
            EditError::Solid(_) => unprocessable("invalid-solid", "Invalid solid", detail),
            EditError::Camera(_) => unprocessable("invalid-camera", "Invalid camera", detail),
            EditError::Light(_) => unprocessable("invalid-light", "Invalid light", detail),
            EditError::BadNumber(_) => Problem::bad_request(detail),
        }
    }
}

/// 413 `too-large`: the body a write would make has too many faces.
fn too_large(detail: String) -> Problem {
    Problem::new(
        StatusCode::PAYLOAD_TOO_LARGE,
        "too-large",
        "Body too large",
        detail,
    )
}

fn unprocessable(kind: &'static str, title: &'static str, detail: String) -> Problem {
    Problem::new(StatusCode::UNPROCESSABLE_ENTITY, kind, title, detail)
}

fn world_problem(w: WorldError, detail: String) -> Problem {
    match w {
        WorldError::UnknownBody(_)
        | WorldError::UnknownEntity(_)
        | WorldError::UnknownCamera(_)
        | WorldError::UnknownLight(_) => Problem::not_found(detail),
        WorldError::Euler(_) => unprocessable("euler-refused", "Euler operator refused", detail),
        WorldError::Transform(_) => unprocessable("invalid-transform", "Invalid transform", detail),
        WorldError::Build(_) | WorldError::Solid(_) | WorldError::InvalidBody(_) => {
            unprocessable("invalid-solid", "Invalid solid", detail)
        }
        WorldError::Camera(_) => unprocessable("invalid-camera", "Invalid camera", detail),
        WorldError::Light(_) => unprocessable("invalid-light", "Invalid light", detail),
        WorldError::DuplicateName { .. } => {
            Problem::new(StatusCode::CONFLICT, "name-taken", "Name taken", detail)
        }
        WorldError::Cycle { .. } | WorldError::Root { .. } => {
            unprocessable("invalid-parts-tree", "Invalid parts-tree change", detail)
        }
        WorldError::BadName { .. } => invalid_name(detail),
        WorldError::Pose(_) => unprocessable("invalid-pose", "Invalid pose", detail),
        WorldError::NonFinite { .. } => Problem::bad_request(detail),
        WorldError::OutOfRange(_) | WorldError::Placement { .. } => out_of_range(detail),
        WorldError::Entangled(_) | WorldError::Boolean { .. } => {
            unprocessable("boolean-refused", "Boolean refused", detail)
        }
        WorldError::TooLarge { .. } => too_large(detail),
        WorldError::BooleanFailed(_) => Problem::internal(detail),
        WorldError::NotProvisional(_) => {
            unprocessable("not-provisional", "Body not provisional", detail)
        }
    }
}

impl From<WriteError> for Problem {
    fn from(e: WriteError) -> Self {
        let detail = e.to_string();
        match e {
            WriteError::Refused(e) => e.into(),
            WriteError::Conflict { actual, .. } => Problem::new(
                StatusCode::PRECONDITION_FAILED,
                "revision-moved",
                "The world has moved on",
                detail,
            )
            .with_revision(actual),
            WriteError::Storage(_) => Problem::new(
                StatusCode::SERVICE_UNAVAILABLE,
                "storage-failed",
                "Storage failed",
                detail,
            )
            .retry_after(5),
            WriteError::Busy(_) => Problem::busy(detail, 1),
            WriteError::Stopped => Problem::unavailable(),
        }
    }
}

/// `res`, an answer given before the request's body was read, marked
/// `Connection: close`: the server will not read the rest of that body, so the
/// connection cannot carry another request and the client must not reuse it.
pub fn refused_unread(mut res: Response) -> Response {
    res.headers_mut()
        .insert(header::CONNECTION, HeaderValue::from_static("close"));
    res
}
