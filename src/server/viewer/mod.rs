//! The browser viewer: a page at `GET /` and its files at `GET /viewer/{file}`, built
//! into the binary.
//!
//! The page is plain HTML, CSS and ES modules (no build step). It is not part of the API:
//! it needs no token to load (like `/healthz`), and everything it shows it reads through
//! the API with the token the user gives it, so a read token is enough to use it.
//!
//! Every answer carries a strong `ETag` (a digest of the file) and
//! `Cache-Control: no-cache`: browsers keep the files and revalidate them, getting
//! `304 Not Modified` until a new binary serves different bytes. The files are served
//! with a content security policy that allows only this origin's scripts, styles and
//! connections.

use std::sync::OnceLock;

use axum::extract::Path;
use axum::http::header::{
    CACHE_CONTROL, CONTENT_SECURITY_POLICY, CONTENT_TYPE, ETAG, IF_NONE_MATCH,
    X_CONTENT_TYPE_OPTIONS,
};
use axum::http::{HeaderMap, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Response};
use sha2::{Digest, Sha256};

use super::problem::Problem;

/// One file of the viewer.
struct Asset {
    /// Its name under `/viewer/`.
    name: &'static str,
    /// Its media type.
    content_type: &'static str,
    /// Its bytes.
    body: &'static [u8],
}

/// The page itself, served at `/` (and at `/viewer/index.html`).
const INDEX: &str = "index.html";

/// Declares the viewer's files: each is embedded from this directory.
macro_rules! assets {
    ($($name:literal => $type:literal),* $(,)?) => {
        &[$(Asset { name: $name, content_type: $type, body: include_bytes!($name) }),*]
    };
}

/// Every file the viewer is made of.
const ASSETS: &[Asset] = assets! {
    "index.html" => "text/html; charset=utf-8",
    "viewer.css" => "text/css; charset=utf-8",
    "main.js" => "text/javascript; charset=utf-8",
    "api.js" => "text/javascript; charset=utf-8",
    "camera.js" => "text/javascript; charset=utf-8",
    "orbit.js" => "text/javascript; charset=utf-8",
    "frames.js" => "text/javascript; charset=utf-8",
    "png16.js" => "text/javascript; charset=utf-8",
    "picture.js" => "text/javascript; charset=utf-8",
    "picking.js" => "text/javascript; charset=utf-8",
    "events.js" => "text/javascript; charset=utf-8",
    "panels.js" => "text/javascript; charset=utf-8",
    "spatial.js" => "text/javascript; charset=utf-8",
    "overlay.js" => "text/javascript; charset=utf-8",
    "status.js" => "text/javascript; charset=utf-8",
};

/// What the page may load and connect to: this origin only (images also as blobs and
/// data URLs, which the page makes itself).
const POLICY: &str = "default-src 'none'; script-src 'self'; style-src 'self'; \
     img-src 'self' blob: data:; connect-src 'self'; base-uri 'none'; form-action 'none'; \
     frame-ancestors 'none'";

/// `GET /`: the viewer's page.
pub async fn index(headers: HeaderMap) -> Response {
    match find(INDEX) {
        Some(i) => answer(i, &headers),
        None => Problem::internal("the viewer's page is missing from this build").into_response(),
    }
}

/// `GET /viewer/{file}`: one of the viewer's files; 404 for any other name.
pub async fn asset(Path(file): Path<String>, headers: HeaderMap) -> Response {
    match find(&file) {
        Some(i) => answer(i, &headers),
        None => Problem::not_found(format!("the viewer has no file {file:?}")).into_response(),
    }
}

/// The index of the asset called `name`.
fn find(name: &str) -> Option<usize> {
    ASSETS.iter().position(|a| a.name == name)
}

/// The strong entity tag of each asset, computed once: the first 16 bytes of its
/// SHA-256, in hex and quoted.
fn etags() -> &'static [HeaderValue] {
    static TAGS: OnceLock<Vec<HeaderValue>> = OnceLock::new();
    TAGS.get_or_init(|| {
        ASSETS
            .iter()
            .map(|a| {
                let digest = Sha256::digest(a.body);
                let hex: String = digest[..16].iter().map(|b| format!("{b:02x}")).collect();
                HeaderValue::from_str(&format!("\"{hex}\""))
                    .unwrap_or_else(|_| HeaderValue::from_static("\"0\""))
            })
            .collect()
    })
}

/// Whether an `If-None-Match` header names `tag` (or is `*`).
fn matches(headers: &HeaderMap, tag: &HeaderValue) -> bool {
    let Some(tag) = tag.to_str().ok() else {
        return false;
    };
    headers
        .get_all(IF_NONE_MATCH)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(','))
        .map(|t| t.trim().trim_start_matches("W/"))
        .any(|t| t == tag || t == "*")
}

