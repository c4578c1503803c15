//! Durable writes per second over real HTTP: a server on a fresh data directory (SQLite
//! journal, `synchronous=FULL` unless `--normal`), and 1, 8 and 64 concurrent clients
//! each sending small writes (a body's pose) as fast as their answers come back. Every
//! answered write is on disk.
//!
//! ```sh
//! cargo run --release --example durable_writes -- [seconds per level] [--normal]
//! ```

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use serde_json::json;
use winged::model::World;
use winged::server::background::Background;
use winged::server::durable::{self, SnapshotPolicy};
use winged::server::metrics::Metrics;
use winged::server::{Options, build};
use winged::store::{Durability, StoreOptions};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let seconds: u64 = args.iter().find_map(|a| a.parse().ok()).unwrap_or(5);
    let durability = if args.iter().any(|a| a == "--normal") {
        Durability::Normal
    } else {
        Durability::Full
    };
    let dir = tempfile::tempdir().expect("a temporary directory");
    let data = dir.path().join("world");
    let metrics = Arc::new(Metrics::new());
    let server = {
        let (data, metrics) = (data.clone(), metrics.clone());
        Background::start("127.0.0.1:0".parse().unwrap(), move || {
            let opened = durable::open(
                &data,
                StoreOptions {
                    durability,
                    ..StoreOptions::default()
                },
                SnapshotPolicy::default(),
                1000,
                metrics.clone(),
                || Some(World::new()),
            )
            .map_err(std::io::Error::other)?;
            let options = Options {
                metrics,
                ..Options::default()
            };
            build(opened.world, opened.journal, opened.recent, options)
        })
        .expect("the server starts")
    };
    let base = server.base();
    println!(
        "durable writes over HTTP, {:?} durability, {seconds} s per level, data in {}",
        durability,
        data.display()
    );
    println!(
        "| clients | writes | writes/s | p50 ms | p99 ms | commits | entries per commit | ms per commit |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for clients in [1usize, 8, 64] {
        // One body per client, so that the writes do not contend on a name or a body.
        let bodies: Vec<u64> = (0..clients)
            .map(|i| {
                let agent = ureq::Agent::new_with_defaults();
                let v: serde_json::Value = agent
                    .post(format!("{base}/v1/bodies"))
                    .send_json(json!({"name": format!("c{clients}-{i}"), "shape": {"type": "box", "size": [1, 1, 1]}}))
                    .expect("a body")
                    .body_mut()
                    .read_json()
                    .expect("JSON");
                v["id"].as_u64().expect("an id")
            })
            .collect();
        let (commits0, entries0, seconds0) = commit_totals(&metrics);
        let stop = Arc::new(AtomicBool::new(false));
        let started = Instant::now();
        let workers: Vec<_> = bodies
            .into_iter()
            .map(|body| {
                let (base, stop) = (base.clone(), stop.clone());
                std::thread::spawn(move || {
                    let agent = ureq::Agent::new_with_defaults();
                    let mut latencies = Vec::new();
                    let mut x = 0.0;
                    while !stop.load(Ordering::Relaxed) {
                        x += 1.0;
                        let t = Instant::now();
                        agent
                            .patch(format!("{base}/v1/bodies/{body}"))
                            .send_json(
                                json!({"pose": {"position": [x, 0, 0], "rotation": [0, 0, 0, 1]}}),
                            )
                            .expect("a durable write");
                        latencies.push(t.elapsed());
                    }
                    latencies
                })
            })
            .collect();
        std::thread::sleep(Duration::from_secs(seconds));
        stop.store(true, Ordering::Relaxed);
        let mut all: Vec<Duration> = workers
            .into_iter()
            .flat_map(|w| w.join().expect("a client"))
            .collect();
        let elapsed = started.elapsed().as_secs_f64();
        all.sort();
        let pct = |p: f64| {
            all.get(((all.len() as f64 * p) as usize).min(all.len().saturating_sub(1)))
                .map_or(0.0, |d| d.as_secs_f64() * 1e3)
        };
        let (commits1, entries1, seconds1) = commit_totals(&metrics);
        let commits = commits1 - commits0;
        println!(
            "| {clients} | {} | {:.0} | {:.2} | {:.2} | {commits:.0} | {:.1} | {:.2} |",
            all.len(),
            all.len() as f64 / elapsed,
            pct(0.5),
            pct(0.99),
            (entries1 - entries0) / commits.max(1.0),
            (seconds1 - seconds0) * 1e3 / commits.max(1.0),
        );
    }
    server.stop().expect("the server stops");
}

/// (commits, entries, seconds) so far, read from the metrics' text.
fn commit_totals(m: &Metrics) -> (f64, f64, f64) {
    let text = m.render();
    let value = |name: &str| {
        text.lines()
            .find(|l| l.starts_with(name))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (
        value("winged_journal_commit_duration_seconds_count"),
        value("winged_journal_batch_entries_sum"),
        value("winged_journal_commit_duration_seconds_sum"),
    )
}
