//! Large request bodies against the real binary over real HTTP: what a refused request
//! costs the server.
//!
//! - Five polyhedron bodies just under the request size limit, each with far more faces
//!   than a body may have, sent at once: each is answered 413 problem+json, the server's
//!   resident memory grows by less than 512 MiB over idle, and `/healthz` keeps
//!   answering meanwhile (its worst latency is printed).
//! - Vertex, face and corner counts are refused (413) one past their limits and not
//!   refused for their size at the limits.
//! - A small PNG whose header claims 16000×16000 pixels, sent to camera solution for a
//!   640×480 camera, is refused with the size mismatch without being decoded (no 256 MB
//!   jump in resident memory).

#[path = "support/process.rs"]
mod process;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread;
use std::time::{Duration, Instant};

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD as BASE64;
use process::{Server, agent, memory_kib_of};
use serde_json::{Value, json};
use winged::edit::command::{MAX_BODY_CORNERS, MAX_BODY_FACES, MAX_BODY_VERTICES};
use winged::server::api::MAX_REQUEST_BYTES;

const MIB: u64 = 1024 * 1024;

/// `{"shape":{"type":"polyhedron","vertices":[...],"faces":[...]}}` with `vertices`
/// copies of `vertex`, then `first_face` and `faces - 1` copies of `face`.
fn polyhedron(
    vertices: usize,
    vertex: &str,
    first_face: &str,
    faces: usize,
    face: &str,
) -> Vec<u8> {
    let mut b = Vec::with_capacity(
        64 + vertices * (vertex.len() + 1) + first_face.len() + faces * (face.len() + 1),
    );
    b.extend_from_slice(br#"{"shape":{"type":"polyhedron","vertices":["#);
    for i in 0..vertices {
        if i > 0 {
            b.push(b',');
        }
        b.extend_from_slice(vertex.as_bytes());
    }
    b.extend_from_slice(br#"],"faces":["#);
    b.extend_from_slice(first_face.as_bytes());
    for _ in 1..faces {
        b.push(b',');
        b.extend_from_slice(face.as_bytes());
    }
    b.extend_from_slice(b"]}}");
    b
}

/// A polyhedron body of about `bytes` bytes (at most that many): four vertices and as
/// many triangles as fit.
fn triangles_filling(bytes: usize) -> Vec<u8> {
    let vertex_list = "[0,0,0],[1,0,0],[0,1,0],[0,0,1]";
    let fixed = polyhedron(1, vertex_list, "[0,1,2]", 1, "").len();
    let faces = 1 + (bytes - fixed) / "[0,1,2],".len();
    let b = polyhedron(1, vertex_list, "[0,1,2]", faces, "[0,1,2]");
    assert!(b.len() <= bytes, "{} > {bytes}", b.len());
    b
}

/// A face of `n` corners, all vertex 0.
fn long_face(n: usize) -> String {
    let mut f = String::with_capacity(2 * n + 2);
    f.push('[');
    for i in 0..n {
        if i > 0 {
            f.push(',');
        }
        f.push('0');
    }
    f.push(']');
    f
}

/// A status, the problem's `type` (empty when the answer is no problem) and the time
/// the answer took.
struct Answer {
    status: u16,
    kind: String,
    detail: String,
    took: Duration,
}

fn post_raw(http: &ureq::Agent, url: &str, body: &[u8]) -> Answer {
    let started = Instant::now();
    let mut res = http
        .post(url)
        .header("content-type", "application/json")
        .send(body)
        .expect("the server answers");
    let took = started.elapsed();
    let status = res.status().as_u16();
    let media = res
        .headers()
        .get("content-type")
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_string();
    let text = res.body_mut().read_to_string().unwrap_or_default();
    let (kind, detail) = if media == "application/problem+json" {
        let v: Value = serde_json::from_str(&text).expect("a problem is JSON");
        (
            v["type"].as_str().unwrap_or("").to_string(),
            v["detail"].as_str().unwrap_or("").to_string(),
        )
    } else {
        (String::new(), text)
    };
    Answer {
        status,
        kind,
        detail,
        took,
    }
}

/// The server's resident memory, sampled every 10 ms until stopped; the peak in KiB.
struct RssSampler {
    stop: Arc<AtomicBool>,
    peak: Arc<AtomicU64>,
    thread: thread::JoinHandle<()>,
}

impl RssSampler {
    fn start(pid: u32) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let peak = Arc::new(AtomicU64::new(0));
        let (s, p) = (stop.clone(), peak.clone());
        let thread = thread::spawn(move || {
            while !s.load(Ordering::Relaxed) {
                if let Some(kib) = memory_kib_of(pid, "VmRSS") {
                    p.fetch_max(kib, Ordering::Relaxed);
                }
                thread::sleep(Duration::from_millis(10));
            }
        });
        RssSampler { stop, peak, thread }
    }

    /// The highest resident size seen, in KiB.
    fn finish(self) -> u64 {
        self.stop.store(true, Ordering::Relaxed);
        self.thread.join().expect("the sampler ends");
        self.peak.load(Ordering::Relaxed)
    }
}

/// `GET /healthz` every 20 ms until stopped: polls, failures and the worst latency.
struct HealthPoller {
    stop: Arc<AtomicBool>,
    thread: thread::JoinHandle<(u32, u32, Duration)>,
}

impl HealthPoller {
    fn start(base: &str) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let s = stop.clone();
        let url = format!("{base}/healthz");
        let thread = thread::spawn(move || {
            let http = agent(Duration::from_secs(30));
            let (mut polls, mut failures, mut worst) = (0, 0, Duration::ZERO);
            while !s.load(Ordering::Relaxed) {
                let started = Instant::now();
                let ok = matches!(http.get(&url).call(), Ok(r) if r.status().as_u16() == 200);
                worst = worst.max(started.elapsed());
                polls += 1;
                if !ok {
                    failures += 1;
                }
                thread::sleep(Duration::from_millis(20));
            }
            (polls, failures, worst)
        });
        HealthPoller { stop, thread }
    }

    fn finish(self) -> (u32, u32, Duration) {
        self.stop.store(true, Ordering::Relaxed);
        self.thread.join().expect("the poller ends")
    }
}

