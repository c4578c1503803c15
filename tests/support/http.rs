//! A real server on an ephemeral loopback port, and a real HTTP client, for the HTTP
//! tests.

#![allow(dead_code)]

use serde_json::Value;
use winged::model::World;
use winged::server::background::Background;

/// A running server; stopped (gracefully) when dropped.
pub struct TestServer {
    pub base: String,
    _server: Background,
    agent: ureq::Agent,
}

impl TestServer {
    /// Serves an empty world.
    pub fn start() -> Self {
        Self::with_world(World::new())
    }

    /// Serves `world` on 127.0.0.1 with an ephemeral port.
    pub fn with_world(world: World) -> Self {
        Self::with_limits(world, winged::server::Limits::default())
    }

    /// Serves `world`, in memory, under `limits`.
    pub fn with_limits(world: World, limits: winged::server::Limits) -> Self {
        Self::with_app(move || {
            winged::server::in_memory(world, limits).expect("the world's owner starts")
        })
    }

    /// Serves the application `make` builds (called on the server's runtime).
    pub fn with_app(make: impl FnOnce() -> winged::server::App + Send + 'static) -> Self {
        let server = Background::start("127.0.0.1:0".parse().unwrap(), move || Ok(make()))
            .expect("the server starts");
        let agent: ureq::Agent = ureq::Agent::config_builder()
            .http_status_as_error(false)
            .build()
            .into();
        TestServer {
            base: server.base(),
            _server: server,
            agent,
        }
    }

    pub fn url(&self, path: &str) -> String {
        format!("{}{}", self.base, path)
    }

    pub fn get(&self, path: &str) -> Reply {
        Reply::from(self.agent.get(&self.url(path)).call())
    }

    pub fn delete(&self, path: &str) -> Reply {
        Reply::from(self.agent.delete(&self.url(path)).call())
    }

    pub fn post(&self, path: &str, body: &Value) -> Reply {
        Reply::from(self.agent.post(&self.url(path)).send_json(body))
    }

    pub fn put(&self, path: &str, body: &Value) -> Reply {
        Reply::from(self.agent.put(&self.url(path)).send_json(body))
    }

    pub fn patch(&self, path: &str, body: &Value) -> Reply {
        Reply::from(self.agent.patch(&self.url(path)).send_json(body))
    }

    /// POSTs nothing: no body, no content type.
    pub fn post_empty(&self, path: &str) -> Reply {
        Reply::from(self.agent.post(&self.url(path)).send_empty())
    }

    /// POSTs raw bytes with a content type.
    pub fn post_raw(&self, path: &str, content_type: &str, body: &[u8]) -> Reply {
        Reply::from(
            self.agent
                .post(&self.url(path))
                .header("content-type", content_type)
                .send(body),
        )
    }

    pub fn agent(&self) -> ureq::Agent {
        self.agent.clone()
    }
}

/// An answer: status, content type, headers and body (as bytes, and as text for JSON).
#[derive(Debug)]
pub struct Reply {
    pub status: u16,
    pub content_type: String,
    pub text: String,
    pub bytes: Vec<u8>,
    pub headers: ureq::http::HeaderMap,
}

impl Reply {
    /// A header's value as text ("" if absent).
    pub fn header(&self, name: &str) -> &str {
        self.headers
            .get(name)
            .and_then(|v| v.to_str().ok())
            .unwrap_or("")
    }

    pub fn json(&self) -> Value {
        serde_json::from_str(&self.text).unwrap_or_else(|e| panic!("not JSON ({e}): {}", self.text))
    }

    /// Asserts a 2xx answer and returns its JSON.
    pub fn ok(&self) -> Value {
        assert!(
            (200..300).contains(&self.status),
            "expected success, got {}: {}",
            self.status,
            self.text
        );
        self.json()
    }

    /// Asserts a problem+json answer of `status` and returns it.
    pub fn problem(&self, status: u16) -> Value {
        assert_eq!(self.status, status, "{}", self.text);
        assert_eq!(
            self.content_type, "application/problem+json",
            "{}",
            self.text
        );
        let p = self.json();
        assert_eq!(p["status"], status);
        assert!(p["type"].as_str().is_some_and(|t| !t.is_empty()));
        assert!(p["title"].as_str().is_some_and(|t| !t.is_empty()));
        assert!(p["detail"].as_str().is_some_and(|t| !t.is_empty()));
        p
    }
}

impl From<Result<ureq::http::Response<ureq::Body>, ureq::Error>> for Reply {
    fn from(r: Result<ureq::http::Response<ureq::Body>, ureq::Error>) -> Self {
        let mut res = r.expect("the request reaches the server");
        let status = res.status().as_u16();
        let content_type = res
            .headers()
            .get("content-type")
            .and_then(|v| v.to_str().ok())
            .unwrap_or("")
            .to_string();
        let headers = res.headers().clone();
        let bytes = res
            .body_mut()
            .with_config()
            .limit(512 * 1024 * 1024)
            .read_to_vec()
            .expect("a body");
        Reply {
            status,
            content_type,
            text: String::from_utf8_lossy(&bytes).into_owned(),
            bytes,
            headers,
        }
    }
}

