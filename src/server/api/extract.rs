//! The extractors handlers take their arguments with: axum's path and query extractors
//! and a JSON body reader, each refusing with a [`Problem`] rather than axum's own
//! plain-text rejection.
//!
//! A handler names what it needs directly (`ApiPath(id): ApiPath<u64>`,
//! `ApiQuery(q): ApiQuery<ListQuery>`, `ApiJson(req): ApiJson<SolveReq>`); a request that
//! does not fit is answered with the problem before the handler runs. The problems are
//! the ones [`Problem`]'s conversions from axum's rejections give: 400 `bad-request`
//! with axum's description of what did not parse.

use axum::extract::{FromRequest, FromRequestParts, OptionalFromRequest, Path, Query, Request};
use axum::http::header::CONTENT_TYPE;
use serde::de::DeserializeOwned;

use super::body::{Bodies, from_json, is_json, not_json};
use crate::server::problem::Problem;

/// The path parameters of the route, as `T`; 400 when they do not parse as `T`.
#[derive(Debug, FromRequestParts)]
#[from_request(via(Path), rejection(Problem))]
pub struct ApiPath<T>(pub T);

/// The query string, as `T`; 400 when it does not parse as `T`.
#[derive(Debug, FromRequestParts)]
#[from_request(via(Query), rejection(Problem))]
pub struct ApiQuery<T>(pub T);

/// A JSON request body of type `T`, read within the size limit and parsed as
/// [`super::body`] describes.
///
/// Refused with 415 when the body is not declared JSON, 413 when it is too large and 400
/// when it is no `T`. As `Option<ApiJson<T>>` the body is optional: a request without a
/// `Content-Type` has none.
#[derive(Debug)]
pub struct ApiJson<T>(pub T);

impl<S, T> FromRequest<S> for ApiJson<T>
where
    S: Send + Sync,
    T: DeserializeOwned + Send + 'static,
{
    type Rejection = Problem;

    async fn from_request(req: Request, _: &S) -> Result<Self, Problem> {
        if !is_json(req.headers()) {
            return Err(not_json());
        }
        Bodies::of(&req)?
            .parse(req, |bytes| from_json(bytes).map(ApiJson))
            .await
    }
}

impl<S, T> OptionalFromRequest<S> for ApiJson<T>
where
    S: Send + Sync,
    T: DeserializeOwned + Send + 'static,
{
    type Rejection = Problem;

    async fn from_request(req: Request, state: &S) -> Result<Option<Self>, Problem> {
        if req.headers().contains_key(CONTENT_TYPE) {
            <Self as FromRequest<S>>::from_request(req, state)
                .await
                .map(Some)
        } else {
            Ok(None)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use axum::body::Body;
    use axum::http::StatusCode;
    use serde::Deserialize;

    #[derive(Debug, Deserialize)]
    struct Named {
        name: Option<String>,
    }

    fn request(uri: &str, content_type: Option<&str>, body: &str) -> Request {
        let mut b = axum::http::Request::builder().method("POST").uri(uri);
        if let Some(t) = content_type {
            b = b.header(CONTENT_TYPE, t);
        }
        let mut req = b.body(Body::from(body.to_owned())).expect("a request");
        req.extensions_mut().insert(Bodies::new(1024, 1));
        req
    }

    fn run<T>(f: impl Future<Output = T>) -> T {
        tokio::runtime::Builder::new_current_thread()
            .build()
            .expect("a runtime")
            .block_on(f)
    }

    #[derive(Debug, Deserialize)]
    struct Since {
        since: u64,
    }

    #[test]
    fn a_query_that_does_not_parse_is_a_bad_request() {
        let (mut parts, _) = request("/?since=7", None, "").into_parts();
        let ApiQuery(q) =
            run(ApiQuery::<Since>::from_request_parts(&mut parts, &())).expect("a query");
        assert_eq!(q.since, 7);
        let (mut parts, _) = request("/?since=x", None, "").into_parts();
        let p = run(ApiQuery::<Since>::from_request_parts(&mut parts, &())).expect_err("refused");
        assert_eq!((p.status, p.kind), (StatusCode::BAD_REQUEST, "bad-request"));
        assert!(p.detail.contains("since"), "{}", p.detail);
    }

    #[test]
    fn an_optional_body_is_none_without_a_content_type() {
        let none = run(<Option<ApiJson<Named>>>::from_request(
            request("/", None, ""),
            &(),
        ))
        .expect("no body");
        assert!(none.is_none());
        let some = run(<Option<ApiJson<Named>>>::from_request(
            request("/", Some("application/json"), r#"{"name": "twin"}"#),
            &(),
        ))
        .expect("a body");
        assert_eq!(some.and_then(|ApiJson(n)| n.name).as_deref(), Some("twin"));
        let p = run(<Option<ApiJson<Named>>>::from_request(
            request("/", Some("text/plain"), "twin"),
            &(),
        ))
        .expect_err("not JSON");
        assert_eq!(p.status, StatusCode::UNSUPPORTED_MEDIA_TYPE);
        let p = run(<Option<ApiJson<Named>>>::from_request(
            request("/", Some("application/json"), "{"),
            &(),
        ))
        .expect_err("malformed");
        assert_eq!(p.status, StatusCode::BAD_REQUEST);
    }
}
