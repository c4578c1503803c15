//! Routes for following the world: the changes after a revision, and the live stream.

use std::sync::Arc;

use axum::extract::rejection::QueryRejection;
use axum::extract::{FromRequestParts, Query, State};
use axum::http::HeaderMap;
use axum::http::request::Parts;
use axum::response::sse::{KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use serde::Deserialize;

use super::extract::ApiQuery;
use super::{Answer, read_answer};
use crate::server::dto::ChangesPage;
use crate::server::events::{Feed, Since};
use crate::server::problem::Problem;

/// The most changes one answer carries by default, and at most.
const DEFAULT_LIMIT: usize = 1000;
const MAX_LIMIT: usize = 10_000;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ChangesQuery {
    since: u64,
    limit: Option<usize>,
}

/// The query read as [`ApiQuery`] reads it, with the route's form added to the 400
/// detail.
impl<S: Send + Sync> FromRequestParts<S> for ChangesQuery {
    type Rejection = Problem;

    async fn from_request_parts(parts: &mut Parts, state: &S) -> Result<Self, Problem> {
        Query::from_request_parts(parts, state)
            .await
            .map(|Query(q)| q)
            .map_err(|r: QueryRejection| {
                Problem::bad_request(format!(
                    "{}; ask as /v1/world/changes?since=REVISION[&limit=N]",
                    r.body_text()
                ))
            })
    }
}

/// `GET /v1/world/changes?since=N[&limit=L]`: every change after revision N, oldest
/// first, or `resync: true` when N is older than the history kept.
pub(super) async fn changes(State(feed): State<Arc<Feed>>, q: ChangesQuery) -> Answer {
    let limit = q.limit.unwrap_or(DEFAULT_LIMIT).clamp(1, MAX_LIMIT);
    Ok(match feed.since(q.since, limit) {
        Since::Changes {
            changes,
            more,
            revision,
        } => read_answer(
            revision,
            ChangesPage {
                since: q.since,
                revision,
                resync: false,
                oldest: None,
                more,
                changes,
            },
        ),
        Since::Resync { revision, oldest } => read_answer(
            revision,
            ChangesPage {
                since: q.since,
                revision,
                resync: true,
                oldest: Some(oldest),
                more: false,
                changes: Vec::new(),
            },
        ),
    })
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct EventsQuery {
    since: Option<u64>,
}

/// `GET /v1/world/events`: Server-Sent Events, one `change` event per write (its `id` is
/// the revision), from after `Last-Event-ID` (or `?since=N`, or now) on.
pub(super) async fn events(
    State(feed): State<Arc<Feed>>,
    headers: HeaderMap,
    ApiQuery(q): ApiQuery<EventsQuery>,
) -> Result<Response, Problem> {
    let last_event = match headers.get("last-event-id") {
        None => None,
        Some(v) => Some(
            v.to_str()
                .ok()
                .and_then(|t| t.trim().parse::<u64>().ok())
                .ok_or_else(|| Problem::bad_request("Last-Event-ID must be a revision number"))?,
        ),
    };
    let last = last_event.or(q.since).unwrap_or_else(|| feed.revision());
    Ok(Sse::new(feed.stream(last))
        .keep_alive(KeepAlive::default())
        .into_response())
}
