//! The world's owner under load, in process (no HTTP): how many commands per second the
//! actor answers through its [`Handle`], one requester at a time and with many at once.
//! See BENCHMARKS.md ("Server") for the figures and the goal (≥ 300,000 commands/s).
//!
//! ```text
//! cargo bench --bench actor                  # everything (about half a minute)
//! cargo bench --bench actor -- translate     # one group
//! ```
//!
//! A command is one message to the actor and its answer: an edit (`Handle::apply`) or a
//! snapshot (`Handle::snapshot`). The runtime is tokio's multi-threaded one with a worker
//! per core, as `winged serve` uses. Every loop undoes what it does (a translation and
//! its opposite, MKEV then KLEV of the new vertex), so the world stays the same size.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use tokio::runtime::Runtime;
use winged::edit::Edit;
use winged::edit::command::{CreateBody, EulerOp, Motion, Move, Shape};
use winged::model::Frame;
use winged::model::World;
use winged::server::actor::{self, Handle};

/// Requesters in the concurrent benchmarks (as many as HTTP connections in the wrk run).
const TASKS: u64 = 64;
/// Commands each requester sends per batch in the concurrent benchmarks.
const PER_TASK: u64 = 16;

fn runtime() -> Runtime {
    tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .expect("tokio runtime")
}

fn translate(body: u64, x: f64) -> Edit {
    Edit::Transform {
        body,
        motion: Move {
            motion: Motion::Translate {
                vector: DVec3::new(x, 0.0, 0.0),
            },
            frame: Frame::World,
            target: None,
        },
    }
}

/// A box body made through the actor; its id.
async fn create_box(h: &Handle) -> u64 {
    let made = h
        .apply(Edit::CreateBody(CreateBody {
            name: None,
            parent: None,
            pose: None,
            color: None,
            shape: Shape::Box {
                size: DVec3::splat(2.0),
            },
        }))
        .await
        .expect("a box");
    made.outcome.id.expect("body id")
}

/// A box body made through the actor; its id, one face id and that face's first vertex id.
async fn make_box(h: &Handle) -> (u64, u64, u64) {
    let id = create_box(h).await;
    let w = h.snapshot().await.expect("actor running");
    let body = w
        .body(winged::model::BodyId(winged::model::Serial(id)))
        .expect("the box");
    let f = body.faces().next().expect("a face");
    let v = body.face_vertices(f).next().expect("a corner");
    (id, body.face_serial(f).get(), body.vertex_serial(v).get())
}

/// MKEV from `vertex` into `face`, then KLEV of the new vertex: two commands.
async fn mkev_klev(h: &Handle, body: u64, face: u64, vertex: u64) {
    let made = h
        .apply(Edit::Euler {
            body,
            op: EulerOp::Mkev {
                face,
                vertex,
                position: Some(DVec3::ZERO),
            },
        })
        .await
        .expect("MKEV");
    let v = made.outcome.vertex.expect("new vertex");
    h.apply(Edit::Euler {
        body,
        op: EulerOp::Klev { vertex: v },
    })
    .await
    .expect("KLEV");
}

/// Runs `fut` as a task on one of the runtime's workers (as an HTTP handler runs), and
/// waits for it.
fn on_runtime<T: Send + 'static>(
    rt: &Runtime,
    fut: impl std::future::Future<Output = T> + Send + 'static,
) -> T {
    rt.block_on(async move { tokio::spawn(fut).await.expect("task") })
}

/// Runs `per_task` rounds of `round` on each of `tasks` concurrent tasks; the elapsed time.
fn concurrent<F, Fut>(rt: &Runtime, tasks: u64, per_task: u64, round: F) -> Duration
where
    F: Fn(u64, u64) -> Fut + Send + Sync + Clone + 'static,
    Fut: std::future::Future<Output = ()> + Send + 'static,
{
    rt.block_on(async move {
        let start = Instant::now();
        let mut set = tokio::task::JoinSet::new();
        for t in 0..tasks {
            let round = round.clone();
            set.spawn(async move {
                for i in 0..per_task {
                    round(t, i).await;
                }
            });
        }
        while let Some(r) = set.join_next().await {
            r.expect("task");
        }
        start.elapsed()
    })
}

fn translate_bench(c: &mut Criterion) {
    let rt = runtime();
    let h = rt.block_on(async { actor::spawn_in_memory(World::new()) });
    let (body, _, _) = rt.block_on(make_box(&h));
    let mut g = c.benchmark_group("translate");

    g.throughput(Throughput::Elements(1));
    g.bench_function("one_requester", |b| {
        let mut sign = 1.0;
        b.iter_custom(|iters| {
            let h = h.clone();
            sign = -sign;
            on_runtime(&rt, async move {
                let start = Instant::now();
                for i in 0..iters {
                    let x = if i % 2 == 0 { sign } else { -sign };
                    black_box(h.apply(translate(body, x)).await.unwrap());
                }
                start.elapsed()
            })
        })
    });

    g.throughput(Throughput::Elements(TASKS * PER_TASK));
    g.bench_function("64_requesters", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let h = h.clone();
                total += concurrent(&rt, TASKS, PER_TASK, move |_, i| {
                    let h = h.clone();
                    async move {
                        let x = if i % 2 == 0 { 1.0 } else { -1.0 };
                        black_box(h.apply(translate(body, x)).await.unwrap());
                    }
                });
            }
            total
        })
    });
    g.finish();
}