/// The server's resident size once it has answered a first request, in KiB.
fn idle_rss(server: &Server) -> u64 {
    let http = agent(Duration::from_secs(30));
    let res = http
        .get(format!("{}/healthz", server.base))
        .call()
        .expect("healthz answers");
    assert_eq!(res.status().as_u16(), 200);
    thread::sleep(Duration::from_millis(200));
    server.memory_kib("VmRSS").expect("/proc is readable")
}

#[test]
fn five_oversized_polyhedra_at_once_are_refused_within_bounded_memory() {
    let server = Server::start(&["--memory"]);
    let url = format!("{}/v1/bodies", server.base);
    // Just under the request size limit, so that only the face count can refuse it.
    let body = Arc::new(triangles_filling(MAX_REQUEST_BYTES - 1));
    let idle = idle_rss(&server);

    let sampler = RssSampler::start(server.pid());
    let health = HealthPoller::start(&server.base);
    let started = Instant::now();
    let senders: Vec<_> = (0..5)
        .map(|_| {
            let (url, body) = (url.clone(), body.clone());
            thread::spawn(move || post_raw(&agent(Duration::from_secs(300)), &url, &body))
        })
        .collect();
    let answers: Vec<Answer> = senders
        .into_iter()
        .map(|t| t.join().expect("a sender"))
        .collect();
    let all_answered = started.elapsed();
    let (polls, failures, worst) = health.finish();
    let peak = sampler.finish();
    let hwm = server.memory_kib("VmHWM").unwrap_or(0);
    let after = server.memory_kib("VmRSS").unwrap_or(0);

    let growth = peak.max(hwm).saturating_sub(idle);
    println!(
        "five {:.1} MiB polyhedron bodies at once: idle RSS {} MiB, peak {} MiB (VmHWM {} MiB), \
         growth {} MiB, {} MiB resident afterwards; all answered in {:.2} s, each in {:?} s; \
         /healthz: {polls} polls, {failures} failed, worst {:.1} ms",
        body.len() as f64 / MIB as f64,
        idle / 1024,
        peak / 1024,
        hwm / 1024,
        growth / 1024,
        after / 1024,
        all_answered.as_secs_f64(),
        answers
            .iter()
            .map(|a| (a.took.as_secs_f64() * 100.0).round() / 100.0)
            .collect::<Vec<_>>(),
        worst.as_secs_f64() * 1e3,
    );
    for a in &answers {
        assert_eq!(a.status, 413, "{}", a.detail);
        assert_eq!(a.kind, "urn:winged:problem:too-large", "{}", a.detail);
        assert!(a.detail.contains("faces"), "{}", a.detail);
    }
    assert!(
        growth < 512 * 1024,
        "resident memory grew by {} MiB while refusing five bodies",
        growth / 1024
    );
    assert!(polls > 0, "/healthz was never polled");
    assert_eq!(failures, 0, "/healthz failed {failures} of {polls} times");
    // The figure to watch is printed above; this bound only catches a stalled server on a
    // loaded machine, where timing is noisy.
    assert!(
        worst < Duration::from_secs(1),
        "/healthz took {worst:?} at worst"
    );

    // The server still takes ordinary writes.
    let http = agent(Duration::from_secs(30));
    let res = http
        .post(&url)
        .send_json(json!({"shape": {"type": "box", "size": [1, 1, 1]}}))
        .expect("the server answers");
    assert_eq!(res.status().as_u16(), 201);
}