/// Checks a topology dump's winged-edge invariants: every link names an entity of the
/// dump, each wing meets its edge, each face's vertex cycle closes, and
/// F − E + V = 2(1 − H) for the handle count given.
pub fn check_topology_dump(t: &Value, handles: i64) {
    use std::collections::{HashMap, HashSet};
    let vs: HashSet<u64> = t["vertices"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v["id"].as_u64().unwrap())
        .collect();
    let fs: HashSet<u64> = t["faces"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["id"].as_u64().unwrap())
        .collect();
    let edges: HashMap<u64, &Value> = t["edges"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| (e["id"].as_u64().unwrap(), e))
        .collect();
    for e in edges.values() {
        for k in ["nvt", "pvt"] {
            assert!(vs.contains(&e[k].as_u64().unwrap()), "{k} of {e}");
        }
        for k in ["nface", "pface"] {
            assert!(fs.contains(&e[k].as_u64().unwrap()), "{k} of {e}");
        }
        // PCW and NCCW meet the edge at PVT; NCW and PCCW at NVT.
        for (k, at) in [
            ("pcw", "pvt"),
            ("nccw", "pvt"),
            ("ncw", "nvt"),
            ("pccw", "nvt"),
        ] {
            let w = edges
                .get(&e[k].as_u64().unwrap())
                .unwrap_or_else(|| panic!("{k} of {e} is no edge"));
            let v = &e[at];
            assert!(
                w["nvt"] == *v || w["pvt"] == *v,
                "{k} of {e} misses its {at}"
            );
        }
    }
    for f in t["faces"].as_array().unwrap() {
        for v in f["vertices"].as_array().unwrap() {
            assert!(vs.contains(&v.as_u64().unwrap()));
        }
    }
    let (nf, ne, nv) = (fs.len() as i64, edges.len() as i64, vs.len() as i64);
    assert_eq!(nf - ne + nv, 2 * (1 - handles), "F−E+V of {nf}/{ne}/{nv}");
}

/// A small deterministic random stream (SplitMix64, Box–Muller normals): the same
/// numbers for a seed on every machine.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal.
    pub fn normal(&mut self) -> f64 {
        let u = self.uniform().max(1e-300);
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * self.uniform()).cos()
    }

    /// Uniform on the unit sphere.
    pub fn unit_vector(&mut self) -> glam::DVec3 {
        loop {
            let v = glam::DVec3::new(
                2.0 * self.uniform() - 1.0,
                2.0 * self.uniform() - 1.0,
                2.0 * self.uniform() - 1.0,
            );
            let n = v.length();
            if n > 0.1 && n <= 1.0 {
                return v / n;
            }
        }
    }
}

/// A camera as `PUT /v1/cameras/{name}` takes it.
pub fn camera_json(c: &winged::model::Camera) -> Value {
    let k = c.intrinsics;
    serde_json::json!({
        "pose": {"position": c.pose.position.to_array(), "rotation": c.pose.rotation.to_array()},
        "intrinsics": {"width": k.width, "height": k.height, "fx": k.fx, "fy": k.fy, "cx": k.cx, "cy": k.cy},
    })
}

/// A camera 2 m from the blocks on the demo table, in front of its long side and to
/// the right: 640 × 480, f = 600.
pub fn demo_camera() -> winged::model::Camera {
    let target = glam::DVec3::new(0.0, 0.0, 0.8);
    let eye = target + glam::DVec3::new(0.55, -0.65, 0.52).normalize() * 2.0;
    let k = winged::model::Intrinsics::centered(640, 480, 600.0).expect("intrinsics");
    winged::model::Camera::look_at(eye, target, glam::DVec3::Z, k).expect("a camera")
}

/// An 8-bit RGB PNG of `rgb` (row-major, three samples a pixel).
pub fn png_rgb(width: u32, height: u32, rgb: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder
        .write_header()
        .expect("a header")
        .write_image_data(rgb)
        .expect("pixels");
    out
}

/// A grey picture of one level, as a base64 PNG.
pub fn blank_png_base64(width: u32, height: u32) -> String {
    use base64::Engine as _;
    let samples = vec![90u8; (width * height * 3) as usize];
    base64::engine::general_purpose::STANDARD.encode(png_rgb(width, height, &samples))
}

/// The position and rotation of a pose as the API answers it
/// (`{"position": [x, y, z], "rotation": [qx, qy, qz, qw]}`).
pub fn pose_of(p: &Value) -> (glam::DVec3, glam::DQuat) {
    let v = |x: &Value, k: usize| x[k].as_f64().expect("a number");
    (
        glam::DVec3::new(
            v(&p["position"], 0),
            v(&p["position"], 1),
            v(&p["position"], 2),
        ),
        glam::DQuat::from_xyzw(
            v(&p["rotation"], 0),
            v(&p["rotation"], 1),
            v(&p["rotation"], 2),
            v(&p["rotation"], 3),
        ),
    )
}