fn snapshot_bench(c: &mut Criterion) {
    let rt = runtime();
    let h = rt.block_on(async { actor::spawn_in_memory(World::new()) });
    let (body, _, _) = rt.block_on(make_box(&h));
    let mut g = c.benchmark_group("snapshot");

    g.throughput(Throughput::Elements(1));
    g.bench_function("one_requester", |b| {
        b.iter_custom(|iters| {
            let h = h.clone();
            on_runtime(&rt, async move {
                let start = Instant::now();
                for _ in 0..iters {
                    black_box(h.snapshot().await.unwrap());
                }
                start.elapsed()
            })
        })
    });

    g.throughput(Throughput::Elements(TASKS * PER_TASK));
    g.bench_function("64_requesters", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let h = h.clone();
                total += concurrent(&rt, TASKS, PER_TASK, move |_, _| {
                    let h = h.clone();
                    async move {
                        black_box(h.snapshot().await.unwrap());
                    }
                });
            }
            total
        })
    });

    // Half writes, half reads: every read after a write makes a new snapshot (a clone of
    // the world's parts tree, sharing the bodies).
    g.bench_function("64_requesters_mixed_with_translates", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let h = h.clone();
                total += concurrent(&rt, TASKS, PER_TASK, move |_, i| {
                    let h = h.clone();
                    async move {
                        if i % 2 == 0 {
                            let x = if i % 4 == 0 { 1.0 } else { -1.0 };
                            black_box(h.apply(translate(body, x)).await.unwrap());
                        } else {
                            black_box(h.snapshot().await.unwrap());
                        }
                    }
                });
            }
            total
        })
    });
    g.finish();
}

fn euler_bench(c: &mut Criterion) {
    let rt = runtime();
    let h = rt.block_on(async { actor::spawn_in_memory(World::new()) });
    // One box per requester, so that each one's MKEV/KLEV pairs never meet another's.
    let boxes: Vec<(u64, u64, u64)> = rt.block_on(async {
        let mut v = Vec::new();
        for _ in 0..TASKS {
            v.push(make_box(&h).await);
        }
        v
    });
    let mut g = c.benchmark_group("mkev_klev");

    g.throughput(Throughput::Elements(2));
    g.bench_function("one_requester", |b| {
        let (body, face, vertex) = boxes[0];
        b.iter_custom(|iters| {
            let h = h.clone();
            on_runtime(&rt, async move {
                let start = Instant::now();
                for _ in 0..iters {
                    mkev_klev(&h, body, face, vertex).await;
                }
                start.elapsed()
            })
        })
    });

    g.throughput(Throughput::Elements(TASKS * PER_TASK * 2));
    g.bench_function("64_requesters", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let h = h.clone();
                let boxes = boxes.clone();
                total += concurrent(&rt, TASKS, PER_TASK, move |t, _| {
                    let h = h.clone();
                    let (body, face, vertex) = boxes[t as usize];
                    async move { mkev_klev(&h, body, face, vertex).await }
                });
            }
            total
        })
    });
    g.finish();
}

/// A write followed by a read, in a world of many bodies: the read after a write makes a
/// new snapshot. The parts tree is a persistent map, so the snapshot is a pointer copy
/// and the write copies one path of it: the pair should cost about the same at 10 and at
/// 10,000 bodies (it cost O(bodies) while the tree was a `BTreeMap` cloned whole).
fn big_world_bench(c: &mut Criterion) {
    let rt = runtime();
    let mut g = c.benchmark_group("write_then_snapshot");
    g.throughput(Throughput::Elements(2));
    for bodies in [10usize, 10_000] {
        let h = rt.block_on(async { actor::spawn_in_memory(World::new()) });
        let body = rt.block_on(async {
            for _ in 1..bodies {
                create_box(&h).await;
            }
            create_box(&h).await
        });
        g.bench_function(format!("{bodies}_bodies"), |b| {
            b.iter_custom(|iters| {
                let h = h.clone();
                on_runtime(&rt, async move {
                    let start = Instant::now();
                    for i in 0..iters {
                        let x = if i % 2 == 0 { 1.0 } else { -1.0 };
                        black_box(h.apply(translate(body, x)).await.unwrap());
                        black_box(h.snapshot().await.unwrap());
                    }
                    start.elapsed()
                })
            })
        });
    }
    g.finish();
}

/// A body added under the root and deleted again, each followed by a read, in a world
/// of many bodies under the root. The root's list of parts is one vector: while a
/// snapshot shares the root's node, adding or deleting a part copies the whole list, so
/// this pair grows with the world (unlike `write_then_snapshot`).
fn add_delete_bench(c: &mut Criterion) {
    let rt = runtime();
    let mut g = c.benchmark_group("add_delete_then_snapshot");
    g.throughput(Throughput::Elements(4));
    for bodies in [10usize, 10_000, 100_000] {
        let h = rt.block_on(async { actor::spawn_in_memory(World::new()) });
        rt.block_on(async {
            for _ in 0..bodies {
                create_box(&h).await;
            }
        });
        g.bench_function(format!("{bodies}_bodies"), |b| {
            b.iter_custom(|iters| {
                let h = h.clone();
                on_runtime(&rt, async move {
                    let start = Instant::now();
                    for _ in 0..iters {
                        let body = create_box(&h).await;
                        black_box(h.snapshot().await.unwrap());
                        black_box(h.apply(Edit::DeleteBody { body }).await.unwrap());
                        black_box(h.snapshot().await.unwrap());
                    }
                    start.elapsed()
                })
            })
        });
    }
    g.finish();
}

fn config() -> Criterion {
    // Short runs: the figures are taken on a shared 2-core machine.
    Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
        .sample_size(20)
}

criterion_group! {
    name = benches;
    config = config();
    targets = translate_bench, snapshot_bench, euler_bench, big_world_bench, add_delete_bench
}
criterion_main!(benches);
