//! Spatial access benchmarks (winged alone; `bash bench/spatial/run.sh` runs rstar and
//! parry3d beside it on the same data): a closed terrain solid of 1,000,000 triangles
//! and a city of 100,000 boxes, both from `bench/spatial/data.rs`.
//!
//! ```text
//! cargo bench --bench spatial                 # everything (about three minutes)
//! cargo bench --bench spatial -- terrain      # one data set
//! cargo bench --bench spatial -- move         # moving one body of the city
//! ```
//!
//! Measured per data set: `build` (`Spatial::build` of the world; the index built by the
//! previous iteration is dropped outside the timing), sphere queries at
//! `bodies` and `features` detail with radii calibrated (on 300 of the centres) for
//! about 15 and about 120 hits (faces of the terrain, bodies of the city), one query
//! per iteration cycling through 10,000 centres; and for the city `move_one_body`: one
//! `sync` after one body moved. Before each criterion group the same 10,000 queries
//! are also timed one by one, and their p50, p99, mean and mean hit count printed,
//! with `heap_bytes` of the index.

#[path = "../bench/spatial/data.rs"]
mod data;

use std::hint::black_box;
use std::sync::Arc;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use winged::model::{Pose, World};
use winged::spatial::{Detail, Spatial, SphereQuery};

/// Queries per set.
const QUERIES: usize = 10_000;
/// Centres used to calibrate the radii.
const CALIBRATION: usize = 300;
/// Distinct bodies moved one after the other for the percentiles of a move.
const MOVES: usize = 300;

/// Bodies answered.
fn bodies(spatial: &Spatial, c: DVec3, r: f64, detail: Detail) -> usize {
    let q = SphereQuery::new(c, r).with_detail(detail);
    spatial.sphere(&q).expect("a valid query").bodies.len()
}

/// Times the queries one by one and prints their figures.
fn report(what: &str, spatial: &Spatial, centers: &[DVec3], r: f64, detail: Detail) {
    let (t, hits) = data::time_each(centers, |c| match detail {
        Detail::Bodies => bodies(spatial, c, r, detail),
        _ => data::faces_answered(spatial, c, r),
    });
    let unit = if detail == Detail::Bodies {
        "bodies"
    } else {
        "faces"
    };
    println!(
        "{what}: radius {r:.3} m, {detail}: p50 {:.2} µs, p99 {:.2} µs, mean {:.2} µs, \
         mean {hits:.1} {unit} per query",
        t.p50,
        t.p99,
        t.mean,
        detail = detail.name(),
    );
}

/// Criterion timing of one query per iteration, cycling through the centres.
fn bench_queries(
    g: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    spatial: &Spatial,
    centers: &[DVec3],
    r: f64,
    detail: Detail,
) {
    let mut k = 0;
    g.bench_function(name, |b| {
        b.iter(|| {
            k = if k + 1 == centers.len() { 0 } else { k + 1 };
            let q = SphereQuery::new(centers[k], r).with_detail(detail);
            black_box(spatial.sphere(&q).expect("a valid query"))
        })
    });
}

fn terrain(c: &mut Criterion) {
    let terrain = data::Terrain::new();
    let (world, id, _) = terrain.world();
    let world = Arc::new(world);
    let mut g = c.benchmark_group("terrain_1m_triangles");
    g.sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(6));
    g.bench_function("build", |b| {
        b.iter_with_large_drop(|| Spatial::build(world.clone()))
    });
    let spatial = Spatial::build(world.clone());
    let body = &world.node(id).expect("the terrain").body;
    println!(
        "terrain: {} faces; index heap {} bytes ({:.1} B per triangle); the body itself {} bytes",
        body.face_count(),
        spatial.heap_bytes(),
        spatial.heap_bytes() as f64 / terrain.triangles.len() as f64,
        body.heap_bytes(),
    );
    let centers = terrain.centers(QUERIES, 1);
    let calib = &centers[..CALIBRATION];
    g.sample_size(20).measurement_time(Duration::from_secs(3));
    for target in [15.0, 120.0] {
        let r = data::calibrate(target, calib, 0.01, 20.0, |c, r| {
            data::faces_answered(&spatial, c, r)
        });
        for detail in [Detail::Bodies, Detail::Features] {
            let name = format!("sphere_{target}_faces/{}", detail.name());
            report(&format!("terrain {name}"), &spatial, &centers, r, detail);
            bench_queries(&mut g, &name, &spatial, &centers, r, detail);
        }
    }
    g.finish();
}

