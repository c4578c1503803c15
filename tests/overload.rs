//! Overload of the real binary: a flood of writes larger than the server will queue gets
//! 503 answers with `Retry-After` at once, the server's memory stays bounded, and
//! afterwards it serves normally. Also: the server refuses to start open to the network
//! without tokens.

#[path = "support/process.rs"]
mod process;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread;
use std::time::{Duration, Instant};

use process::{Server, agent, run};
use serde_json::{Value, json};

#[test]
fn a_flood_gets_503_with_retry_after_and_the_server_recovers() {
    let server = Server::start(&["--memory", "--queue", "4", "--max-in-flight", "48"]);
    let base = server.base.clone();
    let http = agent(Duration::from_secs(30));
    // A body heavy enough that each write keeps the world's owner busy for a while.
    let mut res = http
        .post(format!("{base}/v1/bodies"))
        .send_json(json!({"name": "ball", "shape": {"type": "sphere", "radius": 1, "segments": 256, "rings": 128}}))
        .expect("the server answers");
    assert_eq!(res.status().as_u16(), 201);
    let ball = res.body_mut().read_json::<Value>().unwrap()["id"]
        .as_u64()
        .unwrap();
    let rss_before = server.memory_kib("VmRSS").expect("/proc is readable");

    let ok = Arc::new(AtomicU64::new(0));
    let busy = Arc::new(AtomicU64::new(0));
    let other = Arc::new(AtomicU64::new(0));
    let stop = Arc::new(AtomicBool::new(false));
    let flooders: Vec<_> = (0..96)
        .map(|i| {
            let (base, ok, busy, other, stop) = (
                base.clone(),
                ok.clone(),
                busy.clone(),
                other.clone(),
                stop.clone(),
            );
            thread::spawn(move || {
                let http = agent(Duration::from_secs(30));
                while !stop.load(Ordering::Relaxed) {
                    // Dilation moves every vertex: real work, and the world stays the
                    // same size.
                    let factor = if i % 2 == 0 { 1.001 } else { 1.0 / 1.001 };
                    let r = http
                        .post(format!("{base}/v1/bodies/{ball}/transform"))
                        .send_json(json!({"op": "dilate", "factor": factor, "frame": "body"}));
                    match r {
                        Ok(res) if res.status().as_u16() == 200 => {
                            ok.fetch_add(1, Ordering::Relaxed);
                        }
                        Ok(res) if res.status().as_u16() == 503 => {
                            let retry = res
                                .headers()
                                .get("retry-after")
                                .and_then(|v| v.to_str().ok())
                                .and_then(|v| v.parse::<u64>().ok());
                            assert!(retry.is_some(), "a 503 without Retry-After");
                            let kind = res
                                .headers()
                                .get("content-type")
                                .and_then(|v| v.to_str().ok())
                                .unwrap_or("")
                                .to_string();
                            assert_eq!(kind, "application/problem+json");
                            busy.fetch_add(1, Ordering::Relaxed);
                        }
                        _ => {
                            other.fetch_add(1, Ordering::Relaxed);
                        }
                    }
                }
            })
        })
        .collect();
    let started = Instant::now();
    let mut peak = rss_before;
    while started.elapsed() < Duration::from_secs(4) {
        peak = peak.max(server.memory_kib("VmRSS").unwrap_or(0));
        thread::sleep(Duration::from_millis(20));
    }
    stop.store(true, Ordering::Relaxed);
    for f in flooders {
        f.join().expect("a flooder");
    }
    let (ok, busy, other) = (
        ok.load(Ordering::Relaxed),
        busy.load(Ordering::Relaxed),
        other.load(Ordering::Relaxed),
    );
    assert!(busy > 0, "no 503 under a flood ({ok} ok)");
    assert!(ok > 0, "nothing got through ({busy} busy)");
    assert_eq!(
        other, 0,
        "answers other than 200 or 503 ({ok} ok, {busy} busy)"
    );
    // Bounded: the owner's queue holds 4 writes and at most 48 requests are in flight;
    // the growth is a few copies of the 32k-face body, not one per request sent.
    let growth_mib = peak.saturating_sub(rss_before) / 1024;
    assert!(
        growth_mib < 256,
        "memory grew by {growth_mib} MiB under the flood ({ok} ok, {busy} busy)"
    );

    // Afterwards it serves normally.
    let mut res = http
        .get(format!("{base}/readyz"))
        .call()
        .expect("the server answers");
    assert_eq!(res.status().as_u16(), 200);
    let ready = res.body_mut().read_json::<Value>().unwrap();
    let mut res = http
        .patch(format!("{base}/v1/bodies/{ball}"))
        .send_json(json!({"name": "calm"}))
        .expect("the server answers");
    assert_eq!(res.status().as_u16(), 200);
    let after = res.body_mut().read_json::<Value>().unwrap();
    assert_eq!(
        after["revision"].as_u64(),
        ready["revision"].as_u64().map(|r| r + 1)
    );
    // Every answered write counted once: the revision is the writes that were applied.
    assert_eq!(ready["revision"].as_u64(), Some(1 + ok));
}

#[test]
fn the_server_refuses_a_public_address_without_tokens() {
    let (status, out) = run(&["serve", "--memory", "--addr", "0.0.0.0:0"]);
    assert!(!status.success());
    assert!(out.contains("--insecure"), "{out}");
    assert!(out.contains("token"), "{out}");

    // With a token it starts (and a read token cannot write).
    let server = Server::start_with_env(
        &["--memory"],
        &[(
            "WINGED_TOKENS",
            "read:r-0123456789abcdef,write:w-0123456789abcdef",
        )],
    );
    let http = agent(Duration::from_secs(10));
    let res = http
        .get(format!("{}/v1/world", server.base))
        .header("Authorization", "Bearer r-0123456789abcdef")
        .call()
        .expect("the server answers");
    assert_eq!(res.status().as_u16(), 200);
    let res = http
        .post(format!("{}/v1/bodies", server.base))
        .header("Authorization", "Bearer r-0123456789abcdef")
        .send_json(json!({"shape": {"type": "box", "size": [1, 1, 1]}}))
        .expect("the server answers");
    assert_eq!(res.status().as_u16(), 403);
    // A malformed token source stops the start with a message naming it.
    let (status, out) = run(&["serve", "--memory", "--token", "superuser:abc"]);
    assert!(!status.success());
    assert!(out.contains("superuser") || out.contains("role"), "{out}");
}