/// The answer for asset `i`: its bytes, or `304 Not Modified` when the client holds them.
fn answer(i: usize, headers: &HeaderMap) -> Response {
    let asset = &ASSETS[i];
    let tag = etags()[i].clone();
    let common = [
        (ETAG, tag.clone()),
        (CACHE_CONTROL, HeaderValue::from_static("no-cache")),
        (X_CONTENT_TYPE_OPTIONS, HeaderValue::from_static("nosniff")),
        (CONTENT_SECURITY_POLICY, HeaderValue::from_static(POLICY)),
    ];
    if matches(headers, &tag) {
        return (StatusCode::NOT_MODIFIED, common).into_response();
    }
    (
        common,
        [(CONTENT_TYPE, HeaderValue::from_static(asset.content_type))],
        asset.body,
    )
        .into_response()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::World;
    use crate::server::background::Background;
    use crate::server::{Limits, in_memory};

    /// Status, content type, ETag and body of `GET path` (with `If-None-Match` when given).
    fn get(
        agent: &ureq::Agent,
        url: &str,
        if_none_match: Option<&str>,
    ) -> (u16, String, String, String) {
        let mut req = axum::http::Request::builder().uri(url);
        if let Some(tag) = if_none_match {
            req = req.header("if-none-match", tag);
        }
        let mut res = agent.run(req.body(()).unwrap()).unwrap();
        let header = |name: &str| {
            res.headers()
                .get(name)
                .map(|v| v.to_str().unwrap().to_string())
                .unwrap_or_default()
        };
        let (ct, tag) = (header("content-type"), header("etag"));
        let body = res.body_mut().read_to_string().unwrap_or_default();
        (res.status().as_u16(), ct, tag, body)
    }

    #[test]
    fn the_page_and_every_file_are_served_through_the_real_router() {
        let server = Background::start("127.0.0.1:0".parse().unwrap(), || {
            in_memory(World::new(), Limits::default())
        })
        .unwrap();
        let base = server.base();
        let agent: ureq::Agent = ureq::Agent::config_builder()
            .http_status_as_error(false)
            .build()
            .into();

        let (status, ct, tag, body) = get(&agent, &format!("{base}/"), None);
        assert_eq!(status, 200);
        assert_eq!(ct, "text/html; charset=utf-8");
        assert!(body.contains("<!doctype html>"), "{body}");
        assert!(body.contains("main.js"), "the page loads its module");
        assert!(tag.starts_with('"') && tag.len() == 34, "{tag}");
        let (status, _, _, body) = get(&agent, &format!("{base}/"), Some(&tag));
        assert_eq!((status, body.as_str()), (304, ""));

        for asset in ASSETS {
            let (status, ct, _, body) = get(&agent, &format!("{base}/viewer/{}", asset.name), None);
            assert_eq!(status, 200, "{}", asset.name);
            assert_eq!(ct, asset.content_type, "{}", asset.name);
            assert_eq!(body.as_bytes(), asset.body, "{}", asset.name);
        }
        let (status, ct, _, _) = get(&agent, &format!("{base}/viewer/nothing.js"), None);
        assert_eq!((status, ct.as_str()), (404, "application/problem+json"));
        drop(agent);
        server.stop().unwrap();
    }

    #[test]
    fn every_module_the_page_imports_is_served() {
        for asset in ASSETS.iter().filter(|a| a.name.ends_with(".js")) {
            let text = std::str::from_utf8(asset.body).unwrap();
            for line in text
                .lines()
                .filter(|l| l.trim_start().starts_with("import "))
            {
                let Some(start) = line.find("\"./") else {
                    continue;
                };
                let rest = &line[start + 3..];
                let name = &rest[..rest.find('"').unwrap()];
                assert!(find(name).is_some(), "{} imports {name}", asset.name);
            }
        }
    }

    #[test]
    fn every_file_beside_this_module_is_served() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/server/viewer");
        for entry in std::fs::read_dir(&dir).unwrap() {
            let name = entry.unwrap().file_name().into_string().unwrap();
            if name != "mod.rs" {
                assert!(find(&name).is_some(), "{name} is not in ASSETS");
            }
        }
    }

    #[test]
    fn if_none_match_lists_and_wildcards_are_understood() {
        let tag = HeaderValue::from_static("\"abc\"");
        let mut h = HeaderMap::new();
        assert!(!matches(&h, &tag));
        h.insert(IF_NONE_MATCH, HeaderValue::from_static("\"x\", W/\"abc\""));
        assert!(matches(&h, &tag));
        h.insert(IF_NONE_MATCH, HeaderValue::from_static("*"));
        assert!(matches(&h, &tag));
        h.insert(IF_NONE_MATCH, HeaderValue::from_static("\"abcd\""));
        assert!(!matches(&h, &tag));
    }
}