#[test]
fn counts_are_refused_past_their_limits_and_not_at_them() {
    let server = Server::start(&["--memory"]);
    let url = format!("{}/v1/bodies", server.base);
    let http = agent(Duration::from_secs(300));
    let three = "[0,0,0],[1,0,0],[0,1,0]";
    // (what, body, status): at a limit the size does not refuse the body, so the
    // builder does (a face names a vertex that is not there, or repeats one): 422.
    let over_faces = MAX_BODY_FACES + 1;
    // The request's face check counts two faces more than a polyhedron's list.
    let at_faces = MAX_BODY_FACES - 2;
    let corners_per_face = MAX_BODY_CORNERS / 4;
    let cases: Vec<(&str, Vec<u8>, u16)> = vec![
        (
            "one vertex too many",
            polyhedron(MAX_BODY_VERTICES + 1, "[0,0,0]", "[0,1,2]", 1, ""),
            413,
        ),
        (
            "as many vertices as allowed",
            polyhedron(MAX_BODY_VERTICES, "[0,0,0]", "[0,1,99999999]", 1, ""),
            422,
        ),
        (
            "one face too many",
            polyhedron(1, three, "[0,1,2]", over_faces, "[0,1,2]"),
            413,
        ),
        (
            "as many faces as allowed",
            polyhedron(1, three, "[0,1,9]", at_faces, "[0,1,2]"),
            422,
        ),
        (
            "one corner too many",
            polyhedron(
                1,
                three,
                &long_face(corners_per_face + 1),
                4,
                &long_face(corners_per_face),
            ),
            413,
        ),
        (
            "as many corners as allowed",
            polyhedron(
                1,
                three,
                &long_face(corners_per_face),
                4,
                &long_face(corners_per_face),
            ),
            422,
        ),
    ];
    for (what, body, status) in cases {
        let a = post_raw(&http, &url, &body);
        println!(
            "{what} ({:.1} MiB): {} in {:.2} s: {}",
            body.len() as f64 / MIB as f64,
            a.status,
            a.took.as_secs_f64(),
            a.detail
        );
        assert_eq!(a.status, status, "{what}: {}", a.detail);
        assert!(
            a.kind.starts_with("urn:winged:problem:"),
            "{what}: not a problem: {}",
            a.detail
        );
    }
    // An octahedron is taken.
    let octahedron = json!({"shape": {"type": "polyhedron",
        "vertices": [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]],
        "faces": [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4],
                  [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]}});
    let mut res = http
        .post(&url)
        .send_json(&octahedron)
        .expect("the server answers");
    assert_eq!(res.status().as_u16(), 201);
    let made: Value = res.body_mut().read_json().expect("JSON");
    assert_eq!(made["faces"], 8);
    assert_eq!(made["vertices"], 6);
}

/// A 16000 × 16000 grey PNG, all black: about 250 KB that decode to 256 MB.
fn huge_black_png() -> Vec<u8> {
    use std::io::Write as _;
    let side = 16_000;
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, side, side);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::High);
    let mut header = encoder.write_header().expect("a header");
    let mut rows = header.stream_writer().expect("a stream");
    let row = vec![0u8; side as usize];
    for _ in 0..side {
        rows.write_all(&row).expect("a row");
    }
    rows.finish().expect("the image ends");
    header.finish().expect("the file ends");
    out
}

#[test]
fn a_picture_of_another_size_is_refused_before_it_is_decoded() {
    let server = Server::start(&["--memory"]);
    let http = agent(Duration::from_secs(120));
    let camera = json!({
        "look_at": {"eye": [3, -3, 2], "target": [0, 0, 0]},
        "intrinsics": {"width": 640, "height": 480, "fx": 600, "fy": 600, "cx": 320, "cy": 240}
    });
    let res = http
        .put(format!("{}/v1/cameras/small", server.base))
        .send_json(&camera)
        .expect("the server answers");
    assert!(res.status().is_success(), "{}", res.status());
    let png = huge_black_png();
    let body = serde_json::to_vec(&json!({"image": BASE64.encode(&png), "initial": "small"}))
        .expect("JSON");
    let idle = idle_rss(&server);

    let sampler = RssSampler::start(server.pid());
    let a = post_raw(&http, &format!("{}/v1/camera-solution", server.base), &body);
    let peak = sampler.finish();
    let hwm = server.memory_kib("VmHWM").unwrap_or(0);
    let growth = peak.max(hwm).saturating_sub(idle);
    println!(
        "a {} KB PNG claiming 16000×16000 for a 640×480 camera: {} in {:.3} s ({}); \
         idle RSS {} MiB, peak {} MiB (VmHWM {} MiB), growth {} MiB",
        png.len() / 1000,
        a.status,
        a.took.as_secs_f64(),
        a.detail,
        idle / 1024,
        peak / 1024,
        hwm / 1024,
        growth / 1024
    );
    assert_eq!(a.status, 422, "{}", a.detail);
    assert_eq!(a.kind, "urn:winged:problem:invalid-image", "{}", a.detail);
    assert!(
        a.detail.contains("16000×16000") && a.detail.contains("640×480"),
        "{}",
        a.detail
    );
    assert!(
        growth < 128 * 1024,
        "resident memory grew by {} MiB for a refused picture",
        growth / 1024
    );
}
