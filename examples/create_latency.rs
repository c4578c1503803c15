//! Small writes and reads while a large body is created: the latency of a `PATCH` of a
//! small body's pose and of a `GET` of that body, sent back to back by two clients
//! while a third creates a UV sphere of `segments × rings` faces, against a running
//! `winged serve` on loopback. See BENCHMARKS.md ("Server"). With `--boolean`, the third
//! takes instead the difference of two such spheres made beforehand (the second moved
//! by half a radius on each axis), which the server solves beside the world's owner.
//!
//! ```text
//! cargo run --release --example create_latency -- http://127.0.0.1:7878
//! cargo run --release --example create_latency -- http://127.0.0.1:7878 --segments 1000 \
//!     --rings 1000 --runs 3
//! cargo run --release --example create_latency -- http://127.0.0.1:7878 --boolean \
//!     --segments 256 --rings 256
//! ```
//!
//! Each run: a small box is made; the writer and the reader start; 200 ms later the
//! sphere is posted; 200 ms after its answer both stop; the sphere and the box are
//! deleted. A probe counts as *during* the creation when it was sent before the
//! creation's answer and answered after the creation was sent. Printed per run: the
//! creation's time, and for each probe its count, p50, p99 and worst latency during the
//! creation, and the worst as a share of the creation's time. Only loopback URLs are
//! accepted.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread;
use std::time::{Duration, Instant};

use serde_json::{Value, json};

struct Args {
    url: String,
    segments: u32,
    rings: u32,
    runs: usize,
    boolean: bool,
}

fn args() -> Result<Args, String> {
    let mut a = Args {
        url: "http://127.0.0.1:7878".into(),
        segments: 1000,
        rings: 1000,
        runs: 3,
        boolean: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match arg.as_str() {
            "--segments" => {
                a.segments = value("--segments")?
                    .parse()
                    .map_err(|e| format!("--segments: {e}"))?
            }
            "--rings" => {
                a.rings = value("--rings")?
                    .parse()
                    .map_err(|e| format!("--rings: {e}"))?
            }
            "--runs" => {
                a.runs = value("--runs")?
                    .parse()
                    .map_err(|e| format!("--runs: {e}"))?
            }
            "--boolean" => a.boolean = true,
            url if url.starts_with("http://") => a.url = url.trim_end_matches('/').to_string(),
            other => return Err(format!("unknown argument {other:?}")),
        }
    }
    let host = a.url.trim_start_matches("http://");
    if !(host.starts_with("127.0.0.1:")
        || host.starts_with("localhost:")
        || host.starts_with("[::1]:"))
    {
        return Err(format!("{} is not a loopback URL", a.url));
    }
    Ok(a)
}

/// One probe: when it was sent and how long its answer took.
#[derive(Clone, Copy)]
struct Probe {
    sent: Instant,
    took: Duration,
}

/// Sends `request` back to back until `stop` is set, timing each.
fn probe(stop: Arc<AtomicBool>, mut request: impl FnMut(&ureq::Agent) -> u16) -> Vec<Probe> {
    let agent = ureq::Agent::new_with_defaults();
    let mut out = Vec::new();
    while !stop.load(Ordering::Relaxed) {
        let sent = Instant::now();
        let status = request(&agent);
        assert!(
            (200..300).contains(&status),
            "a probe was answered {status}"
        );
        out.push(Probe {
            sent,
            took: sent.elapsed(),
        });
    }
    out
}

/// Prints the probes that overlap `from..to` (the creation).
fn report(what: &str, probes: &[Probe], from: Instant, to: Instant) {
    let mut during: Vec<Duration> = probes
        .iter()
        .filter(|p| p.sent < to && p.sent + p.took > from)
        .map(|p| p.took)
        .collect();
    if during.is_empty() {
        println!("  {what:<28} none during the creation");
        return;
    }
    during.sort_unstable();
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let q = |p: f64| during[((during.len() as f64 * p).ceil() as usize).clamp(1, during.len()) - 1];
    let worst = during[during.len() - 1];
    println!(
        "  {what:<28} n={:<6} p50={:.3} ms  p99={:.3} ms  worst={:.3} ms = {:.2} % of the creation",
        during.len(),
        ms(q(0.5)),
        ms(q(0.99)),
        ms(worst),
        100.0 * worst.as_secs_f64() / (to - from).as_secs_f64()
    );
}

fn run(a: &Args) {
    let agent = ureq::Agent::new_with_defaults();
    let mut small = agent
        .post(&format!("{}/v1/bodies", a.url))
        .send_json(json!({"shape": {"type": "box", "size": [1, 1, 1]}}))
        .expect("POST a box");
    let small: Value = small.body_mut().read_json().expect("answer");
    let small = small["id"].as_u64().expect("the box's id");
    let body = format!("{}/v1/bodies/{small}", a.url);

    let stop = Arc::new(AtomicBool::new(false));
    let writer = {
        let (stop, body) = (stop.clone(), body.clone());
        thread::spawn(move || {
            let mut x = 0.0_f64;
            probe(stop, move |agent| {
                x = (x + 0.001) % 1.0;
                agent
                    .patch(&body)
                    .send_json(json!({"pose": {"position": [x, 0.0, 0.0]}}))
                    .map_or(0, |r| r.status().as_u16())
            })
        })
    };
    let reader = {
        let (stop, body) = (stop.clone(), body.clone());
        thread::spawn(move || {
            probe(stop, move |agent| {
                agent
                    .get(&body)
                    .call()
                    .and_then(|mut r| r.body_mut().read_to_vec().map(|_| r.status().as_u16()))
                    .unwrap_or(0)
            })
        })
    };
    let sphere = |at: f64| {
        let mut made = agent
            .post(&format!("{}/v1/bodies", a.url))
            .send_json(json!({
                "shape": {"type": "sphere", "radius": 1.0, "segments": a.segments, "rings": a.rings},
                "pose": {"position": [at, at, at]}
            }))
            .expect("POST a sphere");
        made.body_mut().read_json::<Value>().expect("answer")
    };
    let operands = a.boolean.then(|| (sphere(0.0), sphere(0.5)));
    thread::sleep(Duration::from_millis(200));
    let from = Instant::now();
    let made = match &operands {
        None => sphere(0.0),
        Some((s1, s2)) => {
            let mut cut = agent
                .post(&format!("{}/v1/bodies/{}/boolean", a.url, s1["id"]))
                .send_json(json!({"op": "difference", "with": s2["id"]}))
                .expect("POST the boolean");
            let cut: Value = cut.body_mut().read_json().expect("answer");
            json!({"id": cut["id"], "faces": cut["pieces"][0]["faces"]})
        }
    };
    let to = Instant::now();
    thread::sleep(Duration::from_millis(200));
    stop.store(true, Ordering::Relaxed);
    let writes = writer.join().expect("writer");
    let reads = reader.join().expect("reader");
    println!(
        "{} {}x{}: F={} in {:.3} s",
        if a.boolean {
            "sphere − sphere"
        } else {
            "sphere"
        },
        a.segments,
        a.rings,
        made["faces"],
        (to - from).as_secs_f64()
    );
    report("PATCH /v1/bodies/{id} pose", &writes, from, to);
    report("GET /v1/bodies/{id}", &reads, from, to);
    for id in [made["id"].as_u64().expect("the sphere's id"), small] {
        agent
            .delete(&format!("{}/v1/bodies/{id}", a.url))
            .call()
            .expect("DELETE");
    }
}

fn main() {
    let a = match args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("create_latency: {e}");
            std::process::exit(2);
        }
    };
    for _ in 0..a.runs {
        run(&a);
    }
}
