//! A real server on an ephemeral port, and a plain HTTP client for it.

use std::time::Duration;

use winged::model::World;
use winged::server::background::Background;

/// A server on `127.0.0.1:0` over a fresh data directory, in a thread with its own
/// runtime; shut down (gracefully) when dropped.
pub struct TestServer {
    /// `http://127.0.0.1:PORT`.
    pub base: String,
    _server: Background,
    /// The server's data directory (a real journal and snapshots).
    _data: tempfile::TempDir,
}

impl TestServer {
    /// Serves `world`.
    pub fn start(world: World) -> TestServer {
        let dir = tempfile::tempdir().expect("a temporary directory");
        let data = dir.path().join("world");
        let server = Background::start("127.0.0.1:0".parse().expect("an address"), move || {
            let opened = winged::server::durable::open(
                &data,
                winged::store::StoreOptions::default(),
                winged::server::durable::SnapshotPolicy::default(),
                100_000,
                std::sync::Arc::new(winged::server::metrics::Metrics::new()),
                || Some(world),
            )
            .map_err(std::io::Error::other)?;
            winged::server::build(
                opened.world,
                opened.journal,
                opened.recent,
                winged::server::Options::default(),
            )
        })
        .expect("the server starts");
        TestServer {
            base: server.base(),
            _server: server,
            _data: dir,
        }
    }
}

/// What to send as the request body.
pub enum Send<'a> {
    /// No body and no Content-Type.
    Nothing,
    /// A JSON body with `Content-Type: application/json`.
    Json(&'a serde_json::Value),
    /// Raw bytes, with this Content-Type (or none).
    Raw(Option<&'a str>, &'a [u8]),
}

/// An answer as received.
#[derive(Debug)]
pub struct Reply {
    /// HTTP status.
    pub status: u16,
    /// The Content-Type without parameters, lower-cased ("" if absent).
    pub media_type: String,
    /// The body as text.
    pub text: String,
    /// The body as bytes (for files and images).
    pub bytes: Vec<u8>,
}

impl Reply {
    /// The body as JSON.
    pub fn json(&self) -> serde_json::Value {
        serde_json::from_str(&self.text)
            .unwrap_or_else(|e| panic!("the answer is not JSON ({e}): {}", self.text))
    }
}

/// A blocking HTTP client that treats every status as an answer.
pub struct Http {
    agent: ureq::Agent,
    base: String,
}

impl Http {
    /// A client for `base` (`http://host:port`).
    pub fn new(base: &str) -> Http {
        let agent: ureq::Agent = ureq::Agent::config_builder()
            .http_status_as_error(false)
            .timeout_global(Some(Duration::from_secs(30)))
            .build()
            .into();
        Http {
            agent,
            base: base.to_string(),
        }
    }

    /// Sends `method path` (the path with any query) and reads the answer.
    pub fn call(&self, method: &str, path: &str, body: Send) -> Reply {
        let url = format!("{}{}", self.base, path);
        let result = match (method, body) {
            ("GET", Send::Nothing) => self.agent.get(&url).call(),
            ("DELETE", Send::Nothing) => self.agent.delete(&url).call(),
            (m, body) => {
                let b = match m {
                    "POST" => self.agent.post(&url),
                    "PUT" => self.agent.put(&url),
                    "PATCH" => self.agent.patch(&url),
                    other => panic!("the client cannot send a body with {other}"),
                };
                match body {
                    Send::Nothing => b.send_empty(),
                    Send::Json(v) => b
                        .header("content-type", "application/json")
                        .send(serde_json::to_vec(v).expect("JSON")),
                    Send::Raw(Some(ct), bytes) => b.header("content-type", ct).send(bytes),
                    Send::Raw(None, bytes) => b.send(bytes),
                }
            }
        };
        let mut res = result.unwrap_or_else(|e| panic!("{method} {path}: {e}"));
        let media_type = res
            .headers()
            .get("content-type")
            .and_then(|v| v.to_str().ok())
            .map(|v| {
                v.split(';')
                    .next()
                    .unwrap_or("")
                    .trim()
                    .to_ascii_lowercase()
            })
            .unwrap_or_default();
        // Images are read as bytes; the text is for JSON and text answers.
        let bytes = res
            .body_mut()
            .read_to_vec()
            .unwrap_or_else(|e| panic!("{method} {path}: reading the answer: {e}"));
        let text = String::from_utf8_lossy(&bytes).into_owned();
        Reply {
            status: res.status().as_u16(),
            media_type,
            text,
            bytes,
        }
    }
}
