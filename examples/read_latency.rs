//! Small-read latency under heavy reads: the p50/p99/max latency of `GET /v1/world`
//! while clients pull the whole topology of a million-face body, against a running
//! `winged serve` on loopback. `bench/http/run.sh` runs it; see BENCHMARKS.md ("Server").
//!
//! ```text
//! cargo run --release --example read_latency -- http://127.0.0.1:7878
//! cargo run --release --example read_latency -- http://127.0.0.1:7878 --pullers 4 \
//!     --segments 1000 --rings 1000 --seconds 20 --pause-ms 0 --trace-ms 50
//! ```
//!
//! Phases, each bounded in time (and the probe in count):
//!
//! 1. **idle**: the probe alone: one client sending `GET /v1/world` back to back on a
//!    kept-alive connection (`--pause-ms N` waits N ms between requests; on a virtual
//!    machine that measures the idle cores' wake-up time as much as the server).
//! 2. **create**: the probe while `POST /v1/bodies` makes the big body (a UV sphere of
//!    `segments × rings` faces), which the world's owner builds in one command.
//! 3. **pullers**: the probe while `--pullers` clients each pull
//!    `GET /v1/bodies/{id}/topology` over and over (reading and discarding the bytes).
//!
//! The big body is deleted at the end. Only loopback URLs are accepted. `--trace-ms N`
//! prints each probe slower than N ms and each pull, with times since the start.

use std::io::Read;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};
use std::thread;
use std::time::{Duration, Instant};

use serde_json::{Value, json};

/// When the program started, for `--trace-ms` lines.
static T0: OnceLock<Instant> = OnceLock::new();
/// `--trace-ms`: print every probe slower than this, and every pull (0: off).
static TRACE_MS: AtomicU64 = AtomicU64::new(0);

fn since_start() -> f64 {
    T0.get_or_init(Instant::now).elapsed().as_secs_f64()
}

/// The most probe requests per phase (a bound besides the phase's time).
const MAX_PROBES: usize = 2_000_000;

struct Args {
    url: String,
    pullers: usize,
    segments: u32,
    rings: u32,
    seconds: u64,
    pause: Duration,
}

fn args() -> Result<Args, String> {
    let mut a = Args {
        url: std::env::var("WINGED").unwrap_or_else(|_| "http://127.0.0.1:7878".into()),
        pullers: 4,
        segments: 1000,
        rings: 1000,
        seconds: 20,
        pause: Duration::ZERO,
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut num = |name: &str| -> Result<u64, String> {
            it.next()
                .and_then(|v| v.parse().ok())
                .ok_or(format!("{name} needs a number"))
        };
        match arg.as_str() {
            "--pullers" => a.pullers = num("--pullers")? as usize,
            "--segments" => a.segments = num("--segments")? as u32,
            "--rings" => a.rings = num("--rings")? as u32,
            "--seconds" => a.seconds = num("--seconds")?,
            "--pause-ms" => a.pause = Duration::from_millis(num("--pause-ms")?),
            "--trace-ms" => TRACE_MS.store(num("--trace-ms")?, Ordering::Relaxed),
            url if url.starts_with("http://") => a.url = url.trim_end_matches('/').to_owned(),
            other => return Err(format!("unknown argument {other:?}")),
        }
    }
    let authority = a.url.trim_start_matches("http://");
    let loopback = ["127.0.0.1", "localhost", "[::1]"].iter().any(|h| {
        authority
            .strip_prefix(h)
            .is_some_and(|rest| rest.is_empty() || rest.starts_with([':', '/']))
    });
    if !loopback {
        return Err(format!("{}: only loopback servers are measured", a.url));
    }
    Ok(a)
}

/// A client with a connection pool and no timeouts: with `timeout_global` set, ureq 3.5
/// answered about one request in ten some 4 ms late on this loopback, which would
/// measure the client rather than the server.
fn agent() -> ureq::Agent {
    ureq::Agent::new_with_defaults()
}

/// Latencies of `GET /v1/world`, one after another with `pause` between them, until
/// `stop` is set or `limit` has passed.
fn probe(url: String, stop: Arc<AtomicBool>, limit: Duration, pause: Duration) -> Vec<Duration> {
    let agent = agent();
    let world = format!("{url}/v1/world");
    let start = Instant::now();
    let mut lat = Vec::new();
    while !stop.load(Ordering::Relaxed) && start.elapsed() < limit && lat.len() < MAX_PROBES {
        let t = Instant::now();
        let mut res = agent.get(&world).call().expect("GET /v1/world");
        let _ = res.body_mut().read_to_vec().expect("world body");
        let took = t.elapsed();
        let trace = TRACE_MS.load(Ordering::Relaxed);
        if trace > 0 && took >= Duration::from_millis(trace) {
            println!(
                "trace    t={:.3} s: GET /v1/world took {:.1} ms",
                since_start() - took.as_secs_f64(),
                took.as_secs_f64() * 1e3
            );
        }
        lat.push(took);
        if !pause.is_zero() {
            thread::sleep(pause);
        }
    }
    lat
}

