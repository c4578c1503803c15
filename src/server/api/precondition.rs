//! Write preconditions: "apply this only if the world is still at revision N".
//!
//! A client gives the revision it last saw either as `If-Match: "N"` (the `ETag` every
//! read answers with) or as `expected_revision: N` in a JSON body. The world's owner
//! checks it atomically with the write and answers 412 when the world has moved on.

use std::fmt;
use std::marker::PhantomData;

use axum::body::Bytes;
use axum::extract::{FromRequest, FromRequestParts, Request};
use axum::http::header::IF_MATCH;
use axum::http::request::Parts;
use axum::http::{HeaderMap, HeaderValue, StatusCode};
use serde::Deserialize;
use serde::de::value::MapAccessDeserializer;
use serde::de::{
    self, DeserializeOwned, DeserializeSeed, Deserializer, IntoDeserializer, MapAccess, Visitor,
};

use super::body::{Bodies, from_json, is_json, not_json};
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
/// `expected_revision` field (taken out of the object as it is read, so `T` may refuse
/// unknown fields). The body is read and parsed as [`super::body`] describes.
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
    T: DeserializeOwned + Send + 'static,
{
    type Rejection = Problem;

    async fn from_request(req: Request, _: &S) -> Result<Self, Self::Rejection> {
        // Refused before the body is read: the connection cannot be reused.
        let IfMatch(header) = IfMatch::from_headers(req.headers()).map_err(Problem::unread)?;
        if !is_json(req.headers()) {
            return Err(not_json());
        }
        let (value, field) = Bodies::of(&req)?.parse(req, read_write::<T>).await?;
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

/// A write body: `T` and the `expected_revision` field, if given.
pub(super) fn read_write<T: DeserializeOwned>(bytes: &[u8]) -> Result<(T, Option<u64>), Problem> {
    // Most writes carry no precondition field: read them straight into `T`.
    if memchr::memmem::find(bytes, FIELD.as_bytes()).is_some() {
        from_json::<WithRevision<T>>(bytes).map(|w| (w.value, w.revision))
    } else {
        from_json::<T>(bytes).map(|v| (v, None))
    }
}

/// A JSON object read as `T` without its `expected_revision` field, and that field.
struct WithRevision<T> {
    value: T,
    revision: Option<u64>,
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for WithRevision<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_map(WithRevisionVisitor(PhantomData))
    }
}

struct WithRevisionVisitor<T>(PhantomData<T>);

impl<'de, T: Deserialize<'de>> Visitor<'de> for WithRevisionVisitor<T> {
    type Value = WithRevision<T>;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a JSON object")
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<WithRevision<T>, A::Error> {
        let mut revision = None;
        let value = T::deserialize(MapAccessDeserializer::new(WithoutRevision {
            inner: map,
            revision: &mut revision,
        }))?;
        Ok(WithRevision { value, revision })
    }
}

/// The entries of a map but `expected_revision`, whose value goes to `revision`.
struct WithoutRevision<'a, A> {
    inner: A,
    revision: &'a mut Option<u64>,
}

impl<'de, A: MapAccess<'de>> MapAccess<'de> for WithoutRevision<'_, A> {
    type Error = A::Error;

    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, A::Error> {
        while let Some(key) = self.inner.next_key::<String>()? {
            if key != FIELD {
                return seed.deserialize(key.into_deserializer()).map(Some);
            }
            if self.revision.is_some() {
                return Err(de::Error::duplicate_field(FIELD));
            }
            *self.revision = Some(self.inner.next_value_seed(Revision)?);
        }
        Ok(None)
    }

    fn next_value_seed<V: DeserializeSeed<'de>>(&mut self, seed: V) -> Result<V::Value, A::Error> {
        self.inner.next_value_seed(seed)
    }

    fn size_hint(&self) -> Option<usize> {
        self.inner.size_hint()
    }
}

/// A revision number.
struct Revision;

impl<'de> DeserializeSeed<'de> for Revision {
    type Value = u64;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<u64, D::Error> {
        d.deserialize_u64(self)
    }
}

impl Visitor<'_> for Revision {
    type Value = u64;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{FIELD} to be a revision number")
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<u64, E> {
        Ok(v)
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::server::request::{EulerOp, PatchBody, TransformReq};

    #[test]
    fn the_revision_field_is_taken_out_wherever_it_is() {
        let (p, r) =
            read_write::<PatchBody>(br#"{"name": "a", "expected_revision": 7}"#).expect("read");
        assert_eq!((p.name, r), (Some(Some("a".into())), Some(7)));
        let (op, r) =
            read_write::<EulerOp>(br#"{"expected_revision": 3, "op": "klfe", "edge": 9}"#)
                .expect("read");
        assert_eq!((op, r), (EulerOp::Klfe { edge: 9 }, Some(3)));
        let (t, r) = read_write::<TransformReq>(
            br#"{"op": "translate", "expected_revision": 2, "vector": [1, 0, 0]}"#,
        )
        .expect("read");
        assert_eq!((t.target, r), (None, Some(2)));
        // A name that mentions the field is no precondition.
        let (p, r) = read_write::<PatchBody>(br#"{"name": "expected_revision"}"#).expect("read");
        assert_eq!((p.name, r), (Some(Some("expected_revision".into())), None));
    }

    #[test]
    fn a_bad_or_repeated_revision_is_a_bad_request() {
        for text in [
            r#"{"expected_revision": "latest"}"#,
            r#"{"expected_revision": -1}"#,
            r#"{"expected_revision": null}"#,
            r#"{"expected_revision": 1, "expected_revision": 1}"#,
            r#"{"expected_revision": 1, "nmae": "x"}"#,
            r#"[1, "expected_revision"]"#,
        ] {
            let p = read_write::<PatchBody>(text.as_bytes()).expect_err(text);
            assert_eq!(p.status, StatusCode::BAD_REQUEST, "{text}");
        }
    }
}
