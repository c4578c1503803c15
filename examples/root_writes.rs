//! World writes under a root that lists many bodies, each made while a snapshot of the
//! world is held (as the server's readers hold one): an insert at the root, the kill of
//! the body inserted last, and the kill of a body from the middle of the root's parts.
//! See BENCHMARKS.md ("Server").
//!
//! ```text
//! cargo run --release --example root_writes            # 100,000 boxes under the root
//! cargo run --release --example root_writes -- 20000   # or another count
//! ```
//!
//! Prints the p50 and p99 of 200 writes of each kind, in µs.

use std::time::Instant;

use glam::{DQuat, DVec3};
use winged::model::solids::box_solid;
use winged::model::{BodyId, Pose, World};

fn main() {
    let count: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(100_000);
    let place = |x: f64, y: f64| Pose::new(DVec3::new(x, y, 0.0), DQuat::IDENTITY);
    let mut w = World::new();
    let root = w.root();
    let start = Instant::now();
    let mut listed: Vec<BodyId> = Vec::with_capacity(count);
    for i in 0..count {
        let pose = place(i as f64, 0.0).expect("a pose");
        let b = w
            .insert_with(None, root, pose, |s| box_solid(s, DVec3::ONE))
            .expect("a box");
        listed.push(b);
    }
    println!(
        "{count} boxes under the root, inserted in {:.0} ms (no snapshot held)",
        start.elapsed().as_secs_f64() * 1e3
    );
    let (mut insert, mut kill_last, mut kill_middle) = (Vec::new(), Vec::new(), Vec::new());
    let timed = |w: &mut World, out: &mut Vec<f64>, write: &mut dyn FnMut(&mut World)| {
        let snapshot = w.clone();
        let t = Instant::now();
        write(w);
        out.push(t.elapsed().as_secs_f64() * 1e6);
        drop(snapshot);
    };
    for i in 0..200 {
        let pose = place(i as f64, 5.0).expect("a pose");
        let mut added = None;
        timed(&mut w, &mut insert, &mut |w| {
            added = w
                .insert_with(None, root, pose, |s| box_solid(s, DVec3::ONE))
                .ok();
        });
        let added = added.expect("a box");
        timed(&mut w, &mut kill_last, &mut |w| {
            w.kill(added).expect("live");
        });
        let middle = listed[count / 2 + i];
        timed(&mut w, &mut kill_middle, &mut |w| {
            w.kill(middle).expect("live");
        });
    }
    for (what, v) in [
        ("insert at the root", &mut insert),
        ("kill the body inserted last", &mut kill_last),
        ("kill a body from the middle", &mut kill_middle),
    ] {
        v.sort_by(f64::total_cmp);
        println!(
            "{what}, a snapshot held: p50 {:.1} µs, p99 {:.1} µs",
            v[v.len() / 2],
            v[v.len() * 99 / 100]
        );
    }
}