fn city(c: &mut Criterion) {
    let city = data::city();
    let (world, ids, _) = data::city_world(&city);
    let world = Arc::new(world);
    let mut g = c.benchmark_group("city_100k_bodies");
    g.sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(6));
    g.bench_function("build", |b| {
        b.iter_with_large_drop(|| Spatial::build(world.clone()))
    });
    let mut spatial = Spatial::build(world.clone());
    println!(
        "city: {} bodies; index heap {} bytes ({:.0} B per body)",
        spatial.len(),
        spatial.heap_bytes(),
        spatial.heap_bytes() as f64 / spatial.len() as f64,
    );
    let centers = data::city_centers(QUERIES, 2);
    let calib = &centers[..CALIBRATION];
    g.sample_size(20).measurement_time(Duration::from_secs(3));
    for target in [15.0, 120.0] {
        let r = data::calibrate(target, calib, 1.0, 400.0, |c, r| {
            bodies(&spatial, c, r, Detail::Bodies)
        });
        for detail in [Detail::Bodies, Detail::Features] {
            let name = format!("sphere_{target}_bodies/{}", detail.name());
            report(&format!("city {name}"), &spatial, &centers, r, detail);
            bench_queries(&mut g, &name, &spatial, &centers, r, detail);
        }
    }

    // Moving one body: MOVES distinct bodies, one after the other, each by a few
    // metres; the next world is made (cloned and posed) outside the timing, and the
    // world the index drops is still held, so only `sync` is timed.
    let mut rng = data::Rng::new(3);
    let mut current = world.clone();
    let mut ns = Vec::with_capacity(MOVES);
    let mut rebuilt = 0;
    for _ in 0..MOVES {
        let k = (rng.next_u64() % ids.len() as u64) as usize;
        let b = &city[k];
        let shift = DVec3::new(rng.range(-5.0, 5.0), rng.range(-5.0, 5.0), 0.0);
        let pose = Pose::new(b.center + shift, b.pose().rotation).expect("a pose");
        let next = data::moved(&current, ids[k], pose);
        let t = Instant::now();
        let stats = spatial.sync(next.clone(), Some(&[ids[k]]));
        ns.push(t.elapsed().as_nanos() as f64);
        assert_eq!(stats.moved, 1);
        rebuilt += usize::from(stats.rebuilt);
        current = next;
    }
    let t = data::Timings::of(&mut ns);
    println!(
        "city move_one_body ({MOVES} distinct bodies, each synced alone): p50 {:.2} µs, \
         p99 {:.2} µs, mean {:.2} µs ({rebuilt} rebuilds)",
        t.p50, t.p99, t.mean
    );

    // Criterion: one body moved back and forth between two snapshots that differ in its
    // pose only; each iteration is one move.
    let k = ids.len() / 2 + CITY_ROW_MIDDLE;
    let a: Arc<World> = current;
    let shifted = city[k].center + DVec3::new(4.0, 3.0, 0.0);
    let pose = Pose::new(shifted, city[k].pose().rotation).expect("a pose");
    let b = data::moved(&a, ids[k], pose);
    let mut spatial = Spatial::build(a.clone());
    let mut flip = false;
    g.bench_function("move_one_body", |bench| {
        bench.iter(|| {
            flip = !flip;
            let w = if flip { b.clone() } else { a.clone() };
            black_box(spatial.sync(w, Some(&[ids[k]])))
        })
    });
    g.finish();
}

/// Half a row of the city: puts the body moved by criterion mid-city.
const CITY_ROW_MIDDLE: usize = data::CITY_NX / 2;

criterion_group!(benches, terrain, city);
criterion_main!(benches);