fn report(phase: &str, mut lat: Vec<Duration>, wall: Duration) {
    if lat.is_empty() {
        println!("{phase:<8} no requests");
        return;
    }
    lat.sort_unstable();
    let q = |p: f64| lat[((lat.len() as f64 * p).ceil() as usize).clamp(1, lat.len()) - 1];
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    println!(
        "{phase:<8} GET /v1/world: n={:<6} p50={:.3} ms  p90={:.3} ms  p99={:.3} ms  p99.9={:.3} ms  max={:.3} ms  (over {:.1} s)",
        lat.len(),
        ms(q(0.5)),
        ms(q(0.9)),
        ms(q(0.99)),
        ms(q(0.999)),
        ms(lat[lat.len() - 1]),
        wall.as_secs_f64()
    );
}

fn main() {
    since_start();
    let a = match args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("read_latency: {e}");
            std::process::exit(2);
        }
    };
    let limit = Duration::from_secs(a.seconds);

    // 1. The probe alone.
    let stop = Arc::new(AtomicBool::new(false));
    let t = Instant::now();
    let idle = probe(
        a.url.clone(),
        stop.clone(),
        limit.min(Duration::from_secs(5)),
        a.pause,
    );
    report("idle", idle, t.elapsed());

    // 2. The probe while the big body is made.
    let p = {
        let (url, stop) = (a.url.clone(), stop.clone());
        let pause = a.pause;
        thread::spawn(move || probe(url, stop, Duration::from_secs(120), pause))
    };
    thread::sleep(Duration::from_millis(200));
    let t = Instant::now();
    let mut made = agent()
        .post(&format!("{}/v1/bodies", a.url))
        .send_json(json!({
            "name": "read-latency-sphere",
            "shape": {"type": "sphere", "radius": 1.0, "segments": a.segments, "rings": a.rings}
        }))
        .expect("POST the big sphere");
    let made: Value = made.body_mut().read_json().expect("answer");
    let create = t.elapsed();
    thread::sleep(Duration::from_millis(200));
    stop.store(true, Ordering::Relaxed);
    let during_create = p.join().expect("probe");
    let id = made["id"].as_u64().expect("body id");
    println!(
        "create   sphere {}x{}: F={} E={} V={} in {:.3} s (one command of the world's owner)",
        a.segments,
        a.rings,
        made["faces"],
        made["edges"],
        made["vertices"],
        create.as_secs_f64()
    );
    report("create", during_create, create + Duration::from_millis(400));

    // 3. The probe while the pullers pull the topology.
    let stop = Arc::new(AtomicBool::new(false));
    let pulls = Arc::new(AtomicU64::new(0));
    let bytes = Arc::new(AtomicU64::new(0));
    let pull_ns = Arc::new(AtomicU64::new(0));
    let t = Instant::now();
    let pullers: Vec<_> = (0..a.pullers)
        .map(|_| {
            let (stop, pulls, bytes, pull_ns) =
                (stop.clone(), pulls.clone(), bytes.clone(), pull_ns.clone());
            let url = format!("{}/v1/bodies/{id}/topology", a.url);
            thread::spawn(move || {
                let agent = agent();
                let mut buf = vec![0u8; 1 << 16];
                while !stop.load(Ordering::Relaxed) {
                    let t = Instant::now();
                    let mut res = agent.get(&url).call().expect("GET topology");
                    let mut r = res.body_mut().as_reader();
                    let mut n = 0u64;
                    loop {
                        let k = r.read(&mut buf).expect("topology body");
                        if k == 0 {
                            break;
                        }
                        n += k as u64;
                    }
                    bytes.fetch_add(n, Ordering::Relaxed);
                    pulls.fetch_add(1, Ordering::Relaxed);
                    pull_ns.fetch_add(t.elapsed().as_nanos() as u64, Ordering::Relaxed);
                    if TRACE_MS.load(Ordering::Relaxed) > 0 {
                        println!(
                            "trace    t={:.3} s: a pull started, done at t={:.3} s",
                            since_start() - t.elapsed().as_secs_f64(),
                            since_start()
                        );
                    }
                }
            })
        })
        .collect();
    // Let every puller get its first answer under way before probing.
    thread::sleep(Duration::from_millis(500));
    let probe_start = Instant::now();
    let under_load = probe(
        a.url.clone(),
        Arc::new(AtomicBool::new(false)),
        limit,
        a.pause,
    );
    let probe_wall = probe_start.elapsed();
    stop.store(true, Ordering::Relaxed);
    for p in pullers {
        p.join().expect("puller");
    }
    let wall = t.elapsed();
    report(&format!("pull x{}", a.pullers), under_load, probe_wall);
    let n = pulls.load(Ordering::Relaxed);
    if n > 0 {
        println!(
            "pullers  {n} topology pulls of {:.1} MB each, {:.2} s per pull on average, {:.1} MB/s in all (over {:.1} s)",
            bytes.load(Ordering::Relaxed) as f64 / n as f64 / 1e6,
            pull_ns.load(Ordering::Relaxed) as f64 / n as f64 / 1e9,
            bytes.load(Ordering::Relaxed) as f64 / 1e6 / wall.as_secs_f64(),
            wall.as_secs_f64()
        );
    }

    agent()
        .delete(&format!("{}/v1/bodies/{id}", a.url))
        .call()
        .expect("DELETE the big sphere");
}
